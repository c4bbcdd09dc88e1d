//! Void filling: turns a [`RawGrid`] with voids into an [`ElevationGrid`]
//! whose every height is finite, counting the samples it filled.
//!
//! Method: four-direction inverse-distance interpolation. Each void takes
//! the mean of the nearest valid sample in each of the four grid directions
//! (west and east along its row, south and north along its column), each
//! weighted by 1 / distance in samples; a direction that reaches the edge of
//! the grid through voids only contributes nothing. Consequences:
//! - a void between two valid samples of a line is interpolated linearly,
//!   and a void enclosed on all four sides inside a plane is restored exactly;
//! - every filled height lies within the range of the (at most four) heights
//!   it was computed from, so filling never invents peaks or pits;
//! - a pass reads only heights that were valid before it, so the result does
//!   not depend on the order of the work.
//!
//! A void whose whole row and whole column are void gets nothing in the first
//! pass; a second pass fills it from the first pass's results (after one pass
//! every row and column crossing a valid sample is complete, so two passes
//! always suffice). A grid with no valid sample at all is an error.
//!
//! Cost: O(n + v log v) for n samples and v voids, with 24 bytes per void.

use super::error::{ImportError, Problem};
use super::raw::RawGrid;
use super::ElevationGrid;

/// Fills every void of `raw` and returns the finished grid.
pub fn fill(mut raw: RawGrid) -> Result<ElevationGrid, ImportError> {
    raw.debug_check();
    let voids = raw.void_count();
    if voids == raw.heights.len() as u64 {
        return Err(ImportError::new(&raw.path, Problem::AllVoids));
    }
    let (width, height) = (raw.width as usize, raw.height as usize);
    let mut passes = 0;
    while fill_pass(&mut raw.heights, width, height) > 0 {
        passes += 1;
        debug_assert!(passes < 2, "two passes fill any grid with a valid sample");
    }
    debug_assert!(raw.heights.iter().all(|h| h.is_finite()));
    let RawGrid { width, height, heights, georef, .. } = raw;
    Ok(ElevationGrid { width, height, heights, georef, voids_filled: voids })
}

/// One pass over every void; returns how many voids are left.
fn fill_pass(heights: &mut [f32], width: usize, height: usize) -> usize {
    let voids: Vec<usize> = (0..heights.len()).filter(|&k| heights[k].is_nan()).collect();
    if voids.is_empty() {
        return 0;
    }
    // Weighted sum and total weight per void, in the order of `voids`.
    let mut sums = vec![(0.0f64, 0.0f64); voids.len()];
    let mut add = |index: usize, sum: f64, weight: f64| {
        let ordinal = voids.binary_search(&index).expect("only voids are visited");
        sums[ordinal].0 += sum;
        sums[ordinal].1 += weight;
    };
    for row in 0..height {
        visit_line(heights, Line { start: row * width, stride: 1, len: width }, &mut add);
    }
    for column in 0..width {
        visit_line(heights, Line { start: column, stride: width, len: height }, &mut add);
    }
    let mut left = 0;
    for (&index, &(sum, weight)) in voids.iter().zip(&sums) {
        if weight > 0.0 {
            heights[index] = (sum / weight) as f32;
        } else {
            left += 1;
        }
    }
    left
}

/// A row or column of the grid: samples `start + p * stride`, `p < len`.
#[derive(Clone, Copy)]
struct Line {
    start: usize,
    stride: usize,
    len: usize,
}

/// Calls `add(index, sum, weight)` for every void of the line that has a
/// valid sample before or after it, with the inverse-distance weighted sum
/// and total weight of those (at most two) nearest valid samples.
fn visit_line(heights: &[f32], line: Line, add: &mut impl FnMut(usize, f64, f64)) {
    let at = |p: usize| heights[line.start + p * line.stride];
    let mut p = 0;
    while p < line.len {
        if !at(p).is_nan() {
            p += 1;
            continue;
        }
        let run_start = p;
        while p < line.len && at(p).is_nan() {
            p += 1;
        }
        // The void run is [run_start, p); its valid neighbours bracket it.
        let before = run_start.checked_sub(1);
        let after = (p < line.len).then_some(p);
        if before.is_none() && after.is_none() {
            continue;
        }
        for q in run_start..p {
            let (mut sum, mut weight) = (0.0, 0.0);
            for neighbour in before.into_iter().chain(after) {
                let w = 1.0 / neighbour.abs_diff(q) as f64;
                sum += w * f64::from(at(neighbour));
                weight += w;
            }
            add(line.start + q * line.stride, sum, weight);
        }
    }
}
