//! Error maps and the meshes tiles extract from them (issues 11, 21, 22),
//! against brute force on a small synthetic pyramid: a mesh extracted at
//! any error errs by at most that error (plus its reference lattice's), a
//! child's mesh refines its parent's and morphs onto its surface, the map
//! file reads back, refuses damage, and shards merge into the very file
//! one process writes.

use std::path::Path;
use std::sync::Arc;

use ridgeline::meshes::file::pyramid_identity;
use ridgeline::meshes::{
    build_map, build_map_shared, build_store, merge_stores, MapFile, MeshOptions, MeshedSource,
};
use ridgeline::node::{NodeData, NodeError, NodeId, NodeLayout, NodeMesh, NodeSource};
use ridgeline::pyramid::{self, BuildOptions, Pyramid, Silent};
use ridgeline::scene::PreloadedTerrain;
use ridgeline::tiles::extract::{Extraction, Extractor, PlacedMap, TargetMesh};
use ridgeline::tiles::ResidentNodes;
use testkit::mesh::{brute, level0};

const OPTIONS: MeshOptions = MeshOptions { depth: 2, tile_cells: 4, finest_view_px: 400.0 };

fn pyramid_in(dir: &Path) -> Arc<Pyramid> {
    let grid = pyramid::synthetic_grid(150).expect("a synthetic grid");
    let options = BuildOptions { node_size: 16, border: 2 };
    let built = pyramid::build(&grid, &options, &Silent).expect("build");
    pyramid::write_atomic(&built, &dir.join(pyramid::FILE_NAME), &Silent).expect("write");
    Arc::new(Pyramid::open(dir).expect("open"))
}

fn terrain_in(dir: &Path) -> (Arc<Pyramid>, PreloadedTerrain) {
    let pyramid = pyramid_in(dir);
    let source = MeshedSource::open_or_build(Arc::clone(&pyramid), OPTIONS, &Silent).expect("maps");
    let terrain = PreloadedTerrain::load(&source).expect("every node reads");
    (pyramid, terrain)
}

fn stored(layout: &NodeLayout, level: u8) -> impl Iterator<Item = NodeId> {
    let [nx, ny] = layout.nodes_at(level);
    (0..ny).flat_map(move |y| (0..nx).map(move |x| NodeId::new(level, x, y)))
}

fn place<'a>(
    layout: &'a NodeLayout,
    id: NodeId,
    data: &'a NodeData,
    error_m: f64,
) -> PlacedMap<'a> {
    testkit::mesh::place(layout, id, data, OPTIONS.tile_cells, error_m)
}

/// Node `id`'s whole mesh at `error(level)` per level, keeping its
/// ancestors' vertices (at their levels' errors) when `nested`, and
/// morphing toward the parent's mesh when `nested` too.
fn node_mesh(
    terrain: &PreloadedTerrain,
    id: NodeId,
    error: &dyn Fn(u8) -> f64,
    nested: bool,
) -> NodeMesh {
    let layout = terrain.layout();
    let data = terrain.resident(id).expect("preloaded");
    let own = place(layout, id, data, error(id.level));
    let mut chain = Vec::new();
    let mut up = id;
    while let Some(parent) = up.parent().filter(|p| p.level < layout.levels && nested) {
        chain.push(place(
            layout,
            parent,
            terrain.resident(parent).expect("stored"),
            error(parent.level),
        ));
        up = parent;
    }
    let target = if chain.is_empty() { TargetMesh::None } else { TargetMesh::Parent };
    let job = Extraction {
        own: &own,
        ancestors: &chain,
        target,
        origin: [0, 0],
        width: data.map.cells,
        place_parent: false,
    };
    let mut extractor = Extractor::default();
    extractor.extract(&job).expect("extracts");
    extractor.mesh.clone()
}

