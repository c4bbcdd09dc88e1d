//! The stored delta of a node equals a brute-force recomputation from the
//! full-resolution grid and the node's posts as read back from the file.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use ridgeline::dem::ElevationGrid;
use ridgeline::node::{NodeData, NodeId, NodeSource};
use ridgeline::pyramid::{BuildOptions, Pyramid};
use testkit::fresh_dir;
use testkit::pyramid::{build_and_write, random_grid};

/// Height of the plane through triangle `(a, b, c)` at `(x, y)` if the point
/// lies in the triangle (barycentric weights, with a little slack for points
/// on an edge).
fn height_in_triangle(a: DVec3, b: DVec3, c: DVec3, x: f64, y: f64) -> Option<f64> {
    let det = (b.y - c.y) * (a.x - c.x) + (c.x - b.x) * (a.y - c.y);
    let wa = ((b.y - c.y) * (x - c.x) + (c.x - b.x) * (y - c.y)) / det;
    let wb = ((c.y - a.y) * (x - c.x) + (a.x - c.x) * (y - c.y)) / det;
    let wc = 1.0 - wa - wb;
    let inside = [wa, wb, wc].iter().all(|w| *w >= -1e-12);
    inside.then_some(wa * a.z + wb * b.z + wc * c.z)
}

/// The largest vertical distance between the grid samples under node `id`
/// and the triangles of its posts, recomputed point by point.
fn brute_force_delta(
    grid: &ElevationGrid,
    node: &NodeData,
    id: NodeId,
    node_size: u32,
    border: u32,
) -> f64 {
    let step = 1u64 << id.level;
    let span = node_size as u64 * step;
    let side = (node_size + 1 + 2 * border) as usize;
    let (x0, y0) = (id.x as u64 * span, id.y as u64 * span);
    // A post's position in level-0 sample units, height from the file.
    let post = |p: usize, q: usize| {
        let h = node.heights[(q + border as usize) * side + p + border as usize] as f64;
        DVec3::new((x0 + p as u64 * step) as f64, (y0 + q as u64 * step) as f64, h)
    };
    let mut worst = 0.0f64;
    for j in y0..=(y0 + span).min(grid.height as u64 - 1) {
        for i in x0..=(x0 + span).min(grid.width as u64 - 1) {
            let (x, y) = (i as f64, j as f64);
            let p = (((i - x0) / step) as usize).min(node_size as usize - 1);
            let q = (((j - y0) / step) as usize).min(node_size as usize - 1);
            let (sw, se, nw, ne) = (post(p, q), post(p + 1, q), post(p, q + 1), post(p + 1, q + 1));
            let surface = height_in_triangle(sw, se, ne, x, y)
                .or_else(|| height_in_triangle(sw, ne, nw, x, y))
                .expect("every sample lies in one of its cell's triangles");
            worst = worst.max((grid.at(i as u32, j as u32) as f64 - surface).abs());
        }
    }
    worst
}

/// One f32 step at `value`: how close "equal" can be for a stored f32.
fn ulp(value: f32) -> f64 {
    (f32::from_bits(value.to_bits() + 1) - value) as f64
}

/// Checks `samples` random nodes of the pyramid built from `grid`.
fn check_random_nodes(
    grid: &ElevationGrid,
    options: BuildOptions,
    samples: usize,
    seed: u64,
    case: &str,
) {
    let dir = fresh_dir(&format!("delta-{case}"));
    let (_, path) = build_and_write(grid, options, &dir);
    let pyramid = Pyramid::open(&path).expect("open");
    let layout = *pyramid.layout();
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut node = NodeData::default();
    let mut coarse_with_error = 0;
    for _ in 0..samples {
        let lod = rng.random_range(0..layout.levels);
        let [nx, ny] = layout.nodes_at(lod);
        let id = NodeId::new(lod, rng.random_range(0..nx), rng.random_range(0..ny));
        pyramid.read_node(id, &mut node).expect("read");
        let brute = brute_force_delta(grid, &node, id, options.node_size, options.border);
        let stored = node.delta;
        // Two f64 formulations of one surface differ by ~1e-12 m at most.
        assert!(
            stored as f64 >= brute - 1e-9,
            "{case} {id:?}: stored {stored} below brute force {brute}"
        );
        assert!(
            stored as f64 - brute <= ulp(stored),
            "{case} {id:?}: stored {stored}, brute force {brute}"
        );
        if lod == 0 {
            assert_eq!(stored, 0.0, "level 0 passes through every sample");
        } else {
            coarse_with_error += (stored > 0.0) as u32;
        }
    }
    assert!(
        coarse_with_error > 0 || layout.levels == 1,
        "{case}: no coarse node with an error was checked"
    );
}

#[test]
fn stored_delta_equals_brute_force_on_the_shipped_srtm_tile() {
    let tile = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/dem/srtm3_n39e040_1000.tif");
    let grid =
        ridgeline::dem::import_file(std::path::Path::new(tile)).expect("import the shipped tile");
    check_random_nodes(&grid, BuildOptions::default(), 30, 0x5127, "srtm");
}

#[test]
fn stored_delta_equals_brute_force_on_random_nodes() {
    // Sizes that do and do not fill the last node, odd and even node sizes.
    let cases =
        [(203, 157, 16, 2), (129, 129, 32, 1), (300, 61, 20, 3), (65, 400, 8, 2), (2, 2, 4, 1)];
    for (case, &(width, height, node_size, border)) in cases.iter().enumerate() {
        let grid = random_grid(width, height, case as u64);
        check_random_nodes(
            &grid,
            BuildOptions { node_size, border },
            40,
            case as u64,
            &format!("random-{case}"),
        );
    }
}

#[test]
fn delta_is_measured_not_halved() {
    // A single spike: every level whose posts skip it must report its full
    // height, not a halving sequence.
    let dir = fresh_dir("delta-spike");
    let mut grid = random_grid(129, 129, 9);
    grid.heights.iter_mut().for_each(|h| *h = 100.0);
    grid.heights[65 * 129 + 65] = 600.0;
    let (built, _) = build_and_write(&grid, BuildOptions { node_size: 8, border: 1 }, &dir);
    let deltas: Vec<f32> = built.info.levels.iter().map(|l| l.delta_max).collect();
    assert_eq!(deltas[0], 0.0);
    assert!(deltas[1..].iter().all(|&d| d == 500.0), "{deltas:?}");
}
