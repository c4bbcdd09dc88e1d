//! Meshes whose error grows with the distance (issue 22,
//! `tiles::by_distance`), against brute force on a small synthetic pyramid:
//! the mesh is conforming (no vertex of it lies inside another triangle's
//! edge), errs at every post and cell centre by at most what its rule allows
//! there, and a child whose rule ends past its band keeps its parent's
//! vertices and morphs onto the parent's very surface.

use std::path::Path;
use std::sync::Arc;

use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::node::{NodeData, NodeId, NodeLayout, NodeMesh, NodeSource};
use ridgeline::pyramid::{self, BuildOptions, Pyramid, Silent};
use ridgeline::scene::PreloadedTerrain;
use ridgeline::tiles::by_distance::{DistanceRule, RingView};
use ridgeline::tiles::extract::{Extraction, Extractor, PlacedMap, TargetMesh};
use ridgeline::tiles::ResidentNodes;
use testkit::mesh::{area, brute, level0};

const OPTIONS: MeshOptions = MeshOptions { depth: 2, tile_cells: 4, finest_view_px: 400.0 };

fn terrain_in(dir: &Path) -> (Arc<Pyramid>, PreloadedTerrain) {
    let grid = pyramid::synthetic_grid(150).expect("a synthetic grid");
    let options = BuildOptions { node_size: 64, border: 2 };
    let built = pyramid::build(&grid, &options, &Silent).expect("build");
    pyramid::write_atomic(&built, &dir.join(pyramid::FILE_NAME), &Silent).expect("write");
    let pyramid = Arc::new(Pyramid::open(dir).expect("open"));
    let source = MeshedSource::open_or_build(Arc::clone(&pyramid), OPTIONS, &Silent).expect("maps");
    let terrain = PreloadedTerrain::load(&source).expect("every node reads");
    (pyramid, terrain)
}

/// A band over `level`'s posts: from `near` to `end` level-0 posts away
/// from `anchor` (level-0 posts), its error growing from `least_m`.
fn band(layout: &NodeLayout, anchor: [f64; 2], posts: [f64; 3], least_m: f64) -> RingView {
    let s = layout.spacing_m[0].max(layout.spacing_m[1]);
    let [near, start, end] = posts.map(|p| p * s);
    RingView {
        anchor_m: [anchor[0] * layout.spacing_m[0], anchor[1] * layout.spacing_m[1]],
        slack_m: 0.0,
        near_m: near,
        start_m: start,
        end_m: end,
        per_m: least_m / near,
        reference_m: 0.0,
        own_m: least_m,
        cone: None,
    }
}

fn rule(rings: &[RingView], ends: bool) -> DistanceRule {
    DistanceRule {
        rings: rings.iter().copied().collect(),
        ends,
        finest: rings.len().saturating_sub(1) as u8,
    }
}

fn place<'a>(
    layout: &'a NodeLayout,
    id: NodeId,
    data: &'a NodeData,
    rule: DistanceRule,
) -> PlacedMap<'a> {
    let least = rule.rings[0].own_m;
    testkit::mesh::place(layout, id, data, OPTIONS.tile_cells, least).with_view(rule)
}

fn extract(own: &PlacedMap<'_>, chain: &[PlacedMap<'_>], cells: u32) -> NodeMesh {
    let target = if chain.is_empty() { TargetMesh::None } else { TargetMesh::Parent };
    let job = Extraction {
        own,
        ancestors: chain,
        target,
        origin: [0, 0],
        width: cells,
        place_parent: false,
    };
    let mut extractor = Extractor::default();
    extractor.extract(&job).expect("extracts");
    extractor.mesh.clone()
}

/// No vertex lies strictly inside a triangle's edge: the mesh has no
/// T-junction, so it draws no crack inside itself.
fn assert_conforming(layout: &NodeLayout, id: NodeId, mesh: &NodeMesh) {
    let posts: Vec<[f64; 2]> =
        mesh.vertices.iter().map(|v| level0(layout, id, mesh, v.post)).collect();
    for tri in mesh.indices.chunks_exact(3) {
        for k in 0..3 {
            let (a, b) = (posts[tri[k] as usize], posts[tri[(k + 1) % 3] as usize]);
            for p in &posts {
                let inside = area(a, b, *p).abs() < 1e-9
                    && (0..2).all(|d| p[d] > a[d].min(b[d]) - 1e-9 && p[d] < a[d].max(b[d]) + 1e-9)
                    && *p != a
                    && *p != b;
                assert!(!inside, "{id:?}: vertex {p:?} inside the edge {a:?}-{b:?}");
            }
        }
    }
}

