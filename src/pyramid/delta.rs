//! Ulrich's geometric error delta for every node of one level, measured
//! against the full-resolution grid.
//!
//! The posts of level `l` joined as triangles form one surface shared by all
//! nodes of the level (neighbours share their edge posts). For each level-0
//! sample the vertical distance to that surface is computed once, row by row
//! in parallel, and each node keeps the largest distance among the samples it
//! covers, edge samples counting for both neighbours.

use rayon::prelude::*;

use super::progress::Progress;
use super::raster::LevelRaster;
use crate::dem::ElevationGrid;
use crate::mesh::rtin::round_up_to_f32;

/// Delta of every node of level `raster.level`, `nodes[0] * nodes[1]` values in
/// node order (row by row, south first), each rounded up to `f32`.
pub(crate) fn level_deltas(
    grid: &ElevationGrid,
    raster: &LevelRaster,
    nodes: [u32; 2],
    span: u64,
    progress: &dyn Progress,
) -> Vec<f32> {
    let node_count = nodes[0] as usize * nodes[1] as usize;
    if raster.level == 0 {
        // The level-0 surface passes through every sample.
        return vec![0.0; node_count];
    }
    let width = grid.width as usize;
    let worst = (0..grid.height)
        .into_par_iter()
        .fold(
            || (vec![0.0f64; node_count], vec![0.0f64; width]),
            |(mut worst, mut row_error), j| {
                row_distances(grid, raster, j, &mut row_error);
                record_row(&row_error, j, nodes, span, &mut worst);
                progress.advance(1);
                (worst, row_error)
            },
        )
        .map(|(worst, _)| worst)
        .reduce(
            || vec![0.0; node_count],
            |a, b| a.iter().zip(&b).map(|(x, y)| x.max(*y)).collect(),
        );
    worst.into_iter().map(round_up_to_f32).collect()
}

/// Vertical distance from each sample of level-0 row `j` to the level's surface.
///
/// Within one cell and one row the surface is linear in `fu` on each side of
/// the diagonal, so each cell is two branch-free runs: samples west of the
/// diagonal (`a < b`, north-west triangle) and the rest (south-east).
fn row_distances(grid: &ElevationGrid, raster: &LevelRaster, j: u32, out: &mut [f64]) {
    let lod = raster.level;
    let step = 1usize << lod;
    let inv_step = 1.0 / step as f64;
    let m = j >> lod;
    let south = raster.row(m);
    let north = raster.row((m + 1).min(raster.rows - 1));
    let b = (j as usize) & (step - 1);
    let fv = b as f64 * inv_step;
    let last = raster.cols as usize - 1;
    let samples = &grid.heights[j as usize * grid.width as usize..][..grid.width as usize];
    for (k, (samples, out)) in samples.chunks(step).zip(out.chunks_mut(step)).enumerate() {
        let k1 = (k + 1).min(last);
        let (h00, h10, h01, h11) =
            (south[k] as f64, south[k1] as f64, north[k] as f64, north[k1] as f64);
        // cell_surface with fv fixed: base + fu * slope on each triangle.
        let (north_west_base, north_west_slope) = (h00 + fv * (h01 - h00), h11 - h01);
        let (south_east_base, south_east_slope) = (h00 + fv * (h11 - h10), h10 - h00);
        let split = b.min(samples.len());
        let (west, east) = samples.split_at(split);
        let (out_west, out_east) = out.split_at_mut(split);
        distances_to_line(west, 0, north_west_base, north_west_slope, inv_step, out_west);
        distances_to_line(east, split, south_east_base, south_east_slope, inv_step, out_east);
    }
}

/// `|sample - (base + fu * slope)|` for samples `first, first + 1, ...` of a
/// cell, `fu = a / step`.
#[inline]
fn distances_to_line(
    samples: &[f32],
    first: usize,
    base: f64,
    slope: f64,
    inv_step: f64,
    out: &mut [f64],
) {
    for (a, (&sample, out)) in (first..).zip(samples.iter().zip(out)) {
        *out = (sample as f64 - (base + a as f64 * inv_step * slope)).abs();
    }
}

/// Folds one row's distances into the nodes that cover the row.
fn record_row(row_error: &[f64], j: u32, nodes: [u32; 2], span: u64, worst: &mut [f64]) {
    let node_row = j as u64 / span;
    let on_edge = j as u64 % span == 0 && node_row > 0;
    let rows = [Some(node_row), on_edge.then(|| node_row - 1)];
    let last_sample = row_error.len() as u64 - 1;
    for y in rows.into_iter().flatten().filter(|&y| y < nodes[1] as u64) {
        for x in 0..nodes[0] as u64 {
            let first = x * span;
            let end = ((x + 1) * span).min(last_sample);
            let largest =
                row_error[first as usize..=end as usize].iter().fold(0.0f64, |a, &b| a.max(b));
            let slot = &mut worst[(y * nodes[0] as u64 + x) as usize];
            *slot = slot.max(largest);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::node::cell_surface;

    #[test]
    fn rounding_up_never_loses_the_bound() {
        for value in [0.0, 0.1, 1.0 / 3.0, 1234.5678901, 1e-30] {
            let r = round_up_to_f32(value);
            assert!(r as f64 >= value);
            assert!((r as f64 - value) <= (value * 1e-6).max(1e-40));
        }
    }

    #[test]
    fn the_cell_surface_meets_its_corners_and_diagonal() {
        let (h00, h10, h01, h11) = (1.0, 2.0, 4.0, 8.0);
        assert_eq!(cell_surface(h00, h10, h01, h11, 0.0, 0.0), h00);
        assert_eq!(cell_surface(h00, h10, h01, h11, 1.0, 0.0), h10);
        assert_eq!(cell_surface(h00, h10, h01, h11, 0.0, 1.0), h01);
        assert_eq!(cell_surface(h00, h10, h01, h11, 1.0, 1.0), h11);
        // On the diagonal both triangles agree: linear from h00 to h11.
        assert_eq!(cell_surface(h00, h10, h01, h11, 0.5, 0.5), 4.5);
    }
}