#[test]
fn an_extracted_mesh_errs_by_at_most_its_error() {
    let dir = testkit::fresh_dir("meshes-error");
    let (pyramid, terrain) = terrain_in(&dir);
    let layout = *pyramid.layout();
    let last = layout.posts.map(|p| (p - 1) as f64);
    for scale in [1.0, 2.0, 8.0] {
        for level in 0..layout.levels {
            let mut worst_ratio = 0.0f64;
            for id in stored(&layout, level) {
                let data = terrain.resident(id).expect("every node of one grid");
                let error_m = (data.map.floor_m as f64).max(0.5) * scale;
                let mesh = node_mesh(&terrain, id, &|_| error_m, false);
                let span = (layout.node_size as u64) << level;
                let origin = [id.x as u64 * span, id.y as u64 * span];
                let mut worst = 0.0f64;
                // Level-0 posts and cell centres under the node, inside the data.
                for j2 in 0..=2 * span {
                    for i2 in 0..=2 * span {
                        let q =
                            [(origin[0] * 2 + i2) as f64 / 2.0, (origin[1] * 2 + j2) as f64 / 2.0];
                        let centre = i2 % 2 == 1 && j2 % 2 == 1;
                        if q[0] > last[0] || q[1] > last[1] || (i2 % 2 != j2 % 2) && !centre {
                            continue;
                        }
                        let [sx, sy] = layout.spacing_m;
                        let exact =
                            pyramid.exact_height(q[0] * sx, q[1] * sy).expect("inside") as f64;
                        let drawn =
                            brute(&layout, id, &mesh, q, false).expect("the mesh covers its node");
                        worst = worst.max((drawn - exact).abs());
                    }
                }
                let bound = error_m.max(data.map.floor_m as f64) + data.map.reference_delta as f64;
                assert!(
                    worst <= bound + 1e-3,
                    "{id:?} at {error_m} m: brute {worst} > bound {bound}"
                );
                worst_ratio = worst_ratio.max(worst / bound);
            }
            println!(
                "level {level}, {scale} x the floor: worst error {worst_ratio:.3} of the bound"
            );
        }
    }
}

#[test]
fn a_child_refines_its_parent_and_morphs_onto_its_surface() {
    let dir = testkit::fresh_dir("meshes-morph");
    let (pyramid, terrain) = terrain_in(&dir);
    let layout = *pyramid.layout();
    // Each level's error twice the finer one's, as the rings make them.
    let error = |level: u8| 0.8 * (1u64 << level) as f64;
    for level in 0..layout.levels - 1 {
        for id in stored(&layout, level) {
            let child = node_mesh(&terrain, id, &error, true);
            let pid = id.parent().expect("below the root");
            let parent = node_mesh(&terrain, pid, &error, true);
            let span = ((layout.node_size as u64) << level) as f64;
            let origin = [id.x as f64 * span, id.y as f64 * span];
            let inside =
                |p: [f64; 2]| (0..2).all(|k| p[k] >= origin[k] && p[k] <= origin[k] + span);
            let child_posts: Vec<[f64; 2]> =
                child.vertices.iter().map(|v| level0(&layout, id, &child, v.post)).collect();
            for v in &parent.vertices {
                let p = level0(&layout, pid, &parent, v.post);
                let centre = v.post.iter().all(|c| c % 2 == 1);
                if inside(p) && !centre {
                    assert!(child_posts.contains(&p), "{id:?}: parent vertex {p:?} missing");
                }
            }
            // Targets lie on the parent's mesh, so the fully morphed child
            // (its triangles refining the parent's) is the parent's surface.
            for (v, p) in child.vertices.iter().zip(&child_posts) {
                let on_parent =
                    brute(&layout, pid, &parent, *p, false).expect("parent covers child");
                if v.height.is_nan() || on_parent.is_nan() {
                    continue;
                }
                assert!(
                    (v.target as f64 - on_parent).abs() < 1e-2,
                    "{id:?} {p:?}: {} vs {on_parent}",
                    v.target
                );
            }
            let last = layout.posts.map(|p| p as f64 - 2.0);
            for tri in child.indices.chunks_exact(3) {
                let ps: [[f64; 2]; 3] = [0, 1, 2].map(|k| child_posts[tri[k] as usize]);
                if ps.iter().any(|p| p[0] > last[0] || p[1] > last[1]) {
                    continue; // clipped at the data's last post when drawn
                }
                let c = [0, 1].map(|k| ps.iter().map(|p| p[k]).sum::<f64>() / 3.0);
                let morphed = brute(&layout, id, &child, c, true).expect("centroid inside");
                let on_parent = brute(&layout, pid, &parent, c, false).expect("parent covers");
                if morphed.is_nan() || on_parent.is_nan() {
                    continue;
                }
                assert!(
                    (morphed - on_parent).abs() <= 1e-2,
                    "{id:?} at {c:?}: {morphed} vs {on_parent}"
                );
            }
        }
    }
}

