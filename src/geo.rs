//! Georeference of an elevation grid: where its samples sit on the earth and
//! how that maps to the local metric frame the rest of Ridgeline works in.
//!
//! Conventions used everywhere in the crate:
//! - samples are *posts* (point values); a raster whose cells are areas
//!   (GeoTIFF PixelIsArea) is converted so that `origin` names the centre of
//!   the south-west sample;
//! - row 0 is the **southern** row and column 0 the western column, so sample
//!   `(i, j)` lies `i` spacings east and `j` spacings north of the origin;
//! - the local frame has x east and y north in metres, with the origin at the
//!   south-west sample, and heights in metres above mean sea level.

/// The coordinate system of `origin` and `spacing`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Crs {
    /// Longitude and latitude in degrees (WGS 84 / EPSG:4326).
    Geographic,
    /// A planar system in metres (for example UTM), EPSG code where known.
    Projected { epsg: Option<u32> },
    /// No georeference: the grid is planar with spacing in metres.
    Local,
}

/// Where sample `(0, 0)` is and how far apart samples are.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GeoRef {
    pub crs: Crs,
    /// Centre of the south-west sample: (x or longitude, y or latitude).
    pub origin: [f64; 2],
    /// Distance between neighbouring samples east and north, both positive,
    /// in the units of `crs` (degrees or metres).
    pub spacing: [f64; 2],
}

impl GeoRef {
    /// A local planar grid with `spacing` metres between samples.
    pub fn local(spacing: [f64; 2]) -> Self {
        GeoRef { crs: Crs::Local, origin: [0.0, 0.0], spacing }
    }
}
