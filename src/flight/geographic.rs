//! Longitude and latitude to the local metric frame for datasets stored in
//! geographic coordinates (`Crs::Geographic`), and back.
//!
//! Ridgeline draws a geographic grid as if it were planar: the mapping is
//! equirectangular about the dataset's centre latitude `lat_c`, with the
//! WGS 84 scales of [`crate::geo::metres_per_degree`] there:
//!
//! ```text
//! x = wrap(lon - lon0) * E(lat_c)     (east;  E = N(phi) cos(phi) per degree)
//! y = (lat - lat0) * N(lat_c)         (north; N = M(phi) per degree)
//! ```
//!
//! where `(lon0, lat0)` is the centre of the south-west sample (`GeoRef::origin`).
//! The node pyramid's `spacing_m` comes from the same function, so sample
//! `(i, j)` lands at `(i * spacing_m[0], j * spacing_m[1])` and a latitude and
//! longitude typed by a user lands on the terrain the renderer draws there.
//!
//! The error of this flat approximation grows with the dataset's north-south
//! extent (x scale is exact only at `lat_c`), which is acceptable for the
//! areas Ridgeline displays.

use glam::DVec2;

use crate::geo::{metres_per_degree, GeoRef};

/// A latitude and longitude in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatLon {
    /// Latitude, degrees north.
    pub lat: f64,
    /// Longitude, degrees east.
    pub lon: f64,
}

/// The equirectangular frame of one geographic dataset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equirectangular {
    /// Longitude and latitude of the centre of the south-west sample.
    origin_deg: DVec2,
    /// Metres per degree east and north at the centre latitude; both > 0.
    metres_per_degree: DVec2,
}

impl Equirectangular {
    /// The frame of a grid whose `origin` and `spacing` are in degrees
    /// (`georef.crs` should be `Crs::Geographic`) with `extent_samples`
    /// samples east and north.
    pub fn new(georef: &GeoRef, extent_samples: [u32; 2]) -> Self {
        debug_assert_eq!(
            georef.crs,
            crate::geo::Crs::Geographic,
            "origin and spacing must be degrees"
        );
        let metres_per_degree =
            DVec2::from(metres_per_degree(georef.centre_latitude(extent_samples)));
        Equirectangular { origin_deg: DVec2::from(georef.origin), metres_per_degree }
    }

    /// Local metres (east, north of the south-west sample) of a point.
    pub fn to_local(&self, lat: f64, lon: f64) -> DVec2 {
        let delta_deg =
            DVec2::new(wrap_longitude(lon - self.origin_deg.x), lat - self.origin_deg.y);
        delta_deg * self.metres_per_degree
    }

    /// The inverse of [`Self::to_local`]; longitude comes back in [-180, 180]
    /// (rounding may give either end).
    pub fn to_geographic(&self, local: DVec2) -> LatLon {
        let deg = self.origin_deg + local / self.metres_per_degree;
        LatLon { lat: deg.y, lon: wrap_longitude(deg.x) }
    }
}

/// Local metres of `(lat, lon)` in the frame of a geographic grid of
/// `extent_samples` samples (east, north); see the module documentation.
pub fn geographic_to_local(georef: &GeoRef, extent_samples: [u32; 2], lat: f64, lon: f64) -> DVec2 {
    Equirectangular::new(georef, extent_samples).to_local(lat, lon)
}

/// Latitude and longitude of a local position: the inverse of [`geographic_to_local`].
pub fn local_to_geographic(georef: &GeoRef, extent_samples: [u32; 2], local: DVec2) -> LatLon {
    Equirectangular::new(georef, extent_samples).to_geographic(local)
}

/// `degrees` brought into [-180, 180), so that a dataset next to the
/// antimeridian maps longitudes on both sides of it next to each other.
fn wrap_longitude(degrees: f64) -> f64 {
    (degrees + 180.0).rem_euclid(360.0) - 180.0
}
