//! The procedural earth as a node source: size, determinism, posts that are
//! samples, borders, exact min/max, and a delta bound that holds against
//! brute force.

use proptest::prelude::*;
use ridgeline::node::{NodeData, NodeError, NodeId, NodeSource};
use ridgeline::procedural::{EarthParams, ProceduralEarth, ProceduralError, HEIGHT_RANGE_M};

fn earth(node_size: u32) -> ProceduralEarth {
    ProceduralEarth::new(EarthParams::earth(node_size, 0x5eed)).unwrap()
}

fn read(earth: &ProceduralEarth, id: NodeId) -> NodeData {
    let mut data = NodeData::default();
    earth.read_node(id, &mut data).unwrap();
    data
}

/// The largest |surface - sample| over the level-0 samples a node covers.
fn brute_force_delta(earth: &ProceduralEarth, id: NodeId, data: &NodeData) -> f64 {
    let layout = earth.layout();
    let span = layout.span(id.level) as i64;
    let stride = (1i64 << id.level) as f64;
    let mut worst = 0.0f64;
    for j in 0..=span {
        for i in 0..=span {
            let surface = data.interpolate(layout, [i as f64 / stride, j as f64 / stride]) as f64;
            let sample = earth.sample(id.x as i64 * span + i, id.y as i64 * span + j) as f64;
            worst = worst.max((surface - sample).abs());
        }
    }
    worst
}

#[test]
fn covers_the_earth_with_a_single_root() {
    let earth = earth(16);
    let layout = earth.layout();
    assert!(layout.posts[0] > 1 << 24 && layout.posts[1] > 1 << 24);
    assert_eq!(layout.nodes_at(layout.levels - 1), [1, 1]);
    assert_eq!(layout.nodes_at(0), [1 << 20, 1 << 20]);
    assert!(layout.extent_m()[0] > 40_000_000.0);
    let root = read(&earth, NodeId::new(layout.levels - 1, 0, 0));
    assert!(root.max - root.min > 1000.0, "a continent-sized node has relief: {root:?}");
}

#[test]
fn heights_are_deterministic_and_depend_on_the_seed() {
    let id = NodeId::new(3, 12_345, 54_321);
    let a = read(&earth(16), id);
    assert_eq!(a, read(&earth(16), id));
    let other = ProceduralEarth::new(EarthParams::earth(16, 1)).unwrap();
    assert_ne!(a.heights, read(&other, id).heights);
}

#[test]
fn heights_stay_in_range_and_look_like_terrain() {
    let earth = earth(16);
    let [low, high] = earth.height_bounds();
    assert!(low >= HEIGHT_RANGE_M[0] - 1e-9 && high <= HEIGHT_RANGE_M[1] + 1e-9);
    let (mut min, mut max, mut sum, mut n) = (f64::MAX, f64::MIN, 0.0, 0.0);
    let step = 1i64 << 14;
    for j in (0..1 << 24).step_by(step as usize) {
        for i in (0..1 << 24).step_by(step as usize) {
            let h = earth.sample(i, j) as f64;
            (min, max, sum, n) = (min.min(h), max.max(h), sum + h, n + 1.0);
        }
    }
    println!("heights over 1024^2 samples: min {min:.0} m, mean {:.0} m, max {max:.0} m", sum / n);
    assert!(min >= low && max <= high);
    assert!(max - min > 3000.0, "mountains and lowlands");
    // Hills: a 1 km square of samples has relief, but not cliffs.
    let relief = |x: i64, y: i64| {
        let hs: Vec<f64> =
            (0..400).map(|k| earth.sample(x + k % 20 * 21, y + k / 20 * 21) as f64).collect();
        hs.iter().cloned().fold(f64::MIN, f64::max) - hs.iter().cloned().fold(f64::MAX, f64::min)
    };
    let local = relief(3_000_000, 7_000_000);
    assert!(local > 1.0 && local < 2000.0, "local relief {local}");
}

#[test]
fn posts_are_level_zero_samples_at_the_level_stride() {
    let earth = earth(16);
    let layout = *earth.layout();
    for id in [NodeId::new(0, 7, 9), NodeId::new(5, 1000, 3), NodeId::new(12, 17, 30)] {
        let data = read(&earth, id);
        let (span, stride) = (layout.span(id.level) as i64, 1i64 << id.level);
        for (i, j) in [(0, 0), (16, 16), (3, 11), (16, 0)] {
            let sample =
                earth.sample(id.x as i64 * span + i * stride, id.y as i64 * span + j * stride);
            assert_eq!(data.post(&layout, i as u32, j as u32), sample, "{id:?} post ({i}, {j})");
        }
        // The parent's posts are every second post of its children.
        let parent = read(&earth, id.parent().unwrap());
        let (ci, cj) = ((id.x % 2) * 8, (id.y % 2) * 8);
        assert_eq!(parent.post(&layout, ci + 4, cj + 2), data.post(&layout, 8, 4));
    }
}

