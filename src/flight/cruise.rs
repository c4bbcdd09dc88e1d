//! The built-in cruise (`--flight cruise`): the case where LOD decides
//! everything. Level flight at [`CRUISE_ALTITUDE_M`] (10 km, where the sea's
//! horizon is 357 km away) across the middle of a dataset, nose
//! [`LOOK_DOWN_DEG`] below the horizontal, a gentle right turn (heading
//! [`START_HEADING_DEG`] to [`START_HEADING_DEG`] + [`TURN_DEG`]) at
//! [`GROUND_SPEED`] for [`CRUISE_SECONDS`]. Over terrain higher than the
//! altitude allows (a peak within [`MIN_CLEARANCE_M`]) the whole flight is
//! raised: it stays level.

use glam::DVec2;

use super::path::{FlightPath, Waypoint};
use super::pose::{normalize_heading, Pose};

/// Cruise altitude, metres above mean sea level.
pub const CRUISE_ALTITUDE_M: f64 = 10_000.0;
/// Metres per second (about 490 knots).
pub const GROUND_SPEED: f64 = 250.0;
/// Seconds flown.
pub const CRUISE_SECONDS: f64 = 120.0;
/// Seconds between waypoints.
pub const ROW_INTERVAL_S: f64 = 5.0;
/// Heading at the start, degrees.
pub const START_HEADING_DEG: f64 = 45.0;
/// Degrees turned right over the flight.
pub const TURN_DEG: f64 = 20.0;
/// Nose below the horizontal, degrees.
pub const LOOK_DOWN_DEG: f64 = 4.0;
/// Bank of the turn, degrees (coordinated at the turn rate and speed above: about 1).
const BANK_DEG: f64 = 1.0;
/// Least clearance over the terrain sampled along the track, metres.
pub const MIN_CLEARANCE_M: f64 = 1_000.0;
/// Terrain samples per leg between waypoints (a 1250 m leg: every 156 m).
const LEG_SAMPLES: u32 = 8;

/// The built-in cruise over the rectangle `extent_m` metres wide whose
/// south-west corner is at local `origin_m`, centred on its middle;
/// `height_at` is the terrain (non-finite or `None` heights are ignored).
pub fn builtin_cruise(
    origin_m: [f64; 2],
    extent_m: [f64; 2],
    height_at: &dyn Fn(f64, f64) -> Option<f32>,
) -> FlightPath {
    let centre = DVec2::from(origin_m) + DVec2::from(extent_m) * 0.5;
    let rows = (CRUISE_SECONDS / ROW_INTERVAL_S).round() as usize + 1;
    let heading_at = |t: f64| START_HEADING_DEG + TURN_DEG * t / CRUISE_SECONDS;
    // Integrate the track from the start; centre it on the rectangle's middle.
    let mut track = vec![DVec2::ZERO];
    for k in 1..rows {
        let t = (k as f64 - 0.5) * ROW_INTERVAL_S;
        let h = heading_at(t).to_radians();
        let step = DVec2::new(h.sin(), h.cos()) * GROUND_SPEED * ROW_INTERVAL_S;
        track.push(track[k - 1] + step);
    }
    let middle = (track[0] + track[rows - 1]) * 0.5;
    let positions: Vec<DVec2> = track.iter().map(|p| *p - middle + centre).collect();
    let highest = positions
        .windows(2)
        .flat_map(|leg| {
            (0..=LEG_SAMPLES).map(move |i| leg[0].lerp(leg[1], i as f64 / LEG_SAMPLES as f64))
        })
        .filter_map(|p| height_at(p.x, p.y).map(f64::from).filter(|h| h.is_finite()))
        .fold(f64::NEG_INFINITY, f64::max);
    let altitude = CRUISE_ALTITUDE_M.max((highest + MIN_CLEARANCE_M).ceil());
    let waypoints = positions
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let t = k as f64 * ROW_INTERVAL_S;
            Waypoint {
                t,
                pose: Pose {
                    position: p.map(|c| (c * 10.0).round() / 10.0).extend(altitude),
                    heading_deg: normalize_heading(heading_at(t)),
                    pitch_deg: -LOOK_DOWN_DEG,
                    roll_deg: BANK_DEG,
                },
            }
        })
        .collect();
    FlightPath::new(waypoints).expect("the built-in cruise keeps every value inside the path rules")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cruise_is_level_at_ten_km_in_the_middle() {
        let extent = [4e7, 4e7];
        let path = builtin_cruise([0.0, 0.0], extent, &|_, _| Some(1000.0));
        let (start, end) = (path.sample(path.start_time()), path.sample(path.end_time()));
        assert_eq!(start.position.z, CRUISE_ALTITUDE_M);
        assert_eq!(end.position.z, CRUISE_ALTITUDE_M);
        let flown = start.position.truncate().distance(end.position.truncate());
        assert!((flown - GROUND_SPEED * CRUISE_SECONDS).abs() < 1000.0, "{flown}");
        let middle = (start.position + end.position).truncate() * 0.5;
        assert!(middle.distance(DVec2::splat(2e7)) < 1000.0, "{middle}");
        let high = builtin_cruise([0.0, 0.0], extent, &|_, _| Some(9_500.0));
        assert_eq!(high.sample(0.0).position.z, 10_500.0);
    }
}
