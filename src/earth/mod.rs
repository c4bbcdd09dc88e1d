//! The earth Ridgeline draws on: the WGS 84 ellipsoid, the projections
//! projected grids are placed with, and where a grid's posts are on it.
//! GL-free, f64 throughout.
//!
//! | module | owns |
//! |---|---|
//! | [`ellipsoid`] | geodetic latitude, longitude and height to ECEF and back (Vermeille), the geodetic normal, east-north-up frames, longitude normalisation |
//! | [`projection`] | transverse Mercator by Krüger's series (UTM, ETRS89 / UTM) and Web Mercator, by EPSG code |
//! | [`cache`] | [`PlaceCache`]: a projected grid's node series and tile samples, kept across frames |
//! | [`bounds`] | oriented boxes of grid patches on the ellipsoid, the ellipsoid's horizon (for culling and distances on the earth) |
//! | [`expansion`] | [`Expansion`]: a projected grid's posts about a node's centre as a short conformal series (what the shader places a projected grid's vertices with) |
//! | [`frame`] | [`EarthFrame`]: a frame's eye and each node's placement in f64, the f32 uniforms and small-term formula the vertex shader places vertices with |
//! | [`placement`] | [`GridPlacement`]: a grid's posts to latitude, longitude and ECEF and back, longitude that wraps, the chart |
//!
//! Heights are taken as heights above the ellipsoid. Elevation data give
//! heights above mean sea level (the geoid, up to 106 m away from the
//! ellipsoid); the camera's altitude is also above mean sea level, so both
//! are offset alike and the geoid's slow change (at most a few metres in
//! 100 km) is the only error left. A geoid model would add its undulation
//! to both.

pub mod bounds;
pub mod cache;
pub mod ellipsoid;
pub mod expansion;
pub mod frame;
pub mod placement;
pub mod projection;

pub use bounds::{EarthBox, EllipsoidHorizon};
pub use cache::{NodeSeries, PatchSamples, PlaceCache};
pub use ellipsoid::{geodetic_of, normalize_longitude, Geodetic};
pub use expansion::Expansion;
pub use frame::{EarthFrame, NodePlace};
pub use placement::{GridPlacement, ProjectedLattice};
pub use projection::{Projection, TransverseMercator, UnsupportedEpsg};
