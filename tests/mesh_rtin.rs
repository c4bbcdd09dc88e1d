//! Property tests of `ridgeline::mesh` against simple models: the extracted
//! mesh errs by at most its threshold, its triangles tile the square once
//! with no T-junction, the delta and the mesh lookup equal brute force, and
//! view refinement never adds triangles as tau grows, and the restricted
//! RTIN gives every aligned square the codes of the square's own RTIN.

use proptest::prelude::*;
use ridgeline::mesh::{
    code::error_code, max_post_distance, max_surface_distance, view_refine, Diagonal, HeightGrid,
    Mesh, MeshSampler, Metric, OwnCodes, Rtin, RtinOptions, ViewParams,
};

/// A grid of `2^k + 1` posts a side with random heights: rough noise or a
/// smooth random walk, so that meshes range from full to nearly empty.
fn grid() -> impl Strategy<Value = (u32, Vec<f32>)> {
    (1u32..=5, any::<bool>()).prop_flat_map(|(k, smooth)| {
        let side = (1 << k) + 1;
        prop::collection::vec(-50.0f32..50.0, (side * side) as usize).prop_map(move |noise| {
            let heights = if smooth { integrate(side, &noise) } else { noise };
            (side, heights)
        })
    })
}

/// Running sums along rows and columns: a rough but correlated surface.
fn integrate(side: u32, noise: &[f32]) -> Vec<f32> {
    let s = side as usize;
    let mut h = noise.to_vec();
    for j in 0..s {
        for i in 1..s {
            h[j * s + i] = h[j * s + i - 1] + noise[j * s + i] * 0.1;
        }
    }
    for j in 1..s {
        for i in 0..s {
            h[j * s + i] += h[(j - 1) * s + i] * 0.5;
        }
    }
    h
}

fn corners(mesh: &Mesh, t: usize) -> [[f64; 2]; 3] {
    mesh.triangle(t).map(|[i, j]| [i as f64, j as f64])
}

fn area2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Barycentric weights of `p` in `tri` when `p` is inside or on it.
fn weights(tri: [[f64; 2]; 3], p: [f64; 2]) -> Option<[f64; 3]> {
    let w = [area2(tri[1], tri[2], p), area2(tri[2], tri[0], p), area2(tri[0], tri[1], p)];
    let sum = w[0] + w[1] + w[2];
    w.iter().all(|&x| x >= 0.0).then(|| w.map(|x| x / sum))
}

/// The model of a mesh's height at `p`: the first triangle found by linear search.
fn brute_height(mesh: &Mesh, h: &[f32], p: [f64; 2]) -> f64 {
    (0..mesh.triangle_count())
        .find_map(|t| {
            let w = weights(corners(mesh, t), p)?;
            let idx = &mesh.indices[3 * t..3 * t + 3];
            Some((0..3).map(|k| w[k] * h[idx[k] as usize] as f64).sum())
        })
        .expect("every point of the square is covered")
}

fn brute_post_distance(mesh: &Mesh, h: &[f32], grid: &HeightGrid) -> f64 {
    let mut worst = 0.0f64;
    for j in 0..grid.side() {
        for i in 0..grid.side() {
            let on_mesh = brute_height(mesh, h, [i as f64, j as f64]);
            worst = worst.max((on_mesh - grid.at(i, j) as f64).abs());
        }
    }
    worst
}

/// Posts and every cell centre (the level-0 surface there is the mean of the
/// cell's south-west and north-east posts): a superset of the overlay's vertices.
fn brute_surface_distance(mesh: &Mesh, h: &[f32], grid: &HeightGrid) -> f64 {
    let mut worst = brute_post_distance(mesh, h, grid);
    for j in 0..grid.cells() {
        for i in 0..grid.cells() {
            let level0 = (grid.at(i, j) as f64 + grid.at(i + 1, j + 1) as f64) / 2.0;
            let on_mesh = brute_height(mesh, h, [i as f64 + 0.5, j as f64 + 0.5]);
            worst = worst.max((on_mesh - level0).abs());
        }
    }
    worst
}

/// Counter-clockwise triangles covering each quarter of every cell exactly
/// once (RTIN triangles are unions of the quarters cut by the cell
/// diagonals), and no vertex inside another triangle's edge.
fn assert_tiles_and_conforms(mesh: &Mesh) {
    let cells = (mesh.side - 1) as f64;
    let total: f64 = (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = corners(mesh, t);
            let doubled = area2(a, b, c);
            assert!(doubled > 0.0, "triangle {t} is counter-clockwise from above");
            doubled / 2.0
        })
        .sum();
    assert_eq!(total, cells * cells);
    for j in 0..mesh.side - 1 {
        for i in 0..mesh.side - 1 {
            let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
            for p in [[x - 0.25, y], [x + 0.25, y], [x, y - 0.25], [x, y + 0.25]] {
                let covering =
                    (0..mesh.triangle_count()).filter(|&t| weights(corners(mesh, t), p).is_some());
                assert_eq!(covering.count(), 1, "quarter at {p:?}");
            }
        }
    }
    for t in 0..mesh.triangle_count() {
        let tri = corners(mesh, t);
        for k in 0..3 {
            let (p, q) = (tri[k], tri[(k + 1) % 3]);
            for v in &mesh.vertices {
                let v = [v[0] as f64, v[1] as f64];
                let inside = area2(p, q, v) == 0.0
                    && (v[0] - p[0]) * (v[0] - q[0]) + (v[1] - p[1]) * (v[1] - q[1]) < 0.0;
                assert!(!inside, "T-junction at {v:?} on the edge {p:?}-{q:?}");
            }
        }
    }
}

