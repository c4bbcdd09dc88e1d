//! Page-in of the maps that store no heights (issue 21): the heights and
//! normals read straight from the pyramid's nodes are bit for bit those of
//! the reference grid (`reference_grid` then `fill_posts`, the build's
//! path), on random nodes (voids, zeros of either sign, absent nodes read
//! from an ancestor, neighbours that disagree on shared posts, the data's
//! last post inside a node, borders of 0 to 3) and on a layered pyramid
//! with voids.

use std::collections::HashSet;
use std::path::Path;

use proptest::prelude::*;
use ridgeline::meshes::build::fill_posts;
use ridgeline::meshes::pagein::fill_from_pyramid;
use ridgeline::meshes::reference::reference_grid;
use ridgeline::node::{ErrorMap, NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use ridgeline::pyramid::{self, BuildOptions, Pyramid, Silent};

/// Nodes of random heights, each its own (so neighbours and ancestors
/// disagree everywhere), some absent with all their descendants.
struct Random {
    layout: NodeLayout,
    absent: HashSet<NodeId>,
    seed: u64,
}

impl Random {
    fn new(node_size: u32, border: u32, posts: [u32; 2], seed: u64, absent_share: u64) -> Random {
        let levels = NodeLayout::levels_for(posts, node_size);
        let layout = NodeLayout { levels, node_size, border, posts, spacing_m: [30.0, 45.0] };
        let mut random = Random { layout, absent: HashSet::new(), seed };
        // Top-down, so a node is absent with all its descendants (presence
        // is hierarchical), and the root is always stored.
        for level in (0..levels.saturating_sub(1)).rev() {
            let [nx, ny] = layout.nodes_at(level);
            for id in (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(level, x, y))) {
                let parent_absent = id.parent().is_some_and(|p| random.absent.contains(&p));
                if parent_absent || random.mix(id, u64::MAX) % 100 < absent_share {
                    random.absent.insert(id);
                }
            }
        }
        random
    }

    fn mix(&self, id: NodeId, k: u64) -> u64 {
        let mut z = self.seed
            ^ (u64::from(id.level) << 56)
            ^ (u64::from(id.x) << 28)
            ^ u64::from(id.y)
            ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A height, now and then without data, zero or negative zero.
    fn height(&self, id: NodeId, k: u64) -> f32 {
        let r = self.mix(id, k);
        match r % 64 {
            0 => f32::NAN,
            1 => 0.0,
            2 => -0.0,
            _ => (r >> 8) as f32 / (1u64 << 56) as f32 * 3000.0 - 400.0,
        }
    }
}

impl NodeSource for Random {
    fn layout(&self) -> &NodeLayout {
        &self.layout
    }

    fn has_node(&self, id: NodeId) -> bool {
        self.layout.contains(id) && !self.absent.contains(&id)
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        if !self.has_node(id) {
            return Err(NodeError::Absent { id });
        }
        let side = self.layout.stored_side() as u64;
        out.heights.clear();
        out.heights.extend((0..side * side).map(|k| self.height(id, k)));
        Ok(())
    }
}

/// Checks page-in against the reference grid for node `id` on the
/// lattice `shift` levels finer, with every `every`-th post as a key.
fn check_node(source: &dyn NodeSource, id: NodeId, shift: u8, every: u32) {
    let post_level = id.level - shift;
    let grid = reference_grid(source, id, post_level).expect("reads the grid");
    let mut expected = ErrorMap {
        post_level,
        cells: grid.side - 1,
        keys: (0..grid.side * grid.side).step_by(every as usize).collect(),
        ..ErrorMap::default()
    };
    let mut read = expected.clone();
    fill_posts(&mut expected, &grid, source.layout());
    fill_from_pyramid(source, id, &mut read).expect("reads the posts");
    let bits = |h: &[f32]| h.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let what = format!("{id:?} on level {post_level}");
    assert_eq!(bits(&read.heights), bits(&expected.heights), "{what}");
    assert_eq!(read.normals, expected.normals, "{what}");
}

/// Every stored node of `source` from level 1 up, its map 1 and 2 levels
/// finer (what the maps that store no heights have).
fn check_every_node(source: &dyn NodeSource, every: u32) -> usize {
    let layout = *source.layout();
    let mut checked = 0;
    for level in 1..layout.levels {
        let [nx, ny] = layout.nodes_at(level);
        for id in (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(level, x, y))) {
            if !source.has_node(id) {
                continue;
            }
            for shift in 1..=level.min(2) {
                check_node(source, id, shift, every);
                checked += 1;
            }
        }
    }
    checked
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn page_in_reads_the_reference_grids_bits(
        size_log in 2u32..=4,
        border in 0u32..=3,
        posts in [20u32..90, 20u32..90],
        seed in any::<u64>(),
        absent_share in 0u64..40,
        every in 1u32..=3,
    ) {
        let source = Random::new(1 << size_log, border, posts, seed, absent_share);
        prop_assert!(check_every_node(&source, every) > 0);
    }
}

