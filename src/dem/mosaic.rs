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
    let footprints: Vec<Footprint> = grids.iter().map(Footprint::of).collect();
    let plan = plan(&footprints, MAX_SAMPLES)?;
    let mut out = RawGrid::voids(&grids[0].path, plan.width, plan.height, plan.georef);
    for (grid, offset) in grids.iter().zip(plan.offsets) {
        paste(&mut out, grid, offset);
    }
    out.debug_check();
    Ok(out)
}

/// Where one input lies: its file, georeference and size in posts.
#[derive(Clone, Debug)]
pub struct Footprint {
    /// The input file.
    pub path: std::path::PathBuf,
    /// Its georeference.
    pub georef: GeoRef,
    /// Posts east and north.
    pub size: [u32; 2],
}

impl Footprint {
    /// The footprint of `grid`.
    pub fn of(grid: &RawGrid) -> Footprint {
        Footprint { path: grid.path.clone(), georef: grid.georef, size: [grid.width, grid.height] }
    }
}

/// A mosaic's lattice: its size, georeference, and each input's post
/// (0, 0) on it.
#[derive(Clone, Debug)]
pub struct MosaicPlan {
    /// Posts per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Where post (0, 0) is.
    pub georef: GeoRef,
    /// Per input, its post (0, 0) in the mosaic's posts.
    pub offsets: Vec<[u32; 2]>,
}

/// The lattice over `inputs` (at least one), the first one's, refusing a
/// mosaic of more than `max_samples` posts or more than `u32::MAX` a side.
pub fn plan(inputs: &[Footprint], max_samples: u64) -> Result<MosaicPlan, ImportError> {
    let reference = inputs[0].georef;
    let mut placed = Vec::with_capacity(inputs.len());
    let mut bounds = Bounds { min: [i64::MAX; 2], max: [i64::MIN; 2] };
    for input in inputs {
        let offset = lattice_offset(&reference, input)?;
        bounds.include(offset, input.size);
        let [w, h] = bounds.size();
        if bounds.samples() > max_samples || w > u64::from(u32::MAX) || h > u64::from(u32::MAX) {
            let why = format!(
                "with this file the mosaic would be {w} x {h} samples, more than {max_samples}"
            );
            return Err(ImportError::new(&input.path, Problem::Mosaic(why)));
        }
        placed.push(offset);
    }
    let [width, height] = bounds.size().map(|s| s as u32);
    let origin = [0, 1].map(|a| reference.origin[a] + bounds.min[a] as f64 * reference.spacing[a]);
    let offsets = placed.iter().map(|o| [0, 1].map(|a| (o[a] - bounds.min[a]) as u32)).collect();
    Ok(MosaicPlan { width, height, georef: GeoRef { origin, ..reference }, offsets })
}

/// Where `grid`'s post (0, 0) lies on the reference lattice, in spacings.
fn lattice_offset(reference: &GeoRef, grid: &Footprint) -> Result<[i64; 2], ImportError> {
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
    if off_lattice || cells.iter().any(|c| c.abs() > u32::MAX as f64) {
        return fail(format!(
            "its posts lie {cells:?} spacings from the first file's, not on the same lattice"
        ));
    }
    Ok(cells.map(|c| c.round() as i64))
}

/// Copies `grid` into `out` at `offset`, keeping heights already there.
fn paste(out: &mut RawGrid, grid: &RawGrid, offset: [u32; 2]) {
    let [di, dj] = offset;
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
        // Offsets are within u32::MAX of the first input: no overflow.
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
