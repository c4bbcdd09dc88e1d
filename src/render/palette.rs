//! Colours and bands of the display, with where their defaults come from.
//!
//! Terrain-awareness colouring follows Garmin's published convention for
//! its terrain display and synthetic vision (G1000 Pilot's Guide for the
//! Cessna Nav III, 190-00498-07 Rev. A, Figure 6-115 "Terrain
//! Altitude/Color Correlation", and the same figure in the TERRAIN-SVS and
//! TAWS-B sections): terrain above the aircraft or within 100 ft below it
//! is red, terrain 100 to 1000 ft below it is yellow (amber here),
//! terrain further below keeps its elevation tint (Garmin draws it black
//! on the terrain page). Both bands are configurable (`--warning-above`,
//! `--caution-below`) because operators and phases of flight differ.
//! Earlier defaults (at the aircraft, 500 ft) matched neither Garmin's nor
//! Honeywell's published bands.

/// Terrain this many metres above the aircraft, or higher, is red:
/// -30.48 m, so terrain within 100 ft below the aircraft is red too.
pub const DEFAULT_WARNING_ABOVE_M: f32 = -30.48;
/// Terrain less than this many metres below the aircraft is amber
/// (1000 ft).
pub const DEFAULT_CAUTION_BELOW_M: f32 = 304.8;
/// Sun elevation and azimuth used for slope shading: from the north-west,
/// as cartographers light relief so that it reads as raised, not sunken.
pub const SUN_AZIMUTH_DEG: f64 = 315.0;
/// Sun elevation above the horizon, degrees.
pub const SUN_ELEVATION_DEG: f64 = 45.0;

/// Unit vector toward the sun in the local frame (x east, y north, z up).
pub fn sun_direction() -> glam::Vec3 {
    let az = SUN_AZIMUTH_DEG.to_radians();
    let el = SUN_ELEVATION_DEG.to_radians();
    glam::DVec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin()).as_vec3()
}

/// Colour drawn where there is no terrain in the sky half (clear colour
/// above the horizon) and the ground-coloured haze below it.
pub const SKY_ZENITH: [f32; 3] = [0.16, 0.36, 0.68];
/// Sky colour at the horizon: the bottom of the sky gradient, the colour distant
/// terrain fades into and the clear colour.
pub const SKY_HORIZON: [f32; 3] = [0.62, 0.76, 0.90];

/// The "no data" hatching's dark colour (its stripes are twice as bright):
/// drawn by the sky pass below the horizon wherever no terrain covers the
/// sky, and by the terrain pass on curtains (`tiles::curtain`).
pub const NO_DATA_HATCH: [f32; 3] = [0.22, 0.22, 0.24];