/// A pyramid of two layers whose heights disagree by 12 m: a coarse one,
/// and a fine one over part of it whose edges fall inside blocks, so a
/// stored level-0 node has a neighbour read from a coarser ancestor, and
/// the two disagree on their shared posts.
fn layered_pyramid_in(dir: &Path) -> Arc<Pyramid> {
    let terrain = |x: f64, y: f64| 600.0 + 250.0 * (x / 3000.0).sin() * (y / 4100.0).cos();
    let layer = |origin: [f64; 2], spacing: f64, posts: [u32; 2], offset: f64| {
        testkit::pyramid::projected_grid(origin, [spacing; 2], posts, |x, y| terrain(x, y) + offset)
    };
    let layers =
        [layer([0.0, 0.0], 400.0, [40, 40], 0.0), layer([2_000.0, 3_000.0], 100.0, [61, 75], 12.0)];
    let options = BuildOptions { node_size: 16, border: 2 };
    let built = pyramid::build_layers(&layers, &options, &Silent).expect("build the layers");
    pyramid::write_atomic(&built, &dir.join(pyramid::FILE_NAME), &Silent).expect("write");
    Arc::new(Pyramid::open(dir).expect("open"))
}

/// The block build (one scan per block, each node's map cut from it)
/// against each node's map built without it (through its share square's
/// own block where its edges are shared, else alone): equal for every
/// node, at the test's depth and at one whose blocks span every level, on
/// one grid and on two layers (where a stored node's neighbour comes from
/// an ancestor: a shard builds alone what one process cuts from a block,
/// and both must write the same bytes). Where no edge is shared the map
/// is the one built alone; shared edges only raise codes.
#[test]
fn every_map_of_the_block_build_is_the_map_built_alone() {
    let dir = testkit::fresh_dir("meshes-blocks");
    the_block_build_is_each_map_built_alone(&dir, &pyramid_in(&dir));
    let layered = dir.join("layered");
    std::fs::create_dir_all(&layered).expect("a directory");
    the_block_build_is_each_map_built_alone(&layered, &layered_pyramid_in(&layered));
}

fn the_block_build_is_each_map_built_alone(dir: &Path, pyramid: &Arc<Pyramid>) {
    let layout = *pyramid.layout();
    let identity = pyramid_identity(pyramid.path()).expect("identity");
    let nodes = ridgeline::meshes::source::stored_nodes(pyramid.as_ref());
    let mut shared = 0;
    for depth in [2, 5] {
        let options = MeshOptions { depth, ..OPTIONS };
        let path = dir.join(format!("depth-{depth}.rlm"));
        build_store(pyramid.as_ref(), identity, &nodes, options, &path, &Silent).expect("builds");
        let file = MapFile::open(&path, &layout, identity).expect("opens");
        let bits = |h: &[f32]| h.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for &id in &nodes {
            let mut read = NodeData::default();
            file.read(pyramid.as_ref(), id, &mut read.map).expect("reads");
            let alone = build_map_shared(pyramid.as_ref(), id, &options).expect("builds alone");
            let what = format!("{id:?} at depth {depth}");
            assert_eq!(read.map.shared_edges, alone.shared_edges, "{what}");
            let own = build_map(pyramid.as_ref(), id, &options).expect("builds alone");
            if alone.shared_edges == 0 {
                // NaN heights compare by bits.
                let parts = |m: &ridgeline::node::ErrorMap| {
                    (m.codes.clone(), m.keys.clone(), bits(&m.heights))
                };
                assert!(
                    parts(&alone) == parts(&own),
                    "{what}: no shared edge, the map built alone"
                );
            } else if alone.is_dense() {
                let raised = alone.codes.iter().zip(&own.codes).all(|(s, o)| s >= o);
                assert!(raised, "{what}: shared edges only raise codes");
                shared += 1;
            }
            assert_eq!(
                (read.map.post_level, read.map.cells),
                (alone.post_level, alone.cells),
                "{what}"
            );
            assert_eq!(read.map.codes, alone.codes, "{what}");
            assert_eq!(read.map.keys, alone.keys, "{what}");
            assert_eq!(bits(&read.map.heights), bits(&alone.heights), "{what}");
            assert_eq!(read.map.normals, alone.normals, "{what}");
            assert_eq!(read.map.reference_delta, alone.reference_delta, "{what}");
            assert_eq!(read.map.height_step, alone.height_step, "{what}");
            assert_eq!(read.map.floor_m, alone.floor_m, "{what}");
        }
    }
    assert!(shared > 0, "some level-0 maps share an edge");
}

