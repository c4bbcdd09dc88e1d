//! Elevation data as it comes in: importers for GeoTIFF, SRTM `.hgt`, DTED and
//! ESRI ASCII grids, mosaicking several files into one grid, and void filling.
//! Everything here is GL-free and produces an [`ElevationGrid`].

use crate::geo::GeoRef;

/// A regular grid of heights in metres with its georeference.
///
/// `heights[j * width + i]` is sample `(i, j)`; row 0 is the southern row
/// (see [`crate::geo`] for the conventions). Every height is finite: voids
/// have been filled (and counted in `voids_filled`) before a grid exists.
#[derive(Clone, Debug, PartialEq)]
pub struct ElevationGrid {
    pub width: u32,
    pub height: u32,
    pub heights: Vec<f32>,
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
