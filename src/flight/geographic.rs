//! Longitude and latitude to the chart of a dataset stored in geographic
//! coordinates (`Crs::Geographic`), and back.
//!
//! The chart is the grid's post lattice in metres: post `(i, j)` is at
//! `(i * spacing_m[0], j * spacing_m[1])`, the spacings those of
//! [`crate::geo::metres_per_degree`] at the dataset's centre latitude
//! `lat_c`, so the chart is the equirectangular projection there:
//!
//! ```text
//! x = (lon - lon0) * E(lat_c)     (east;  E = N(phi) cos(phi) per degree)
//! y = (lat - lat0) * N(lat_c)     (north; N = M(phi) per degree)
//! ```
//!
//! where `(lon0, lat0)` is the centre of the south-west sample
//! (`GeoRef::origin`) and `lon` is taken in the turn that holds the grid
//! ([`crate::earth::GridPlacement::post_of_geodetic`]: from the west edge
//! for a grid that wraps, nearest the centre otherwise). The node
//! pyramid's `spacing_m` comes from the same function, so a latitude and
//! longitude typed by a user lands on the post the data hold there. The
//! chart is not a metric frame: where on the earth a chart point is, and
//! how far apart two are, is the placement's business
//! ([`crate::earth::GridPlacement`]).

use glam::DVec2;

use crate::earth::GridPlacement;
use crate::geo::GeoRef;

/// A latitude and longitude in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatLon {
    /// Latitude, degrees north.
    pub lat: f64,
    /// Longitude, degrees east.
    pub lon: f64,
}

/// The chart of one geographic dataset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equirectangular {
    placement: GridPlacement,
}

impl Equirectangular {
    /// The chart of a grid whose `origin` and `spacing` are in degrees
    /// (`georef.crs` should be `Crs::Geographic`) with `extent_samples`
    /// samples east and north.
    pub fn new(georef: &GeoRef, extent_samples: [u32; 2]) -> Self {
        debug_assert_eq!(
            georef.crs,
            crate::geo::Crs::Geographic,
            "origin and spacing must be degrees"
        );
        let spacing_m = georef.spacing_m(extent_samples);
        Equirectangular { placement: GridPlacement::new(georef, extent_samples, spacing_m) }
    }

    /// The placement the chart belongs to.
    pub fn placement(&self) -> &GridPlacement {
        &self.placement
    }

    /// Chart metres (east, north of the south-west sample) of a point.
    pub fn to_local(&self, lat: f64, lon: f64) -> DVec2 {
        DVec2::from(self.placement.chart_of_geodetic(lat.to_radians(), lon.to_radians()))
    }

    /// The inverse of [`Self::to_local`]; longitude comes back in [-180, 180)
    /// (the chart's own turn before normalising).
    pub fn to_geographic(&self, local: DVec2) -> LatLon {
        let (lat, lon) = self.placement.geodetic_of_chart(local.to_array());
        LatLon { lat: lat.to_degrees(), lon: crate::earth::normalize_longitude(lon.to_degrees()) }
    }
}

/// Chart metres of `(lat, lon)` for a geographic grid of
/// `extent_samples` samples (east, north); see the module documentation.
pub fn geographic_to_local(georef: &GeoRef, extent_samples: [u32; 2], lat: f64, lon: f64) -> DVec2 {
    Equirectangular::new(georef, extent_samples).to_local(lat, lon)
}

/// Latitude and longitude of a chart point: the inverse of [`geographic_to_local`].
pub fn local_to_geographic(georef: &GeoRef, extent_samples: [u32; 2], local: DVec2) -> LatLon {
    Equirectangular::new(georef, extent_samples).to_geographic(local)
}
