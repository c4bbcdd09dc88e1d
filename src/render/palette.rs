//! Colours and bands of the display, with where their defaults come from.
//!
//! Terrain-awareness colouring follows the convention of Honeywell's EGPWS
//! terrain display and FAA TSO-C151 class A TAWS: terrain at or above the
//! aircraft is red, terrain less than 500 ft (152.4 m) below it is amber
//! (yellow on EGPWS), terrain further below keeps its elevation tint. Both
//! bands are configurable because operators and phases of flight differ
//! (TSO-C151 uses 700, 350 and 150 ft of required clearance en route, in the
//! terminal area and on approach).

/// Terrain this many metres above the aircraft, or higher, is red.
pub const DEFAULT_WARNING_ABOVE_M: f32 = 0.0;
/// Terrain less than this many metres below the aircraft is amber (500 ft).
pub const DEFAULT_CAUTION_BELOW_M: f32 = 152.4;
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