/// The mesh of the triangles a walk emits, numbered naively.
fn mesh_of(side: u32, triangles: &[[[u32; 2]; 3]]) -> Mesh {
    let mut vertices: Vec<[u16; 2]> = Vec::new();
    let mut indices = Vec::new();
    for tri in triangles {
        for v in tri {
            let v = [v[0] as u16, v[1] as u16];
            let at = vertices.iter().position(|&w| w == v).unwrap_or_else(|| {
                vertices.push(v);
                vertices.len() - 1
            });
            indices.push(at as u16);
        }
    }
    Mesh { side, vertices, indices }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn extracted_meshes_hold_their_bound_and_tile((side, heights) in grid(), max_error in 0.0f64..60.0) {
        let grid = HeightGrid::new(side, &heights).unwrap();
        let rtin = Rtin::new(&grid, RtinOptions::default()).unwrap();
        let mesh = rtin.extract(max_error).unwrap();
        let h = mesh.vertex_heights(&grid);
        let delta = max_post_distance(&mesh, &h, &grid);
        prop_assert!(delta <= max_error, "delta {delta} above {max_error}");
        prop_assert_eq!(mesh.triangle_count(), rtin.triangle_count(max_error));
        assert_tiles_and_conforms(&mesh);
    }

    #[test]
    fn surface_meshes_hold_their_bound_against_the_truth_surface((side, heights) in grid(), max_error in 0.0f64..60.0) {
        let grid = HeightGrid::new(side, &heights).unwrap();
        let rtin = Rtin::new(&grid, RtinOptions { metric: Metric::Surface, ..RtinOptions::default() }).unwrap();
        let mesh = rtin.extract(max_error).unwrap();
        let h = mesh.vertex_heights(&grid);
        let delta = max_surface_distance(&mesh, &h, &grid);
        prop_assert!(delta <= max_error, "surface delta {delta} above {max_error}");
        prop_assert!((delta - brute_surface_distance(&mesh, &h, &grid)).abs() <= 1e-9 * (1.0 + delta));
        assert_tiles_and_conforms(&mesh);
    }

    #[test]
    fn delta_and_lookup_equal_brute_force((side, heights) in grid(), max_error in 0.0f64..60.0, px in 0.0f64..=1.0, py in 0.0f64..=1.0) {
        let grid = HeightGrid::new(side, &heights).unwrap();
        let mesh = Rtin::new(&grid, RtinOptions::default()).unwrap().extract(max_error).unwrap();
        let h = mesh.vertex_heights(&grid);
        let post = max_post_distance(&mesh, &h, &grid);
        let surface = max_surface_distance(&mesh, &h, &grid);
        prop_assert!((post - brute_post_distance(&mesh, &h, &grid)).abs() <= 1e-9 * (1.0 + post));
        prop_assert!((surface - brute_surface_distance(&mesh, &h, &grid)).abs() <= 1e-9 * (1.0 + surface));
        let sampler = MeshSampler::new(&mesh, &h);
        let p = [px * grid.cells() as f64, py * grid.cells() as f64];
        let looked_up = sampler.height_on_mesh(p[0], p[1]).unwrap();
        prop_assert!((looked_up - brute_height(&mesh, &h, p)).abs() <= 1e-6 * (1.0 + looked_up.abs()));
    }

    #[test]
    fn forced_edges_keep_their_posts_and_still_tile((side, heights) in grid(), max_error in 0.0f64..60.0, step_log in 0u32..3) {
        let step = 1u32 << step_log;
        let grid = HeightGrid::new(side, &heights).unwrap();
        let rtin = Rtin::new(&grid, RtinOptions { edge_step: Some(step), ..RtinOptions::default() }).unwrap();
        let mesh = rtin.extract(max_error).unwrap();
        let last = (side - 1) as u16;
        for k in (0..=last).step_by(step.min(side - 1) as usize) {
            for post in [[k, 0], [k, last], [0, k], [last, k]] {
                prop_assert!(mesh.vertices.contains(&post), "{:?}", post);
            }
        }
        let h = mesh.vertex_heights(&grid);
        prop_assert!(max_post_distance(&mesh, &h, &grid) <= max_error);
        let edges = mesh.boundary_vertices();
        prop_assert!(edges.iter().all(|e| e.len() as u32 > (side - 1) / step));
        assert_tiles_and_conforms(&mesh);
    }

    #[test]
    fn view_refinement_never_grows_with_tau((side, heights) in grid(), eye in (0.0f64..3000.0, 0.0f64..3000.0, -100.0f64..500.0), tau in 0.1f64..8.0) {
        let grid = HeightGrid::new(side, &heights).unwrap();
        let rtin = Rtin::new(&grid, RtinOptions { bounds: true, ..RtinOptions::default() }).unwrap();
        let view = |tau| ViewParams { eye: [eye.0, eye.1, eye.2], spacing: [90.0, 70.0], k: 1108.0, tau };
        let mut fine = Vec::new();
        let n_fine = view_refine(&rtin, &view(tau), &mut |t| fine.push(t.ccw())).unwrap();
        let n_coarse = view_refine(&rtin, &view(tau * 2.0), &mut |_| {}).unwrap();
        prop_assert!(n_coarse <= n_fine, "{} at 2 tau > {} at tau", n_coarse, n_fine);
        prop_assert_eq!(n_fine as usize, fine.len());
        assert_tiles_and_conforms(&mesh_of(side, &fine));
    }
    /// The restricted RTIN against the simple model, the full RTIN of each
    /// aligned square's own grid: the same code at every post of the square,
    /// its edge posts included (the edge rule: a square's edge post takes
    /// only the triangles inside the square, never the block's outside it).
    /// Posts without data (NaN) are mixed in.
    #[test]
    fn restricted_rtin_equals_each_squares_own((side, mut heights) in grid(), voids in prop::collection::vec(any::<u16>(), 0..4), south_east in any::<bool>(), surface in any::<bool>()) {
        for v in voids {
            let k = v as usize % heights.len();
            heights[k] = f32::NAN;
        }
        let grid = HeightGrid::with_voids(side, &heights).unwrap();
        let metric = if surface { Metric::Surface } else { Metric::Posts };
        let block_diagonal = if south_east { Diagonal::SouthEast } else { Diagonal::SouthWest };
        let own = OwnCodes::new(&grid, block_diagonal, metric);
        let cells = side - 1;
        let mut size = cells;
        let mut level = 0u32;
        while size >= 2 {
            for y in 0..cells / size {
                for x in 0..cells / size {
                    // Sub-squares keep the block's hierarchy: a block split
                    // south-east is square (1, 0) of a grid split south-west.
                    let shift = u32::from(south_east) << level;
                    let diagonal = Diagonal::of_node(x + shift, y);
                    let n = size + 1;
                    let sub: Vec<f32> = (0..n * n)
                        .map(|k| heights[((y * size + k / n) * side + x * size + k % n) as usize])
                        .collect();
                    let sub_grid = HeightGrid::with_voids(n, &sub).unwrap();
                    let options = RtinOptions { metric, diagonal, ..RtinOptions::default() };
                    let rtin = Rtin::new(&sub_grid, options).unwrap();
                    let codes = own.restrict([x * size, y * size], size, diagonal);
                    for k in 0..n * n {
                        let expected = error_code(rtin.error_at(k % n, k / n) as f64);
                        prop_assert_eq!(codes[k as usize], expected, "square {}x{} at ({}, {}), post {}", size, size, x, y, k);
                    }
                }
            }
            size /= 2;
            level += 1;
        }
    }
}

