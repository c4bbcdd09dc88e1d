//! The built-in approach `fly` flies when given no path: a descending, gently
//! turning run from the south-west corner region toward the middle of the
//! dataset, shaped to whatever terrain lies under it.
//!
//! The route, for a dataset `w` metres wide (east) and `h` metres tall (north):
//! - ground track: the quadratic Bézier curve from `(0.10 w, 0.10 h)` through
//!   the control point `(0.18 w, 0.62 h)` to the centre `(0.50 w, 0.50 h)`: it
//!   sets off a little east of north and turns right by about 100 degrees
//!   (square dataset) to end heading east-south-east into the middle;
//! - speed: constant along the track, [`APPROACH_SECONDS`] to fly the whole
//!   curve but at most [`MAX_GROUND_SPEED`]; on a large dataset the approach
//!   therefore ends short of the centre, still heading toward it;
//! - waypoints every [`ROW_INTERVAL_S`] seconds;
//! - altitude: from [`START_ABOVE_HIGHEST_M`] above the highest terrain under
//!   the whole flown track, descending linearly toward [`END_ABOVE_TERRAIN_M`]
//!   above the terrain under the last waypoint, never less than
//!   [`MIN_CLEARANCE_M`] above the terrain sampled along the straight legs the
//!   interpolation actually flies between waypoints, never climbing (the
//!   descent is held off until the terrain ahead allows it) and never
//!   descending faster than [`MAX_DESCENT_RATIO`] times the nominal rate (so
//!   after a late obstacle the approach ends higher instead of diving);
//! - heading: along the track; pitch: the leg's flight-path angle plus
//!   [`LOOK_DOWN_DEG`] down (so a few degrees nose down), within
//!   [-[`MAX_PITCH_DOWN_DEG`], 0]; roll: the coordinated-turn bank
//!   `atan(v * turn rate / g)`, at most [`MAX_BANK_DEG`], faded in over the
//!   first and out over the last [`BANK_FADE_S`] seconds so the approach
//!   starts and ends wings level.
//!
//! Values are rounded (0.1 m up for altitudes, 0.1 m positions, 0.01 degrees)
//! so that [`builtin_approach_csv`] is readable, and it round-trips exactly.

use glam::DVec2;

use super::path::{FlightPath, Waypoint};
use super::pose::{heading_difference, normalize_heading, Pose};
use crate::geo::TERRAIN_RANGE_M;

/// Seconds to fly the whole ground track, unless [`MAX_GROUND_SPEED`] caps the speed.
pub const APPROACH_SECONDS: f64 = 75.0;
/// Seconds between waypoints.
pub const ROW_INTERVAL_S: f64 = 2.5;
/// Metres per second (about 490 knots).
pub const MAX_GROUND_SPEED: f64 = 250.0;
/// Metres above the highest terrain under the flown track at the first waypoint.
pub const START_ABOVE_HIGHEST_M: f64 = 1500.0;
/// Metres above the terrain under the last waypoint that the descent aims for.
pub const END_ABOVE_TERRAIN_M: f64 = 300.0;
/// Least clearance, metres, above the terrain along every leg between waypoints.
pub const MIN_CLEARANCE_M: f64 = 150.0;
/// Degrees the nose is pitched down below the leg's flight-path angle.
pub const LOOK_DOWN_DEG: f64 = 2.0;
/// Steepest nose-down pitch, degrees (pitch stays within [-this, 0]).
pub const MAX_PITCH_DOWN_DEG: f64 = 12.0;
/// Largest bank angle, degrees, of the coordinated turn.
pub const MAX_BANK_DEG: f64 = 25.0;
/// Seconds over which the bank fades in at the start and out at the end.
pub const BANK_FADE_S: f64 = 15.0;

/// Ground-track control points as fractions of the extent (east, north).
const TRACK: [[f64; 2]; 3] = [[0.10, 0.10], [0.18, 0.62], [0.50, 0.50]];
/// Straight pieces the track is measured with to find distances along it.
const TRACK_PIECES: usize = 1024;
/// Terrain samples per leg between waypoints (a 625 m leg: every 20 m).
const LEG_SAMPLES: usize = 32;
/// Extents are clamped into this so positions stay inside the accepted range.
const MAX_EXTENT_M: f64 = 2e7;
/// The steepest descent between waypoints, as a multiple of the nominal.
pub const MAX_DESCENT_RATIO: f64 = 2.0;
/// Standard gravity, for the bank of a coordinated turn.
const GRAVITY: f64 = 9.80665;

/// The built-in approach over a dataset `extent_m` metres (east, north) whose
/// terrain height at local `(x, y)` is `height_at(x, y)` (non-finite heights
/// are ignored). Deterministic: the same inputs give the same path.
pub fn builtin_approach(extent_m: [f64; 2], height_at: &dyn Fn(f64, f64) -> f32) -> FlightPath {
    builtin_approach_over([0.0, 0.0], extent_m, height_at)
}

