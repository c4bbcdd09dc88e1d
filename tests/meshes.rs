//! Ulrich's chunks (issue 11): each node's adaptive mesh against brute
//! force on a small synthetic pyramid: the stored delta is the exact
//! distance to the best data, a child refines its parent, morph targets lie
//! on the parent's mesh (so a fully morphed child draws its parent's
//! surface), triangles stay inside their tile squares, and the mesh file
//! refuses damage.

use std::path::Path;
use std::sync::Arc;

use ridgeline::meshes::file::pyramid_identity;
use ridgeline::meshes::{build_meshes, BuiltMeshes, MeshFile, MeshOptions, MeshedSource};
use ridgeline::node::{NodeError, NodeId, NodeLayout, NodeMesh, NodeSource};
use ridgeline::pyramid::{self, BuildOptions, Pyramid, Silent};

const OPTIONS: MeshOptions = MeshOptions { error_m: 3.0, depth: 2, tile_cells: 4 };

fn pyramid_in(dir: &Path) -> Arc<Pyramid> {
    let grid = pyramid::synthetic_grid(150).expect("a synthetic grid");
    let options = BuildOptions { node_size: 16, border: 2 };
    let built = pyramid::build(&grid, &options, &Silent).expect("build");
    pyramid::write_atomic(&built, &dir.join(pyramid::FILE_NAME), &Silent).expect("write");
    Arc::new(Pyramid::open(dir).expect("open"))
}

/// Level-0 post of a node mesh's vertex post `p`.
fn level0(layout: &NodeLayout, id: NodeId, mesh: &NodeMesh, p: [u16; 2]) -> [f64; 2] {
    let origin = [id.x, id.y].map(|v| (v as u64 * layout.node_size as u64) << id.level);
    // Mesh posts count half steps of the mesh's lattice.
    [0, 1].map(|k| origin[k] as f64 + p[k] as f64 * (1u64 << mesh.post_level) as f64 / 2.0)
}

/// The mesh's height at level-0 place `q` by testing every triangle (NaN
/// where its triangle there has no data, `None` outside the mesh).
fn brute_height(layout: &NodeLayout, id: NodeId, mesh: &NodeMesh, q: [f64; 2]) -> Option<f64> {
    for tri in mesh.indices.chunks_exact(3) {
        let v = [0, 1, 2].map(|k| mesh.vertices[tri[k] as usize]);
        let p = v.map(|v| level0(layout, id, mesh, v.post));
        let area = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        let w = [area(p[1], p[2], q), area(p[2], p[0], q), area(p[0], p[1], q)];
        if w.iter().all(|&w| w >= -1e-9) {
            let sum = w[0] + w[1] + w[2];
            return Some((0..3).map(|k| w[k] * v[k].height as f64).sum::<f64>() / sum);
        }
    }
    None
}

fn built(source: &dyn NodeSource) -> BuiltMeshes {
    build_meshes(source, OPTIONS, &Silent).expect("meshes build")
}

fn present(layout: &NodeLayout, level: u8) -> impl Iterator<Item = NodeId> {
    let [nx, ny] = layout.nodes_at(level);
    (0..ny).flat_map(move |y| (0..nx).map(move |x| NodeId::new(level, x, y)))
}

