//! What every importer produces before mosaicking and void filling: a grid in
//! the crate's conventions whose voids are still marked, plus the checks every
//! importer shares (dimension limits, bounded file reads, nodata matching).

use std::io::Read;
use std::path::{Path, PathBuf};

use super::error::{ImportError, Problem};
use crate::geo::GeoRef;

/// The most samples a grid held on the heap (a file read whole, an
/// in-memory mosaic) may have: 2^28, a 16384 x 16384 grid, 1 GiB of `f32`.
/// The streaming import ([`crate::pyramid::spilled`]) decodes larger files
/// swath by swath into spills.
pub const MAX_SAMPLES: u64 = 1 << 28;

/// The most posts one file may declare: 2^33 (a 15" world grid is 2^31.8),
/// 32 GiB of spill. Larger declarations are refused before anything is
/// allocated or created: they are corrupt headers (every format's length
/// check refuses most of them first; a compressed GeoTIFF may declare
/// 4096 times its bytes).
pub const MAX_FILE_POSTS: u64 = 1 << 33;

/// One imported file (or a mosaic of several) with its voids still in place.
///
/// Conventions of [`crate::geo`]: `heights[j * width + i]` is post `(i, j)`,
/// row 0 is the southern row. Invariant: every height is either finite or NaN,
/// and NaN means void (inputs never produce NaN otherwise: a NaN that is not
/// the declared nodata is an error).
#[derive(Clone, Debug, PartialEq)]
pub struct RawGrid {
    /// The file this came from (the first file of a mosaic).
    pub path: PathBuf,
    /// Posts per row, west to east.
    pub width: u32,
    /// Rows, south to north.
    pub height: u32,
    /// `width * height` heights in metres, row 0 southern; NaN is a void.
    pub heights: Vec<f32>,
    /// Where post (0, 0) is and how far apart the posts are.
    pub georef: GeoRef,
}

impl RawGrid {
    /// A grid of `width x height` voids; the caller has checked the dimensions.
    pub fn voids(path: &Path, width: u32, height: u32, georef: GeoRef) -> Self {
        let count = width as usize * height as usize;
        debug_assert!(count as u64 <= MAX_FILE_POSTS);
        RawGrid { path: path.to_path_buf(), width, height, heights: vec![f32::NAN; count], georef }
    }

    /// Number of samples that are voids.
    pub fn void_count(&self) -> u64 {
        self.heights.iter().filter(|h| h.is_nan()).count() as u64
    }

    /// Index of post `(i, j)` in `heights`.
    pub fn index(&self, i: u32, j: u32) -> usize {
        debug_assert!(i < self.width && j < self.height);
        j as usize * self.width as usize + i as usize
    }

    /// Checks the invariant (in debug builds): sizes agree, no infinities.
    pub fn debug_check(&self) {
        debug_assert_eq!(self.heights.len(), self.width as usize * self.height as usize);
        debug_assert!(self.heights.iter().all(|h| h.is_finite() || h.is_nan()));
        debug_assert!(self.georef.spacing.iter().all(|s| s.is_finite() && *s > 0.0));
    }
}

/// Refuses zero or absurd dimensions before anything is allocated, and
/// returns them as `u32`.
pub fn check_dimensions(path: &Path, width: u64, height: u64) -> Result<(u32, u32), ImportError> {
    let absurd =
        || ImportError::new(path, Problem::AbsurdDimensions { width, height, max: MAX_FILE_POSTS });
    if width == 0 || height == 0 || width.saturating_mul(height) > MAX_FILE_POSTS {
        return Err(absurd());
    }
    Ok((u32::try_from(width).map_err(|_| absurd())?, u32::try_from(height).map_err(|_| absurd())?))
}

/// The length of the file in bytes.
pub fn file_len(path: &Path) -> Result<u64, ImportError> {
    let meta = std::fs::metadata(path).map_err(|e| ImportError::new(path, e.into()))?;
    Ok(meta.len())
}

/// Reads the whole file, refusing files longer than `max_len` (no format can
/// need more, so a longer file is not what it claims to be).
pub fn read_bounded(path: &Path, max_len: u64) -> Result<Vec<u8>, ImportError> {
    let len = file_len(path)?;
    if len > max_len {
        return Err(ImportError::new(
            path,
            Problem::SizeMismatch { expected: max_len, actual: len },
        ));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    let file = std::fs::File::open(path).map_err(|e| ImportError::new(path, e.into()))?;
    file.take(max_len).read_to_end(&mut bytes).map_err(|e| ImportError::new(path, e.into()))?;
    Ok(bytes)
}

/// Reads up to `n` bytes from the start of the file (fewer if it is shorter).
pub fn read_prefix(path: &Path, n: u64) -> Result<Vec<u8>, ImportError> {
    let file = std::fs::File::open(path).map_err(|e| ImportError::new(path, e.into()))?;
    let mut bytes = Vec::new();
    file.take(n).read_to_end(&mut bytes).map_err(|e| ImportError::new(path, e.into()))?;
    Ok(bytes)
}

/// A declared nodata value, compared the way the file stores its samples.
#[derive(Clone, Copy, Debug)]
pub struct NoData(pub f64);

impl NoData {
    fn matches(self, value: f64) -> bool {
        value == self.0 || (value.is_nan() && self.0.is_nan())
    }
}

/// Turns one decoded sample into a stored height: NaN for a void (the value is
/// the declared nodata), the value as `f32` if it is finite and fits, and
/// `None` for anything else (NaN, infinity or out of `f32` range that is not
/// the nodata), which the caller reports with the sample's position.
pub fn classify(value: f64, nodata: Option<NoData>) -> Option<f32> {
    if nodata.is_some_and(|nd| nd.matches(value)) {
        return Some(f32::NAN);
    }
    let height = value as f32;
    height.is_finite().then_some(height)
}

/// The error for a sample [`classify`] refused, at `row`/`column` of the file.
pub fn non_finite(path: &Path, row: u64, column: u64, value: f64) -> ImportError {
    ImportError::new(path, Problem::NonFinite { row, column, value })
}
