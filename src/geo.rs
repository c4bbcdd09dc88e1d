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

/// Heights any terrain on the earth lies within, metres: the deepest
/// trench (11 km below sea level) to above the highest summit.
pub const TERRAIN_RANGE_M: [f64; 2] = [-11_000.0, 9_000.0];

/// The coordinate system of `origin` and `spacing`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Crs {
    /// Longitude and latitude in degrees (WGS 84 / EPSG:4326).
    Geographic,
    /// A planar system in metres (for example UTM), EPSG code where known.
    Projected {
        /// The EPSG code of the system, if the file names one.
        epsg: Option<u32>,
    },
    /// No georeference: the grid is planar with spacing in metres.
    Local,
}

/// Where sample `(0, 0)` is and how far apart samples are.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GeoRef {
    /// What `origin` and `spacing` are measured in.
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

/// WGS 84 semi-major axis, metres.
const WGS84_A: f64 = 6_378_137.0;
/// WGS 84 first eccentricity squared.
const WGS84_E2: f64 = 6.694_379_990_141_3e-3;

/// Metres per degree of longitude and of latitude at `latitude_deg` on the
/// WGS 84 ellipsoid: `N(phi) cos(phi)` and `M(phi)` per radian. The local frame
/// of a geographic grid is the equirectangular projection with these scales at
/// the grid's centre latitude; everything that turns degrees into local
/// metres (the pyramid's spacing, flight paths given in latitude and
/// longitude) goes through this one function.
pub fn metres_per_degree(latitude_deg: f64) -> [f64; 2] {
    let phi = latitude_deg.clamp(-90.0, 90.0).to_radians();
    let w = (1.0 - WGS84_E2 * phi.sin().powi(2)).sqrt();
    let prime_vertical = WGS84_A / w;
    let meridional = WGS84_A * (1.0 - WGS84_E2) / (w * w * w);
    let per_radian = std::f64::consts::PI / 180.0;
    [prime_vertical * phi.cos() * per_radian, meridional * per_radian]
}

/// The corners of a grid's posts in degrees (Geographic grids only).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BoundsDeg {
    /// Longitude of the western column of posts, degrees.
    pub west: f64,
    /// Latitude of the southern row of posts, degrees.
    pub south: f64,
    /// Longitude of the eastern column of posts, degrees.
    pub east: f64,
    /// Latitude of the northern row of posts, degrees.
    pub north: f64,
}

impl GeoRef {
    /// Metres between neighbouring samples, east and north, for a grid of
    /// `samples` posts.
    ///
    /// Planar systems are taken to be in metres already. Geographic grids use
    /// WGS 84 radii of curvature at the grid's centre latitude: north spacing
    /// `M(φ)·Δφ`, east spacing `N(φ)·cos φ·Δλ` (angles in radians). The local
    /// frame is thereby an equirectangular projection about the centre; over
    /// a 1° tile at 40° N the true east spacing differs by under 0.4 % at the
    /// tile's north and south edges.
    pub fn spacing_m(&self, samples: [u32; 2]) -> [f64; 2] {
        match self.crs {
            Crs::Geographic => {
                let per_degree = metres_per_degree(self.centre_latitude(samples));
                [per_degree[0] * self.spacing[0], per_degree[1] * self.spacing[1]]
            }
            Crs::Projected { .. } | Crs::Local => self.spacing,
        }
    }

    /// Latitude halfway between the southern and northern rows (degrees;
    /// meaningful for geographic grids only), kept 0.1 degree off the poles so
    /// that the east scale stays above zero.
    pub fn centre_latitude(&self, samples: [u32; 2]) -> f64 {
        let centre = self.origin[1] + self.spacing[1] * samples[1].saturating_sub(1) as f64 / 2.0;
        centre.clamp(-89.9, 89.9)
    }

    /// The outermost posts of a grid of `samples` posts, in degrees, where the
    /// grid is geographic; `None` for planar systems (no inverse projection).
    pub fn bounds_deg(&self, samples: [u32; 2]) -> Option<BoundsDeg> {
        match self.crs {
            Crs::Geographic => Some(BoundsDeg {
                west: self.origin[0],
                south: self.origin[1],
                east: self.origin[0] + self.spacing[0] * samples[0].saturating_sub(1) as f64,
                north: self.origin[1] + self.spacing[1] * samples[1].saturating_sub(1) as f64,
            }),
            Crs::Projected { .. } | Crs::Local => None,
        }
    }

    /// Whether a geographic grid of `width` posts a row spans the whole
    /// turn without its closing column: its last column is one spacing west
    /// of its first, 360 degrees on. Such a grid gets that column (a copy of
    /// the first) at import, so the cells across the seam are drawn and
    /// the grid wraps (see [`crate::earth::GridPlacement`]).
    pub fn lacks_closing_column(&self, width: u32) -> bool {
        self.crs == Crs::Geographic && ((width as f64 * self.spacing[0]) - 360.0).abs() < 1e-6
    }

    /// Why this georeference cannot describe a grid, if it cannot: spacing
    /// must be positive and finite, the origin finite, latitudes on the earth.
    pub fn problem(&self, samples: [u32; 2]) -> Option<String> {
        let finite = self.origin.iter().chain(&self.spacing).all(|v| v.is_finite());
        if !finite {
            return Some(format!("georeference is not finite: {self:?}"));
        }
        if self.spacing.iter().any(|&s| s <= 0.0) {
            return Some(format!("sample spacing must be positive: {:?}", self.spacing));
        }
        if let Some(b) = self.bounds_deg(samples) {
            if b.south < -90.0 || b.north > 90.0 {
                return Some(format!("latitudes {}..{} leave [-90, 90]", b.south, b.north));
            }
        }
        None
    }
}