/// A coarse layer and a fine one, both with a hole of voids (a hole in
/// one is filled from the other) and ending inside nodes: real pyramid
/// nodes, absent ones read from their ancestors.
fn layered_with_voids(dir: &Path) -> Pyramid {
    use ridgeline::dem::ElevationGrid;
    use ridgeline::geo::{Crs, GeoRef};
    let terrain = |x: f64, y: f64| 600.0 + 250.0 * (x / 3000.0).sin() * (y / 4100.0).cos();
    let hole = |x: f64, y: f64| (x - 4_000.0).hypot(y - 5_000.0) < 700.0;
    let layer = |origin: [f64; 2], spacing: f64, posts: [u32; 2]| {
        let heights = (0..posts[1])
            .flat_map(|j| (0..posts[0]).map(move |i| (i, j)))
            .map(|(i, j)| {
                let (x, y) = (origin[0] + i as f64 * spacing, origin[1] + j as f64 * spacing);
                if hole(x, y) {
                    f32::NAN
                } else {
                    terrain(x, y) as f32
                }
            })
            .collect();
        let crs = Crs::Projected { epsg: Some(32632) };
        let georef = GeoRef { crs, origin, spacing: [spacing; 2] };
        ElevationGrid { width: posts[0], height: posts[1], heights, georef, voids_filled: 0 }
    };
    let layers = [layer([0.0, 0.0], 400.0, [42, 39]), layer([2_000.0, 3_000.0], 100.0, [61, 75])];
    let options = BuildOptions { node_size: 16, border: 2 };
    let built = pyramid::build_layers(&layers, &options, &Silent).expect("build the layers");
    pyramid::write_atomic(&built, &dir.join(pyramid::FILE_NAME), &Silent).expect("write");
    Pyramid::open(dir).expect("open")
}

#[test]
fn page_in_reads_a_layered_pyramids_grids_bits() {
    let dir = testkit::fresh_dir("meshes-pagein");
    let pyramid = layered_with_voids(&dir);
    let layout = *pyramid.layout();
    let level0 = |id: NodeId| id.level == 0 && pyramid.has_node(id);
    let [nx, ny] = layout.nodes_at(0);
    let stored = (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(0, x, y)));
    let count = stored.filter(|&id| level0(id)).count();
    assert!(count > 0 && count < (nx * ny) as usize, "some level-0 nodes absent");
    let inside = |k: usize| (layout.posts[k] - 1) % layout.node_size != 0;
    assert!(inside(0) && inside(1), "the data's last post inside a node: {layout:?}");
    let mut data = NodeData::default();
    let voids = (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(0, x, y))).any(|id| {
        level0(id) && {
            pyramid.read_node(id, &mut data).expect("reads");
            data.heights.iter().any(|h| h.is_nan())
        }
    });
    assert!(voids, "some level-0 posts without data");
    assert!(check_every_node(&pyramid, 1) > 0);
}
