//! Joins several imported grids into one: they must share a coordinate
//! system and spacing, and their posts must fall on one common lattice (the
//! first file's). The mosaic covers the bounding box of all inputs; posts
//! no input covers are voids (filled later like any other void). Where
//! inputs overlap, such as the shared edge rows and columns of adjacent
//! SRTM or DTED tiles, the first file (in the order given) holding a valid
//! height there provides it.

use super::error::{ImportError, Problem};
use super::raw::{RawGrid, MAX_SAMPLES};
use crate::geo::GeoRef;

/// Largest relative difference between two inputs' spacings (covers
/// `0.000833333` written to nine digits against 1/1200).
pub const SPACING_TOLERANCE: f64 = 1e-6;
/// Largest distance, in spacings, of an input's posts from the lattice.
pub const ALIGNMENT_TOLERANCE: f64 = 0.01;

/// Joins `grids` (at least one) into one grid on the first grid's lattice.
pub fn mosaic(mut grids: Vec<RawGrid>) -> Result<RawGrid, ImportError> {
    if grids.len() <= 1 {
        return grids
            .pop()
            .ok_or_else(|| ImportError::new(std::path::Path::new(""), Problem::NoInput));
    }
    let reference = grids[0].georef;
    let mut placed = Vec::with_capacity(grids.len());
    let mut bounds = Bounds { min: [i64::MAX; 2], max: [i64::MIN; 2] };
    for grid in &grids {
        let offset = lattice_offset(&reference, grid)?;
        bounds.include(offset, [grid.width, grid.height]);
        if bounds.samples() > MAX_SAMPLES {
            let [w, h] = bounds.size();
            let why = format!(
                "with this file the mosaic would be {w} x {h} samples, more than {MAX_SAMPLES}"
            );
            return Err(ImportError::new(&grid.path, Problem::Mosaic(why)));
        }
        placed.push(offset);
    }
    let [width, height] = bounds.size().map(|s| s as u32);
    let origin = [0, 1].map(|a| reference.origin[a] + bounds.min[a] as f64 * reference.spacing[a]);
    let georef = GeoRef { origin, ..reference };
    let mut out = RawGrid::voids(&grids[0].path, width, height, georef);
    for (grid, offset) in grids.iter().zip(placed) {
        paste(&mut out, grid, [offset[0] - bounds.min[0], offset[1] - bounds.min[1]]);
    }
    out.debug_check();
    Ok(out)
}

/// Where `grid`'s post (0, 0) lies on the reference lattice, in spacings.
fn lattice_offset(reference: &GeoRef, grid: &RawGrid) -> Result<[i64; 2], ImportError> {
    let fail = |why: String| Err(ImportError::new(&grid.path, Problem::Mosaic(why)));
    let georef = &grid.georef;
    if georef.crs != reference.crs {
        return fail(format!(
            "coordinate system {:?} differs from the first file's {:?}",
            georef.crs, reference.crs
        ));
    }
    let relative =
        |a: usize| (georef.spacing[a] - reference.spacing[a]).abs() / reference.spacing[a];
    if relative(0) > SPACING_TOLERANCE || relative(1) > SPACING_TOLERANCE {
        return fail(format!(
            "spacing {:?} differs from the first file's {:?}",
            georef.spacing, reference.spacing
        ));
    }
    let cells = [0, 1].map(|a| (georef.origin[a] - reference.origin[a]) / reference.spacing[a]);
    let off_lattice = cells.iter().any(|c| (c - c.round()).abs() > ALIGNMENT_TOLERANCE);
    if off_lattice || cells.iter().any(|c| c.abs() > MAX_SAMPLES as f64) {
        return fail(format!(
            "its posts lie {cells:?} spacings from the first file's, not on the same lattice"
        ));
    }
    Ok(cells.map(|c| c.round() as i64))
}

/// Copies `grid` into `out` at `offset`, keeping heights already there.
fn paste(out: &mut RawGrid, grid: &RawGrid, offset: [i64; 2]) {
    let [di, dj] = offset.map(|o| u32::try_from(o).expect("offsets are inside the bounds"));
    for j in 0..grid.height {
        for i in 0..grid.width {
            let target = out.index(i + di, j + dj);
            if out.heights[target].is_nan() {
                out.heights[target] = grid.heights[grid.index(i, j)];
            }
        }
    }
}

/// The bounding box of the inputs on the lattice, in posts.
struct Bounds {
    min: [i64; 2],
    /// One past the last post.
    max: [i64; 2],
}

impl Bounds {
    fn include(&mut self, offset: [i64; 2], size: [u32; 2]) {
        for a in 0..2 {
            self.min[a] = self.min[a].min(offset[a]);
            self.max[a] = self.max[a].max(offset[a] + i64::from(size[a]));
        }
    }

    fn size(&self) -> [u64; 2] {
        [0, 1].map(|a| (self.max[a] - self.min[a]) as u64)
    }

    fn samples(&self) -> u64 {
        let [w, h] = self.size();
        w.saturating_mul(h)
    }
}
