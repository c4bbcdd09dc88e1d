//! Opening an elevation file of any supported format (its header only)
//! and decoding one whole onto the heap: the dispatch over the formats,
//! kept apart from [`super::swath`] so the formats do not import it.

use std::path::Path;

use super::error::{ImportError, Problem};
use super::format::{self, Format};
use super::mosaic::Footprint;
use super::raw::{RawGrid, MAX_SAMPLES};
use super::swath::{OpenedFile, SWATH_BYTES};
use super::{ascii_grid, dted, geotiff, hgt, netcdf};

/// Opens a file of any supported format: its header only.
pub fn open(path: &Path) -> Result<Box<dyn OpenedFile>, ImportError> {
    Ok(match format::detect(path)? {
        Format::GeoTiff => Box::new(geotiff::open(path)?),
        Format::Hgt => Box::new(hgt::open(path)?),
        Format::Dted => Box::new(dted::open(path)?),
        Format::AsciiGrid => Box::new(ascii_grid::open(path)?),
        Format::NetCdf => Box::new(netcdf::open(path)?),
    })
}

/// Decodes the whole of an opened file onto the heap, refusing one of
/// more than [`MAX_SAMPLES`] posts (the streaming import,
/// [`crate::pyramid::spilled`], takes those).
pub fn read_whole(opened: Box<dyn OpenedFile>) -> Result<RawGrid, ImportError> {
    let Footprint { path, georef, size: [width, height] } = opened.footprint().clone();
    let posts = u64::from(width) * u64::from(height);
    if posts > MAX_SAMPLES {
        let problem = Problem::TooLargeInMemory { posts, max: MAX_SAMPLES };
        return Err(ImportError::new(&path, problem));
    }
    let mut grid = RawGrid::voids(&path, width, height, georef);
    opened.read_into(&mut grid.heights, SWATH_BYTES, &mut || {})?;
    grid.debug_check();
    Ok(grid)
}
