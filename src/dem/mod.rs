//! Elevation data as it comes in: importers for GeoTIFF, SRTM `.hgt`, DTED and
//! ESRI ASCII grids, mosaicking several files into one grid, and void filling.
//! Everything here is GL-free and produces an [`ElevationGrid`].
//!
//! | module | owns |
//! |---|---|
//! | [`format`](mod@format) | choosing the importer by extension or magic |
//! | [`geotiff`], [`geotiff_georef`] | GeoTIFF rasters through the `tiff` crate |
//! | [`hgt`] | SRTM `.hgt` tiles |
//! | [`dted`] | DTED levels 0, 1, 2 |
//! | [`ascii_grid`] | ESRI ASCII grids |
//! | [`netcdf`] | netCDF-3 classic grids (ETOPO5) |
//! | [`raw`] | the pre-fill grid with voids and the checks importers share |
//! | [`mosaic`] | joining several files on one lattice |
//! | [`voids`] | the documented void fill |
//! | [`error`] | [`ImportError`]: the file and the problem |

use std::path::{Path, PathBuf};

use crate::geo::GeoRef;

pub mod ascii_grid;
pub mod dted;
pub mod error;
pub mod format;
pub mod geotiff;
pub mod geotiff_georef;
pub mod hgt;
pub mod mosaic;
pub mod netcdf;
pub mod raw;
pub mod voids;

pub use error::{ImportError, Problem};
pub use format::Format;
pub use raw::RawGrid;

/// A regular grid of heights in metres with its georeference.
///
/// `heights[j * width + i]` is sample `(i, j)`; row 0 is the southern row
/// (see [`crate::geo`] for the conventions). Every height is finite: voids
/// have been filled (and counted in `voids_filled`) before a grid exists.
#[derive(Clone, Debug, PartialEq)]
pub struct ElevationGrid {
    /// Posts per row, west to east.
    pub width: u32,
    /// Rows, south to north.
    pub height: u32,
    /// `width * height` heights in metres, row 0 southern.
    pub heights: Vec<f32>,
    /// Where post (0, 0) is and how far apart the posts are.
    pub georef: GeoRef,
    /// Samples that were voids in the sources and were filled.
    pub voids_filled: u64,
}

impl ElevationGrid {
    /// The height of sample `(i, j)`.
    pub fn at(&self, i: u32, j: u32) -> f32 {
        debug_assert!(i < self.width && j < self.height);
        self.heights[(j as usize) * (self.width as usize) + i as usize]
    }
}

/// Reads one file of any supported format, voids still marked.
pub fn read_raw(path: &Path) -> Result<RawGrid, ImportError> {
    match format::detect(path)? {
        Format::GeoTiff => geotiff::read(path),
        Format::Hgt => hgt::read(path),
        Format::Dted => dted::read(path),
        Format::AsciiGrid => ascii_grid::read(path),
        Format::NetCdf => netcdf::read(path),
    }
}

/// Imports one file and fills its voids.
pub fn import_file(path: &Path) -> Result<ElevationGrid, ImportError> {
    voids::fill(read_raw(path)?)
}

/// Imports several files (any mix of formats) as one mosaic and fills its
/// voids, including the gaps between files. See [`mosaic`] for the rules.
pub fn import_files(paths: &[PathBuf]) -> Result<ElevationGrid, ImportError> {
    if paths.is_empty() {
        return Err(ImportError::new(Path::new(""), Problem::NoInput));
    }
    let grids = paths.iter().map(|p| read_raw(p)).collect::<Result<Vec<_>, _>>()?;
    voids::fill(mosaic::mosaic(grids)?)
}