#[test]
fn a_mesh_by_distance_is_conforming_and_errs_within_its_rule() {
    let dir = testkit::fresh_dir("meshes-distance");
    let (pyramid, terrain) = terrain_in(&dir);
    let layout = *pyramid.layout();
    let last = layout.posts.map(|p| (p - 1) as f64);
    let (mut nodes, mut coarser) = (0, 0);
    for anchor in [[20.0, 30.0], [75.0, 75.0], [-40.0, 160.0]] {
        let [nx, ny] = layout.nodes_at(0);
        for id in (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(0, x, y))) {
            let data = terrain.resident(id).expect("every node of one grid");
            let span = layout.node_size as u64;
            let origin = [id.x as u64 * span, id.y as u64 * span];
            // Nodes the data fill (edges: `render_data_edges`).
            if (0..2).any(|k| (origin[k] + span) as f64 > last[k]) {
                continue;
            }
            let least = (data.map.floor_m as f64).max(0.3);
            // Two sub-levels chained: the finer's errors, then the coarser's.
            let fine = band(&layout, anchor, [2.0, 14.0, 20.0], least);
            let coarse = band(&layout, anchor, [20.0, 28.0, 40.0], least * 10.0);
            let rule = rule(&[fine, coarse], false);
            let own = place(&layout, id, data, rule.clone());
            let mesh = extract(&own, &[], data.map.cells);
            assert_conforming(&layout, id, &mesh);
            for j2 in 0..=2 * span {
                for i2 in 0..=2 * span {
                    let q = [(origin[0] * 2 + i2) as f64 / 2.0, (origin[1] * 2 + j2) as f64 / 2.0];
                    let centre = i2 % 2 == 1 && j2 % 2 == 1;
                    if (i2 % 2 == 1 || j2 % 2 == 1) && !centre {
                        continue;
                    }
                    let [sx, sy] = layout.spacing_m;
                    let exact = pyramid.exact_height(q[0] * sx, q[1] * sy).expect("inside") as f64;
                    let drawn = brute(&layout, id, &mesh, q, false).expect("covers its node");
                    let allowed =
                        rule.error_at([q[0] * sx, q[1] * sy], 0.0, [-1e9, 1e9]).expect("no end");
                    let bound =
                        allowed.max(data.map.floor_m as f64) + data.map.reference_delta as f64;
                    assert!(
                        (drawn - exact).abs() <= bound + 1e-3,
                        "{id:?} at {q:?}: off by {} > {bound}",
                        (drawn - exact).abs()
                    );
                }
            }
            nodes += 1;
            coarser += usize::from(mesh.vertices.len() < (data.map.cells as usize + 1).pow(2) / 2);
        }
    }
    assert!(nodes >= 8 && coarser > 0, "{nodes} nodes, {coarser} drawn coarser than the data");
}

#[test]
fn a_child_by_distance_keeps_its_parents_vertices_and_morphs_onto_its_surface() {
    let dir = testkit::fresh_dir("meshes-distance-morph");
    let (pyramid, terrain) = terrain_in(&dir);
    let layout = *pyramid.layout();
    let anchor = [30.0, 50.0];
    let [nx, ny] = layout.nodes_at(0);
    let mut shown = 0;
    for id in (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(0, x, y))) {
        let data = terrain.resident(id).expect("stored");
        let pid = id.parent().expect("below the root");
        let pdata = terrain.resident(pid).expect("stored");
        let least = (data.map.floor_m as f64).max(0.3);
        let parent_rule = rule(&[band(&layout, anchor, [30.0, 40.0, 60.0], 4.0 * least)], false);
        // The child's band ends where the parent's starts: past it, the
        // child keeps only the parent's vertices.
        let child_rule = rule(&[band(&layout, anchor, [2.0, 20.0, 30.0], least)], true);
        let parent_alone = place(&layout, pid, pdata, parent_rule.clone());
        let parent = extract(&parent_alone, &[], pdata.map.cells);
        let chain = [place(&layout, pid, pdata, parent_rule)];
        let own = place(&layout, id, data, child_rule);
        let child = extract(&own, &chain, data.map.cells);
        assert_conforming(&layout, id, &child);
        let posts: Vec<[f64; 2]> =
            child.vertices.iter().map(|v| level0(&layout, id, &child, v.post)).collect();
        let span = layout.node_size as f64;
        let origin = [id.x as f64 * span, id.y as f64 * span];
        let inside = |p: [f64; 2]| (0..2).all(|k| p[k] >= origin[k] && p[k] <= origin[k] + span);
        for v in &parent.vertices {
            let p = level0(&layout, pid, &parent, v.post);
            if inside(p) && v.post.iter().any(|c| c % 2 == 0) {
                assert!(posts.contains(&p), "{id:?}: parent vertex {p:?} missing");
            }
        }
        for (v, p) in child.vertices.iter().zip(&posts) {
            let on_parent = brute(&layout, pid, &parent, *p, false).expect("parent covers");
            if !(v.height.is_nan() || on_parent.is_nan()) {
                assert!((v.target as f64 - on_parent).abs() < 1e-2, "{id:?} {p:?}");
                shown += 1;
            }
        }
    }
    assert!(shown > 100, "only {shown} vertices compared");
}