/// [`builtin_approach`] over the rectangle `extent_m` metres wide whose
/// south-west corner is at local `origin_m`: a layered pyramid's finest
/// layer, where the best data are, inside a larger base.
pub fn builtin_approach_over(
    origin_m: [f64; 2],
    extent_m: [f64; 2],
    height_at: &dyn Fn(f64, f64) -> f32,
) -> FlightPath {
    let extent =
        DVec2::from(extent_m.map(|e| if e.is_finite() { e.clamp(0.0, MAX_EXTENT_M) } else { 0.0 }));
    let origin =
        DVec2::from(origin_m.map(|o| if o.is_finite() { o.clamp(0.0, MAX_EXTENT_M) } else { 0.0 }));
    let track = Track::new(origin, extent);
    let speed = (track.length / APPROACH_SECONDS).min(MAX_GROUND_SPEED);
    let rows = (APPROACH_SECONDS / ROW_INTERVAL_S).round() as usize + 1;
    let times: Vec<f64> = (0..rows).map(|k| k as f64 * ROW_INTERVAL_S).collect();
    let params: Vec<f64> = times.iter().map(|t| track.param_at_distance(speed * t)).collect();
    let positions: Vec<DVec2> =
        params.iter().map(|&u| track.point(u).map(|c| round_to(c, 0.1))).collect();
    let headings: Vec<f64> = params.iter().map(|&u| heading_of(track.tangent(u))).collect();
    let altitudes = altitudes(&times, &positions, height_at);
    let waypoints = (0..rows)
        .map(|k| Waypoint {
            t: times[k],
            pose: Pose {
                position: positions[k].extend(altitudes[k]),
                heading_deg: normalize_heading(round_to(headings[k], 0.01)),
                pitch_deg: round_to(pitch(k, &positions, &altitudes), 0.01),
                roll_deg: round_to(bank(k, &times, &headings, speed), 0.01),
            },
        })
        .collect();
    FlightPath::new(waypoints)
        .expect("the built-in approach keeps every value inside the path rules")
}

/// The flight `ridgeline fly` flies when given no path: the built-in approach
/// over `pyramid`'s finest layer, where the best data are, shaped to the
/// best data's heights (no data counts as 0 m).
pub fn default_flight(pyramid: &crate::pyramid::Pyramid) -> FlightPath {
    let height = |x: f64, y: f64| pyramid.exact_height(x, y).unwrap_or(0.0);
    let (origin, extent) = pyramid.finest_area_m();
    builtin_approach_over(origin, extent, &height)
}

/// [`builtin_approach`] as CSV text with a comment describing it, to copy and edit.
pub fn builtin_approach_csv(extent_m: [f64; 2], height_at: &dyn Fn(f64, f64) -> f32) -> String {
    let path = builtin_approach(extent_m, height_at);
    let comment = format!(
        "# Ridgeline built-in approach over a {:.0} m x {:.0} m dataset.\n\
         # t seconds; x, y metres east and north of the south-west sample; alt metres MSL;\n\
         # heading degrees clockwise from true north; pitch nose up; roll right wing down.\n",
        extent_m[0], extent_m[1]
    );
    comment + &path.to_csv()
}

/// The quadratic Bézier ground track with a table of distances along it.
struct Track {
    control: [DVec2; 3],
    /// `cumulative[i]`: distance from the start to parameter `i / TRACK_PIECES`.
    cumulative: Vec<f64>,
    length: f64,
}

impl Track {
    fn new(origin: DVec2, extent: DVec2) -> Self {
        let control = TRACK.map(|fraction| origin + DVec2::from(fraction) * extent);
        let mut track = Track { control, cumulative: vec![0.0], length: 0.0 };
        for i in 1..=TRACK_PIECES {
            let step = track.point(i as f64 / TRACK_PIECES as f64)
                - track.point((i - 1) as f64 / TRACK_PIECES as f64);
            track.length += step.length();
            track.cumulative.push(track.length);
        }
        track
    }

    fn point(&self, u: f64) -> DVec2 {
        let [p0, p1, p2] = self.control;
        p0 * (1.0 - u) * (1.0 - u) + p1 * 2.0 * u * (1.0 - u) + p2 * u * u
    }

    fn tangent(&self, u: f64) -> DVec2 {
        let [p0, p1, p2] = self.control;
        (p1 - p0) * 2.0 * (1.0 - u) + (p2 - p1) * 2.0 * u
    }

