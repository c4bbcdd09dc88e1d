//! The one mapping from longitude/latitude to the local metric frame for
//! datasets stored in geographic coordinates (`Crs::Geographic`).
//!
//! Ridgeline draws a geographic grid as if it were planar, with a fixed number
//! of metres per degree. The mapping is equirectangular about the dataset's
//! centre latitude `lat_c`:
//!
//! ```text
//! x = wrap(lon - lon0) * cos(lat_c) * M        (east)
//! y = (lat - lat0) * M                          (north)
//! M = pi / 180 * 6 371 008.8 m                  (metres per degree of the mean earth radius)
//! ```
//!
//! where `(lon0, lat0)` is the centre of the south-west sample (`GeoRef::origin`)
//! and `lat_c` the latitude halfway between the southern and northern rows.
//! The node pyramid's `spacing_m` MUST come from the same numbers, i.e.
//! `[cos(lat_c) * M * spacing_deg_east, M * spacing_deg_north]`
//! ([`Equirectangular::spacing_m`]), so that sample `(i, j)` lands at
//! `(i * spacing_m[0], j * spacing_m[1])` and a latitude/longitude typed by a
//! user lands on the same terrain the renderer draws there.
//!
//! The error of this flat approximation grows with the dataset's north-south
//! extent (x scale is exact only at `lat_c`), which is acceptable for the
//! tile-sized areas Ridgeline displays.

use glam::DVec2;

use crate::camera::EARTH_RADIUS_M;
use crate::geo::GeoRef;

/// Metres per degree of arc on a sphere of the mean earth radius.
pub const METRES_PER_DEGREE: f64 = std::f64::consts::PI / 180.0 * EARTH_RADIUS_M;

/// How far from a pole the centre latitude may be taken; closer, `cos(lat_c)`
/// would shrink toward zero and the inverse mapping would stop being finite.
const MAX_CENTRE_LATITUDE_DEG: f64 = 89.9;

/// A latitude and longitude in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatLon {
    pub lat: f64,
    pub lon: f64,
}

/// The equirectangular frame of one geographic dataset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equirectangular {
    /// Longitude and latitude of the centre of the south-west sample.
    origin_deg: DVec2,
    /// Metres per degree east (`cos(lat_c) * M`) and north (`M`); both > 0.
    metres_per_degree: DVec2,
}

impl Equirectangular {
    /// The frame of a grid whose `origin` and `spacing` are in degrees
    /// (`georef.crs` should be `Crs::Geographic`) with `extent_samples`
    /// samples east and north.
    pub fn new(georef: &GeoRef, extent_samples: [u32; 2]) -> Self {
        debug_assert_eq!(georef.crs, crate::geo::Crs::Geographic, "origin and spacing must be degrees");
        let rows_above_origin = extent_samples[1].saturating_sub(1) as f64;
        let centre_lat = georef.origin[1] + rows_above_origin * georef.spacing[1] / 2.0;
        let centre_lat = centre_lat.clamp(-MAX_CENTRE_LATITUDE_DEG, MAX_CENTRE_LATITUDE_DEG);
        let metres_per_degree = DVec2::new(centre_lat.to_radians().cos() * METRES_PER_DEGREE, METRES_PER_DEGREE);
        Equirectangular { origin_deg: DVec2::from(georef.origin), metres_per_degree }
    }

    /// Local metres (east, north of the south-west sample) of a point.
    pub fn to_local(&self, lat: f64, lon: f64) -> DVec2 {
        let delta_deg = DVec2::new(wrap_longitude(lon - self.origin_deg.x), lat - self.origin_deg.y);
        delta_deg * self.metres_per_degree
    }

    /// The inverse of [`Self::to_local`]; longitude comes back in [-180, 180]
    /// (rounding may give either end).
    pub fn to_geographic(&self, local: DVec2) -> LatLon {
        let deg = self.origin_deg + local / self.metres_per_degree;
        LatLon { lat: deg.y, lon: wrap_longitude(deg.x) }
    }

    /// Metres between samples `spacing_deg` apart (east, north): what the node
    /// pyramid must use as `spacing_m` for this grid.
    pub fn spacing_m(&self, spacing_deg: [f64; 2]) -> [f64; 2] {
        let metres = DVec2::from(spacing_deg) * self.metres_per_degree;
        [metres.x, metres.y]
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

/// `spacing_m` for a geographic grid, consistent with [`geographic_to_local`].
pub fn geographic_spacing_m(georef: &GeoRef, extent_samples: [u32; 2]) -> [f64; 2] {
    Equirectangular::new(georef, extent_samples).spacing_m(georef.spacing)
}

/// `degrees` brought into [-180, 180), so that a dataset next to the
/// antimeridian maps longitudes on both sides of it next to each other.
fn wrap_longitude(degrees: f64) -> f64 {
    (degrees + 180.0).rem_euclid(360.0) - 180.0
}
