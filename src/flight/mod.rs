//! Camera paths for `fly`: the `--path` CSV format, interpolation between its
//! rows, evenly spaced frame times for headless runs, the built-in flights
//! (the approach flown when no path is given, and the cruise), and the latitude/longitude mapping the CSV's
//! `lat,lon` form uses. GL-free.
//!
//! | module | owns |
//! |---|---|
//! | [`pose`] | [`Pose`]: one instant's position and attitude, blending two of them |
//! | [`path`] | [`FlightPath`]: waypoints at increasing times, sampling, frame times |
//! | [`columns`] | the path's quantities, their header names and accepted ranges |
//! | [`csv`] | reading and writing the CSV format, [`PathError`] |
//! | [`approach`] | the built-in approach |
//! | [`cruise`] | the built-in cruise at 10 km |
//! | [`edges`] | the built-in views along and past every data edge, and along a no-data outline |
//! | [`geographic`] | the equirectangular longitude/latitude to local metres mapping |

pub mod approach;
pub mod columns;
pub mod cruise;
pub mod csv;
pub mod edges;
pub mod geographic;
pub mod path;
pub mod pose;

pub use approach::{builtin_approach, builtin_approach_csv, builtin_approach_over, default_flight};
pub use columns::{Column, ValueProblem};
pub use cruise::builtin_cruise;
pub use csv::{PathError, PathProblem};
pub use edges::{builtin_edges, builtin_outline};
pub use geographic::{geographic_to_local, local_to_geographic, Equirectangular, LatLon};
pub use path::{FlightPath, InvalidPath, Waypoint};
pub use pose::Pose;