    /// The parameter at `distance` metres along the track (clamped to it).
    fn param_at_distance(&self, distance: f64) -> f64 {
        if self.length <= 0.0 {
            return 0.0;
        }
        let piece = self.cumulative.partition_point(|&d| d <= distance).clamp(1, TRACK_PIECES);
        let (before, after) = (self.cumulative[piece - 1], self.cumulative[piece]);
        let within = if after > before {
            ((distance - before) / (after - before)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (piece as f64 - 1.0 + within) / TRACK_PIECES as f64
    }
}

/// Heading in degrees of a direction in the local frame (clockwise from north).
fn heading_of(direction: DVec2) -> f64 {
    normalize_heading(direction.x.atan2(direction.y).to_degrees())
}

/// Altitudes for each waypoint: the nominal linear descent raised to the
/// clearance over both legs touching the waypoint, then shaped by [`shape_descent`].
fn altitudes(times: &[f64], positions: &[DVec2], height_at: &dyn Fn(f64, f64) -> f32) -> Vec<f64> {
    let terrain = |p: DVec2| {
        let h = height_at(p.x, p.y) as f64;
        // Absurd heights cannot push the path outside the accepted altitudes.
        h.is_finite().then(|| h.clamp(TERRAIN_RANGE_M[0], TERRAIN_RANGE_M[1]))
    };
    let leg_highest = highest_terrain_per_leg(positions, &terrain);
    let highest = leg_highest.iter().flatten().copied().max_by(f64::total_cmp).unwrap_or(0.0);
    let start = highest + START_ABOVE_HIGHEST_M;
    let end = terrain(positions[positions.len() - 1]).unwrap_or(highest) + END_ABOVE_TERRAIN_M;
    let duration = times[times.len() - 1];
    let raised: Vec<f64> = (0..times.len())
        .map(|k| {
            let nominal = start + (end - start) * times[k] / duration;
            let legs = [
                k.checked_sub(1).and_then(|i| leg_highest[i]),
                leg_highest.get(k).copied().flatten(),
            ];
            let floor = legs
                .into_iter()
                .flatten()
                .map(|h| h + MIN_CLEARANCE_M)
                .fold(f64::NEG_INFINITY, f64::max);
            nominal.max(floor)
        })
        .collect();
    let max_drop = MAX_DESCENT_RATIO * (start - end).max(0.0) / (times.len() - 1) as f64;
    // Rounding up keeps every clearance.
    shape_descent(raised, max_drop).iter().map(|a| (a * 10.0).ceil() / 10.0).collect()
}

/// The highest terrain sampled along each straight leg between waypoints
/// (`None` where every sample is a void).
fn highest_terrain_per_leg(
    positions: &[DVec2],
    terrain: &dyn Fn(DVec2) -> Option<f64>,
) -> Vec<Option<f64>> {
    let along = |leg: &[DVec2], i: usize| leg[0].lerp(leg[1], i as f64 / LEG_SAMPLES as f64);
    positions
        .windows(2)
        .map(|leg| (0..=LEG_SAMPLES).filter_map(|i| terrain(along(leg, i))).max_by(f64::total_cmp))
        .collect()
}

/// Makes `altitudes` never climb (the descent waits until the terrain ahead
/// allows it) and never drop more than `max_drop` per leg (past a late
/// obstacle the approach ends higher rather than diving). Both passes only
/// raise altitudes, so every clearance is kept.
fn shape_descent(mut altitudes: Vec<f64>, max_drop: f64) -> Vec<f64> {
    for k in (0..altitudes.len() - 1).rev() {
        altitudes[k] = altitudes[k].max(altitudes[k + 1]);
    }
    for k in 1..altitudes.len() {
        altitudes[k] = altitudes[k].max(altitudes[k - 1] - max_drop);
    }
    altitudes
}

/// Nose attitude at waypoint `k`: the flight-path angle of the leg it starts
/// (the last waypoint: the leg it ends) plus a look down at the terrain.
fn pitch(k: usize, positions: &[DVec2], altitudes: &[f64]) -> f64 {
    let leg = k.min(positions.len() - 2);
    let climb = altitudes[leg + 1] - altitudes[leg];
    let run = positions[leg].distance(positions[leg + 1]);
    let flight_path_angle = climb.atan2(run).to_degrees();
    (flight_path_angle - LOOK_DOWN_DEG).clamp(-MAX_PITCH_DOWN_DEG, 0.0)
}

/// Coordinated-turn bank at waypoint `k` from the turn rate around it.
fn bank(k: usize, times: &[f64], headings: &[f64], speed: f64) -> f64 {
    let (before, after) = (k.saturating_sub(1), (k + 1).min(times.len() - 1));
    let turn_rate = heading_difference(headings[before], headings[after]).to_radians()
        / (times[after] - times[before]);
    let bank = (speed * turn_rate / GRAVITY).atan().to_degrees().clamp(-MAX_BANK_DEG, MAX_BANK_DEG);
    let fade =
        (times[k] / BANK_FADE_S).min((times[times.len() - 1] - times[k]) / BANK_FADE_S).min(1.0);
    bank * fade
}

/// `value` rounded to the nearest multiple of `step` (a power of ten below one).
fn round_to(value: f64, step: f64) -> f64 {
    let per_unit = (1.0 / step).round();
    (value * per_unit).round() / per_unit
}