#[test]
fn borders_repeat_the_neighbours_and_extend_at_the_edge() {
    let earth = earth(16);
    let layout = *earth.layout();
    let side = layout.stored_side() as usize;
    let (node, east) = (read(&earth, NodeId::new(2, 40, 40)), read(&earth, NodeId::new(2, 41, 40)));
    for row in 0..side {
        // Stored column side-1 of `node` is the border: `east`'s post 1.
        assert_eq!(node.heights[row * side + side - 1], east.heights[row * side + 2]);
    }
    let corner = read(&earth, NodeId::new(0, 0, 0));
    assert_eq!(
        corner.heights[0],
        corner.post(&layout, 0, 0),
        "south-west border clamps to the edge"
    );
}

#[test]
fn min_and_max_are_exact_over_the_centre_posts() {
    let earth = earth(8);
    let layout = *earth.layout();
    let data = read(&earth, NodeId::new(4, 77, 1234));
    let posts: Vec<f32> = (0..=8)
        .flat_map(|j| (0..=8).map(move |i| (i, j)))
        .map(|(i, j)| data.post(&layout, i, j))
        .collect();
    assert_eq!(data.min, posts.iter().cloned().fold(f32::MAX, f32::min));
    assert_eq!(data.max, posts.iter().cloned().fold(f32::MIN, f32::max));
}

#[test]
fn exact_height_matches_the_level_zero_node_surface() {
    struct ViaNodes(ProceduralEarth);
    impl NodeSource for ViaNodes {
        fn layout(&self) -> &ridgeline::node::NodeLayout {
            self.0.layout()
        }
        fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
            self.0.read_node(id, out)
        }
    }
    let direct = earth(16);
    let via_nodes = ViaNodes(earth(16));
    for (x, y) in [(0.0, 0.0), (1234.5, 987.25), (38.4, 38.4), (5e6 + 0.3, 2e7 + 1.9)] {
        let a = direct.exact_height(x, y).unwrap();
        let b = via_nodes.exact_height(x, y).unwrap();
        assert!((a - b).abs() < 1e-3, "({x}, {y}): {a} vs {b}");
    }
    let far = direct.layout().extent_m()[0];
    assert!(direct.exact_height(far, far).is_ok());
    assert!(matches!(direct.exact_height(-1.0, 0.0), Err(NodeError::OutsideData { .. })));
    assert!(matches!(via_nodes.exact_height(0.0, f64::NAN), Err(NodeError::OutsideData { .. })));
}

#[test]
fn refuses_bad_ids_and_parameters() {
    let earth = earth(16);
    let levels = earth.layout().levels;
    let mut data = NodeData::default();
    for id in [NodeId::new(levels, 0, 0), NodeId::new(0, 1 << 20, 0), NodeId::new(levels - 1, 0, 1)]
    {
        assert!(
            matches!(earth.read_node(id, &mut data), Err(NodeError::OutOfRange { .. })),
            "{id:?}"
        );
    }
    let good = EarthParams::earth(16, 0);
    let bad = [
        (EarthParams { node_size: 1, ..good }, ProceduralError::NodeSize(1)),
        (
            EarthParams { levels: 40, ..good },
            ProceduralError::TooLarge { node_size: 16, levels: 40 },
        ),
        (EarthParams { levels: 0, ..good }, ProceduralError::TooLarge { node_size: 16, levels: 0 }),
        (EarthParams { border: 17, ..good }, ProceduralError::Border { border: 17, node_size: 16 }),
    ];
    for (params, error) in bad {
        assert_eq!(ProceduralEarth::new(params).unwrap_err(), error);
    }
    assert!(matches!(
        ProceduralEarth::new(EarthParams { spacing_m: f64::NAN, ..good }),
        Err(ProceduralError::Spacing(_))
    ));
}

#[test]
fn delta_is_zero_at_level_zero_and_grows_with_the_level() {
    let earth = earth(16);
    assert_eq!(earth.delta_bound(0), 0.0);
    let deltas: Vec<f32> = (0..earth.layout().levels).map(|l| earth.delta_bound(l)).collect();
    assert!(deltas.windows(2).all(|w| w[0] < w[1]), "{deltas:?}");
    let [low, high] = earth.height_bounds();
    assert!(*deltas.last().unwrap() as f64 <= high - low + 1.0);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    /// The delta bound holds against brute force over every level-0 sample
    /// of random small nodes.
    #[test]
    fn delta_bound_holds_against_brute_force(lod in 1u8..=7, fx in 0.0f64..1.0, fy in 0.0f64..1.0, seed in any::<u64>()) {
        let earth = ProceduralEarth::new(EarthParams::earth(4, seed)).unwrap();
        let [nx, ny] = earth.layout().nodes_at(lod);
        let id = NodeId::new(lod, (fx * nx as f64) as u32, (fy * ny as f64) as u32);
        let data = read(&earth, id);
        let exact = brute_force_delta(&earth, id, &data);
        prop_assert!(exact <= data.delta as f64, "{id:?}: brute force {exact} > bound {}", data.delta);
        println!("{id:?}: brute force {exact:.3} m, bound {:.3} m", data.delta);
    }
}
