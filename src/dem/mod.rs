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
//! | [`netcdf`] | netCDF-3 classic grids (ETOPO5); `netcdf_header`: where a variable's values start |
//! | [`swath`] | decoding an opened file swath by swath into any slice (the formats use it) |
//! | [`mod@open`] | opening a file of any format (its header) and decoding one whole |
//! | [`raw`] | the pre-fill grid with voids and the checks importers share |
//! | [`mosaic`] | joining several files on one lattice |
//! | [`voids`] | the documented void fill |
//! | [`sea`] | heights below sea level raised to it (`import --sea-surface`) |
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
mod netcdf_header;
pub mod open;
pub mod raw;
pub mod sea;
pub mod swath;
pub mod voids;

pub use error::{ImportError, Problem};
pub use format::Format;
pub use raw::RawGrid;

/// A regular grid of heights in metres with its georeference.
///
/// `heights[j * width + i]` is sample `(i, j)`; row 0 is the southern row
/// (see [`crate::geo`] for the conventions). Every height is finite or NaN:
/// small voids have been interpolated (and counted in `voids_filled`), NaN
/// marks a post of a large void, which has no data (see [`voids`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ElevationGrid {
    /// Posts per row, west to east.
    pub width: u32,
    /// Rows, south to north.
    pub height: u32,
    /// `width * height` heights in metres, row 0 southern; NaN: no data.
    pub heights: Vec<f32>,
    /// Where post (0, 0) is and how far apart the posts are.
    pub georef: GeoRef,
    /// Samples that were voids in the sources and were interpolated.
    pub voids_filled: u64,
}

/// A grid's heights wherever they are (on the heap or in a
/// [`crate::spill::Spill`]), with the rest of an [`ElevationGrid`]: what
/// the pyramid builders read.
#[derive(Clone, Copy, Debug)]
pub struct GridView<'a> {
    /// Posts per row, west to east.
    pub width: u32,
    /// Rows, south to north.
    pub height: u32,
    /// `width * height` heights in metres, row 0 southern; NaN: no data.
    pub heights: &'a [f32],
    /// Where post (0, 0) is and how far apart the posts are.
    pub georef: GeoRef,
    /// Samples that were voids in the sources and were interpolated.
    pub voids_filled: u64,
}

impl ElevationGrid {
    /// The grid as a [`GridView`].
    pub fn view(&self) -> GridView<'_> {
        GridView {
            width: self.width,
            height: self.height,
            heights: &self.heights,
            georef: self.georef,
            voids_filled: self.voids_filled,
        }
    }

    /// The height of sample `(i, j)`.
    pub fn at(&self, i: u32, j: u32) -> f32 {
        debug_assert!(i < self.width && j < self.height);
        self.heights[(j as usize) * (self.width as usize) + i as usize]
    }
}

/// Reads one file of any supported format onto the heap, voids still
/// marked (at most [`raw::MAX_SAMPLES`] posts; [`swath`] decodes larger
/// ones into spills).
pub fn read_raw(path: &Path) -> Result<RawGrid, ImportError> {
    open::read_whole(open::open(path)?)
}

/// Imports one file and fills its small voids (large ones stay NaN, see
/// [`voids`]); a global grid gets its closing column ([`close_global`]).
pub fn import_file(path: &Path) -> Result<ElevationGrid, ImportError> {
    voids::fill_small(read_raw(path)?).map(close_global)
}

/// A geographic grid whose columns span 360 degrees less one spacing (the
/// way global grids are stored, 0 to 359.92 degrees for ETOPO5) gets a
/// copy of its first column as its last, 360 degrees on: the cells across
/// the seam then exist, and the grid wraps with no seam at 0 or 360
/// degrees. Other grids are returned as they are.
pub fn close_global(grid: ElevationGrid) -> ElevationGrid {
    if !grid.georef.lacks_closing_column(grid.width) {
        return grid;
    }
    let width = grid.width as usize;
    let mut heights = Vec::with_capacity((width + 1) * grid.height as usize);
    for row in grid.heights.chunks(width) {
        heights.extend_from_slice(row);
        heights.push(row[0]);
    }
    ElevationGrid { width: grid.width + 1, heights, ..grid }
}

/// Imports several files (any mix of formats) of one lattice as one mosaic
/// and fills its small voids, including small gaps between files. See
/// [`mosaic`] for the rules.
pub fn import_files(paths: &[PathBuf]) -> Result<ElevationGrid, ImportError> {
    if paths.is_empty() {
        return Err(ImportError::new(Path::new(""), Problem::NoInput));
    }
    let grids = paths.iter().map(|p| read_raw(p)).collect::<Result<Vec<_>, _>>()?;
    voids::fill_small(mosaic::mosaic(grids)?).map(close_global)
}

/// Imports files of different resolutions as layers for
/// [`crate::pyramid::build_layers`]: files of one spacing form one layer
/// (a mosaic, see [`mosaic`]), small voids are filled per layer. All files
/// must share one coordinate system; the error names the first file that
/// does not. Layers come back in the order their first file was given.
pub fn import_layers(paths: &[PathBuf]) -> Result<Vec<ElevationGrid>, ImportError> {
    if paths.is_empty() {
        return Err(ImportError::new(Path::new(""), Problem::NoInput));
    }
    let mut groups: Vec<Vec<RawGrid>> = Vec::new();
    for path in paths {
        let grid = read_raw(path)?;
        if let Some(first) = groups.first().and_then(|g| g.first()) {
            check_same_crs(&first.path, &first.georef, path, &grid.georef)?;
        }
        let same_spacing = |g: &Vec<RawGrid>| same_spacing(&g[0].georef, &grid.georef);
        match groups.iter_mut().find(|g| same_spacing(g)) {
            Some(group) => group.push(grid),
            None => groups.push(vec![grid]),
        }
    }
    groups.into_iter().map(|g| voids::fill_small(mosaic::mosaic(g)?).map(close_global)).collect()
}

/// Refuses the file at `path` when its coordinate system differs from the
/// first file's (`first`): the layers of an import must share one.
pub fn check_same_crs(
    first: &Path,
    first_georef: &GeoRef,
    path: &Path,
    georef: &GeoRef,
) -> Result<(), ImportError> {
    if first_georef.crs == georef.crs {
        return Ok(());
    }
    let why = format!(
        "its coordinate system {:?} differs from {:?} of {}; layers must share one \
         (reproject one of them)",
        georef.crs,
        first_georef.crs,
        first.display()
    );
    Err(ImportError::new(path, Problem::Mosaic(why)))
}

/// Whether two files share a spacing (within [`mosaic::SPACING_TOLERANCE`]),
/// so they belong to one layer.
pub fn same_spacing(a: &GeoRef, b: &GeoRef) -> bool {
    (0..2).all(|k| (b.spacing[k] - a.spacing[k]).abs() / a.spacing[k] <= mosaic::SPACING_TOLERANCE)
}