#[test]
fn the_map_file_reads_back_and_refuses_damage() {
    let dir = testkit::fresh_dir("meshes-file");
    let pyramid = pyramid_in(&dir);
    let layout = *pyramid.layout();
    let source =
        MeshedSource::open_or_build(Arc::clone(&pyramid), OPTIONS, &Silent).expect("build");
    let root = NodeId::new(layout.levels - 1, 0, 0);
    let mut data = NodeData::default();
    source.read_node(root, &mut data).expect("read");
    let mut expected = build_map(pyramid.as_ref(), root, &OPTIONS).expect("builds");
    expected.fit();
    let bits = |h: &[f32]| h.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!((&data.map.keys, &data.map.codes), (&expected.keys, &expected.codes));
    assert_eq!(bits(&data.map.heights), bits(&expected.heights), "NaN heights compare by bits");
    // Flip a byte of the root's record (the last one written).
    let path = source.file().path().to_path_buf();
    let mut bytes = std::fs::read(&path).expect("read the file");
    let n = bytes.len();
    bytes[n - 8] ^= 0x40;
    std::fs::write(&path, &bytes).expect("write");
    let identity = pyramid_identity(pyramid.path()).expect("identity");
    let damaged = MapFile::open(&path, &layout, identity).expect("the header is intact");
    let before = (data.map.keys.clone(), bits(&data.map.heights));
    let error = damaged.read(pyramid.as_ref(), root, &mut data.map).expect_err("damage is found");
    assert!(matches!(error, NodeError::Corrupt { .. }), "{error}");
    assert!(error.to_string().contains(".rlm"), "{error}");
    let after = (data.map.keys.clone(), bits(&data.map.heights));
    assert!(after == before, "a refused record leaves the buffers as they were");
    // A damaged header is refused; opening the source rebuilds the file.
    bytes[20] ^= 1;
    std::fs::write(&path, &bytes).expect("write");
    let refused = MapFile::open(&path, &layout, identity).err().expect("refused");
    assert!(refused.to_string().contains(".rlm"), "{refused}");
    let rebuilt =
        MeshedSource::open_or_build(Arc::clone(&pyramid), OPTIONS, &Silent).expect("rebuilt");
    rebuilt.read_node(root, &mut data).expect("read after the rebuild");
    assert_eq!(data.map.keys, expected.keys);
    // Truncated: refused, never a panic.
    std::fs::write(&path, &bytes[..30]).expect("write");
    assert!(MapFile::open(&path, &layout, identity).is_err());
}

#[test]
fn shards_merge_into_the_file_one_process_writes() {
    let dir = testkit::fresh_dir("meshes-shards");
    let pyramid = pyramid_in(&dir);
    let layout = *pyramid.layout();
    let identity = pyramid_identity(pyramid.path()).expect("identity");
    let nodes = ridgeline::meshes::source::stored_nodes(pyramid.as_ref());
    let whole = dir.join("whole.rlm");
    build_store(pyramid.as_ref(), identity, &nodes, OPTIONS, &whole, &Silent).expect("one process");
    let parts: Vec<_> = (0..4)
        .map(|k| {
            let part = dir.join(format!("part-{k}.rlm"));
            let mine: Vec<NodeId> = nodes.iter().copied().skip(k).step_by(4).collect();
            build_store(pyramid.as_ref(), identity, &mine, OPTIONS, &part, &Silent)
                .expect("a shard");
            assert!(!MapFile::open(&part, &layout, identity).expect("opens").is_complete());
            part
        })
        .collect();
    let merged = dir.join("merged.rlm");
    merge_stores(&parts, &layout, &merged).expect("merges");
    assert_eq!(std::fs::read(&merged).unwrap(), std::fs::read(&whole).unwrap(), "byte for byte");
    // A part missing, or one given twice, is an error naming a file.
    let missing = merge_stores(&parts[..3], &layout, &dir.join("short.rlm"))
        .expect_err("a node lacks its map");
    assert!(missing.to_string().contains(".rlm"), "{missing}");
    let twice =
        [parts[0].clone(), parts[0].clone(), parts[1].clone(), parts[2].clone(), parts[3].clone()];
    assert!(merge_stores(&twice, &layout, &dir.join("twice.rlm")).is_err());
}