#[test]
fn the_stored_delta_is_the_largest_distance_to_the_data() {
    let dir = testkit::fresh_dir("meshes-delta");
    let pyramid = pyramid_in(&dir);
    let layout = *pyramid.layout();
    let meshes = built(pyramid.as_ref());
    let last = layout.posts.map(|p| (p - 1) as f64);
    for level in 0..layout.levels {
        let mut level_worst = 0.0f64;
        for id in present(&layout, level) {
            let chunk = meshes.mesh(&layout, id).expect("every node of a single grid is stored");
            let span = (layout.node_size as u64) << level;
            let origin = [id.x as u64 * span, id.y as u64 * span];
            let mut worst = 0.0f64;
            // Level-0 posts and cell centres under the node, inside the data.
            for j2 in 0..=2 * span {
                for i2 in 0..=2 * span {
                    let q = [(origin[0] * 2 + i2) as f64 / 2.0, (origin[1] * 2 + j2) as f64 / 2.0];
                    let centre = i2 % 2 == 1 && j2 % 2 == 1;
                    if q[0] > last[0] || q[1] > last[1] || (i2 % 2 != j2 % 2) && !centre {
                        continue;
                    }
                    let [sx, sy] = layout.spacing_m;
                    let data = pyramid.exact_height(q[0] * sx, q[1] * sy).expect("inside") as f64;
                    let mesh = brute_height(&layout, id, &chunk.mesh, q).expect("mesh covers node");
                    worst = worst.max((mesh - data).abs());
                }
            }
            assert!(
                worst <= chunk.delta as f64 + 1e-3,
                "{id:?}: brute {worst} > delta {}",
                chunk.delta
            );
            let fully_inside = (0..2).all(|k| (origin[k] + span) as f64 <= last[k]);
            if level <= OPTIONS.depth && fully_inside {
                assert!(
                    chunk.delta as f64 <= worst + 1e-3,
                    "{id:?}: delta {} > brute {worst}",
                    chunk.delta
                );
            }
            assert!(chunk.delta <= OPTIONS.level_error(level) + 1e-3 || level > OPTIONS.depth);
            level_worst = level_worst.max(worst);
        }
        println!("level {level}: brute-force delta {level_worst:.3} m");
    }
}

#[test]
fn a_child_refines_its_parent_and_morphs_onto_its_surface() {
    let dir = testkit::fresh_dir("meshes-morph");
    let pyramid = pyramid_in(&dir);
    let layout = *pyramid.layout();
    let meshes = built(pyramid.as_ref());
    for level in 0..layout.levels - 1 {
        for id in present(&layout, level) {
            let child = &meshes.mesh(&layout, id).expect("stored").mesh;
            let pid = id.parent().expect("below the root");
            let parent = &meshes.mesh(&layout, pid).expect("stored").mesh;
            // Every parent vertex inside the child's square is a child
            // vertex, but a fan's centre (odd half steps): a fan draws its
            // cell's own diagonal, which the child's cells follow.
            let span = ((layout.node_size as u64) << level) as f64;
            let origin = [id.x as f64 * span, id.y as f64 * span];
            let inside =
                |p: [f64; 2]| (0..2).all(|k| p[k] >= origin[k] && p[k] <= origin[k] + span);
            let child_posts: Vec<[f64; 2]> =
                child.vertices.iter().map(|v| level0(&layout, id, child, v.post)).collect();
            for v in &parent.vertices {
                let p = level0(&layout, pid, parent, v.post);
                let centre = v.post.iter().all(|c| c % 2 == 1);
                if inside(p) && !centre {
                    assert!(child_posts.contains(&p), "{id:?}: parent vertex {p:?} missing");
                }
            }
            // Targets lie on the parent's mesh; so, child triangles refining
            // the parent's, the fully morphed child is the parent's surface.
            for (v, p) in child.vertices.iter().zip(&child_posts) {
                if v.height.is_nan() {
                    continue;
                }
                let on_parent =
                    brute_height(&layout, pid, parent, *p).expect("parent covers child");
                // Where the parent draws nothing (its triangle there has a
                // post without data) the vertex does not morph.
                let expected = if on_parent.is_nan() { v.height as f64 } else { on_parent };
                assert!(
                    (v.target as f64 - expected).abs() < 1e-2,
                    "{id:?} {p:?}: {} vs {expected}",
                    v.target
                );
            }
            for tri in child.indices.chunks_exact(3) {
                // At the data's last post the parent's triangles reach past
                // it (clipped there when drawn): left to the render tests.
                let last = layout.posts.map(|p| p as f64 - 2.0);
                let unmorphed = tri.iter().any(|&k| {
                    let p = child_posts[k as usize];
                    p[0] > last[0] || p[1] > last[1]
                });
                if unmorphed {
                    continue;
                }
                let c = tri.iter().fold([0.0; 2], |a, &k| {
                    let p = child_posts[k as usize];
                    [a[0] + p[0] / 3.0, a[1] + p[1] / 3.0]
                });
                // A cell drawn along the data's diagonal where the parent
                // folds the other way is a fan (meshes::fan): no twist left.
                let tolerance = 1e-2;
                let morphed = {
                    let mut m = child.clone();
                    m.vertices.iter_mut().for_each(|v| v.height = v.target);
                    brute_height(&layout, id, &m, c).expect("centroid inside")
                };
                let on_parent = brute_height(&layout, pid, parent, c).expect("parent covers");
                if on_parent.is_nan() || morphed.is_nan() {
                    continue;
                }
                assert!(
                    (morphed - on_parent).abs() <= tolerance,
                    "{id:?} at {c:?}: {morphed} vs {on_parent}"
                );
            }
        }
    }
}