#[test]
fn regular_grids_measure_as_the_pyramid_does() {
    let side = 17u32;
    let heights: Vec<f32> = (0..side * side).map(|k| ((k * 7919) % 31) as f32).collect();
    let grid = HeightGrid::new(side, &heights).unwrap();
    for stride in [1, 2, 4, 8, 16] {
        let mesh = Mesh::regular(side, stride).unwrap();
        let h = mesh.vertex_heights(&grid);
        let delta = max_post_distance(&mesh, &h, &grid);
        assert_eq!(delta, brute_post_distance(&mesh, &h, &grid));
        // No edge runs north-west to south-east: the surface measure adds nothing.
        assert_eq!(max_surface_distance(&mesh, &h, &grid), delta);
        assert_tiles_and_conforms(&mesh);
    }
}

#[test]
fn bad_grids_are_refused() {
    use ridgeline::mesh::MeshError;
    assert_eq!(HeightGrid::new(6, &[0.0; 36]).err(), Some(MeshError::Side(6)));
    assert!(matches!(HeightGrid::new(5, &[0.0; 24]), Err(MeshError::Length { .. })));
    let mut nan = [0.0f32; 9];
    nan[4] = f32::NAN;
    assert_eq!(HeightGrid::new(3, &nan).err(), Some(MeshError::NotFinite { i: 1, j: 1 }));
    let grid = [0.0f32; 9];
    let rtin = Rtin::new(&HeightGrid::new(3, &grid).unwrap(), RtinOptions::default()).unwrap();
    assert!(rtin.extract(f64::NAN).is_err());
    assert!(rtin.extract(-1.0).is_err());
}
