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
//!
//! # Small and large voids
//! [`fill`] fills every void. The importers use [`fill_small`], which fills
//! only *small* voids: a void (4-connected region of void posts) every post
//! of which lies within [`SMALL_VOID_RADIUS`] posts (chessboard distance)
//! of a valid post, so at most 8 posts across. Larger voids, such as the
//! missing rows and columns of a partial SRTM tile, are left NaN: no data,
//! never drawn, unless a coarser layer covers them in a layered pyramid
//! (see [`crate::pyramid::layers`]). A terrain-awareness display must not
//! show terrain it invented.

use std::collections::VecDeque;

use super::error::{ImportError, Problem};
use super::raw::RawGrid;
use super::ElevationGrid;

/// A void whose every post lies within this many posts of valid data is
/// small and interpolated; larger voids stay no-data.
pub const SMALL_VOID_RADIUS: u32 = 4;

/// Fills the small voids of `raw` (see the module notes) and leaves the
/// large ones NaN; `voids_filled` counts the filled posts.
pub fn fill_small(mut raw: RawGrid) -> Result<ElevationGrid, ImportError> {
    raw.debug_check();
    if raw.void_count() == raw.heights.len() as u64 {
        return Err(ImportError::new(&raw.path, Problem::AllVoids));
    }
    let large = large_voids(&raw.heights, raw.width as usize, raw.height as usize);
    // Large-void posts are set aside (infinite, so no pass visits them; no
    // small void touches them, so none reads them) and put back afterwards.
    for &k in &large {
        raw.heights[k] = f32::INFINITY;
    }
    let small = raw.void_count();
    let (width, height) = (raw.width as usize, raw.height as usize);
    let mut passes = 0;
    while fill_pass(&mut raw.heights, width, height) > 0 {
        passes += 1;
        if passes >= 2 {
            break;
        }
    }
    for &k in &large {
        raw.heights[k] = f32::NAN;
    }
    let RawGrid { width, height, heights, georef, .. } = raw;
    Ok(ElevationGrid { width, height, heights, georef, voids_filled: small })
}

/// Each post's distance to the nearest post with data, in posts (8-
/// connected, two chamfer passes; `u32::MAX / 2` where there is none).
fn chamfer_distance(heights: &[f32], width: usize, height: usize) -> Vec<u32> {
    let far = u32::MAX / 2;
    let mut distance: Vec<u32> = heights.iter().map(|h| if h.is_nan() { far } else { 0 }).collect();
    for j in 0..height {
        for i in 0..width {
            let k = j * width + i;
            let mut d = distance[k];
            if i > 0 {
                d = d.min(distance[k - 1] + 1);
            }
            if j > 0 {
                d = d.min(distance[k - width] + 1);
                if i > 0 {
                    d = d.min(distance[k - width - 1] + 1);
                }
                if i + 1 < width {
                    d = d.min(distance[k - width + 1] + 1);
                }
            }
            distance[k] = d;
        }
    }
    for j in (0..height).rev() {
        for i in (0..width).rev() {
            let k = j * width + i;
            let mut d = distance[k];
            if i + 1 < width {
                d = d.min(distance[k + 1] + 1);
            }
            if j + 1 < height {
                d = d.min(distance[k + width] + 1);
                if i + 1 < width {
                    d = d.min(distance[k + width + 1] + 1);
                }
                if i > 0 {
                    d = d.min(distance[k + width - 1] + 1);
                }
            }
            distance[k] = d;
        }
    }
    distance
}

/// The posts of every large void: chessboard distance to the nearest valid
/// post above [`SMALL_VOID_RADIUS`] somewhere in its 4-connected region.
fn large_voids(heights: &[f32], width: usize, height: usize) -> Vec<usize> {
    let distance = chamfer_distance(heights, width, height);
    // Regions holding a post too far from data are large, whole.
    let mut seen = vec![false; heights.len()];
    let mut large = Vec::new();
    let mut queue = VecDeque::new();
    for start in 0..heights.len() {
        if seen[start] || distance[start] <= SMALL_VOID_RADIUS {
            continue;
        }
        seen[start] = true;
        queue.push_back(start);
        while let Some(k) = queue.pop_front() {
            large.push(k);
            let (i, j) = (k % width, k / width);
            let mut visit = |n: usize| {
                if !seen[n] && heights[n].is_nan() {
                    seen[n] = true;
                    queue.push_back(n);
                }
            };
            if i > 0 {
                visit(k - 1);
            }
            if i + 1 < width {
                visit(k + 1);
            }
            if j > 0 {
                visit(k - width);
            }
            if j + 1 < height {
                visit(k + width);
            }
        }
    }
    large.sort_unstable();
    large
}

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
