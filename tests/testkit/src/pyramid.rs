//! Helpers shared by the pyramid tests: random grids, pyramids built and written.

use std::path::PathBuf;

use rand::{Rng, SeedableRng};
use ridgeline::dem::ElevationGrid;
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::pyramid::{self, BuildOptions, BuiltPyramid, Silent};

/// A rough random terrain: a random walk in both directions plus noise, so
/// coarse levels have real errors, with a geographic georeference.
pub fn random_grid(width: u32, height: u32, seed: u64) -> ElevationGrid {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut heights = vec![0.0f32; width as usize * height as usize];
    for j in 0..height as usize {
        for i in 0..width as usize {
            let west = if i > 0 { heights[j * width as usize + i - 1] } else { 500.0 };
            let south = if j > 0 { heights[(j - 1) * width as usize + i] } else { west };
            heights[j * width as usize + i] = 0.5 * (west + south) + rng.random_range(-40.0..40.0);
        }
    }
    let georef = GeoRef { crs: Crs::Geographic, origin: [7.5, 45.9], spacing: [1.0 / 1200.0; 2] };
    ElevationGrid { width, height, heights, georef, voids_filled: 3 }
}

/// A grid in UTM zone 37 N metres (EPSG:32637) whose post `(i, j)` has
/// height `h(x, y)` at its place: the layers the layered-pyramid tests
/// stack.
pub fn projected_grid(
    origin: [f64; 2],
    spacing: [f64; 2],
    posts: [u32; 2],
    h: impl Fn(f64, f64) -> f64,
) -> ElevationGrid {
    let heights = (0..posts[1])
        .flat_map(|j| (0..posts[0]).map(move |i| (i, j)))
        .map(|(i, j)| {
            h(origin[0] + i as f64 * spacing[0], origin[1] + j as f64 * spacing[1]) as f32
        })
        .collect();
    let georef = GeoRef { crs: Crs::Projected { epsg: Some(32637) }, origin, spacing };
    ElevationGrid { width: posts[0], height: posts[1], heights, georef, voids_filled: 0 }
}

/// Builds `grid` and writes it to `dir/pyramid.rlp`.
pub fn build_and_write(
    grid: &ElevationGrid,
    options: BuildOptions,
    dir: &std::path::Path,
) -> (BuiltPyramid, PathBuf) {
    let built = pyramid::build(grid, &options, &Silent).expect("build");
    let path = dir.join(pyramid::FILE_NAME);
    pyramid::write_atomic(&built, &path, &Silent).expect("write");
    (built, path)
}