#[test]
fn every_triangle_lies_in_one_tile_square() {
    let dir = testkit::fresh_dir("meshes-squares");
    let pyramid = pyramid_in(&dir);
    let layout = *pyramid.layout();
    let meshes = built(pyramid.as_ref());
    for level in 0..layout.levels {
        for id in present(&layout, level) {
            let mesh = &meshes.mesh(&layout, id).expect("stored").mesh;
            // Half steps: a square is twice its posts.
            let square = ((2 * OPTIONS.tile_cells) << (level - mesh.post_level)) as u16;
            for tri in mesh.indices.chunks_exact(3) {
                let p = [0, 1, 2].map(|k| mesh.vertices[tri[k] as usize].post);
                for k in 0..2 {
                    let lo = p.iter().map(|q| q[k]).min().unwrap();
                    let hi = p.iter().map(|q| q[k]).max().unwrap();
                    assert!(
                        hi - lo <= square && lo / square == (hi - 1).max(lo) / square,
                        "{id:?} {p:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_mesh_file_reads_back_and_refuses_damage() {
    let dir = testkit::fresh_dir("meshes-file");
    let pyramid = pyramid_in(&dir);
    let layout = *pyramid.layout();
    let source =
        MeshedSource::open_or_build(Arc::clone(&pyramid), OPTIONS, &Silent).expect("build");
    let meshes = built(pyramid.as_ref());
    let root = NodeId::new(layout.levels - 1, 0, 0);
    let mut data = ridgeline::node::NodeData::default();
    source.read_node(root, &mut data).expect("read");
    let expected = meshes.mesh(&layout, root).expect("stored");
    let bytes_of = |mesh: &NodeMesh| {
        let v: &[u8] = bytemuck::cast_slice(&mesh.vertices);
        (mesh.post_level, v.to_vec(), mesh.indices.clone())
    };
    assert_eq!(bytes_of(&data.mesh), bytes_of(&expected.mesh), "NaN heights compare by bits");
    assert_eq!(data.delta, expected.delta);
    // Flip a byte of the root's record (the last one written).
    let path = source.file().path().to_path_buf();
    let mut bytes = std::fs::read(&path).expect("read the file");
    let n = bytes.len();
    bytes[n - 8] ^= 0x40;
    std::fs::write(&path, &bytes).expect("write");
    let identity = pyramid_identity(pyramid.path()).expect("identity");
    let damaged = MeshFile::open(&path, &layout, identity).expect("the header is intact");
    let error = damaged.read(&layout, root, &mut data.mesh).expect_err("damage is found");
    assert!(matches!(error, NodeError::Corrupt { .. }), "{error}");
    assert!(error.to_string().contains(".rlm"), "{error}");
    // A damaged header is refused; opening the source rebuilds the file.
    bytes[20] ^= 1;
    std::fs::write(&path, &bytes).expect("write");
    let refused = MeshFile::open(&path, &layout, identity).err().expect("refused");
    assert!(refused.to_string().contains(".rlm"), "{refused}");
    let rebuilt = MeshedSource::open_or_build(pyramid, OPTIONS, &Silent).expect("rebuilt");
    rebuilt.read_node(root, &mut data).expect("read after the rebuild");
    assert_eq!(bytes_of(&data.mesh), bytes_of(&expected.mesh));
    // Truncated: refused, never a panic.
    std::fs::write(&path, &bytes[..30]).expect("write");
    assert!(MeshFile::open(&path, &layout, identity).is_err());
}
