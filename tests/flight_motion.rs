//! Moving along a camera path: interpolation (heading along the shorter arc),
//! clamping, frame times, cameras from poses, and the built-in approach over
//! synthetic terrain.

use std::path::Path;

use glam::DVec3;
use proptest::prelude::*;
use ridgeline::flight::approach::{
    APPROACH_SECONDS, END_ABOVE_TERRAIN_M, MAX_BANK_DEG, MAX_DESCENT_RATIO, MAX_PITCH_DOWN_DEG,
    MIN_CLEARANCE_M, START_ABOVE_HIGHEST_M,
};
use ridgeline::flight::pose::heading_difference;
use ridgeline::flight::{
    builtin_approach, builtin_approach_csv, FlightPath, InvalidPath, Pose, Waypoint,
};
use ridgeline::geo::GeoRef;

fn waypoint(t: f64, position: [f64; 3], heading: f64, pitch: f64, roll: f64) -> Waypoint {
    Waypoint {
        t,
        pose: Pose {
            position: DVec3::from(position),
            heading_deg: heading,
            pitch_deg: pitch,
            roll_deg: roll,
        },
    }
}

fn two_rows(heading_from: f64, heading_to: f64) -> FlightPath {
    FlightPath::new(vec![
        waypoint(10.0, [0.0, 0.0, 1000.0], heading_from, -10.0, 20.0),
        waypoint(20.0, [1000.0, -500.0, 500.0], heading_to, 10.0, -20.0),
    ])
    .unwrap()
}

#[test]
fn positions_and_attitude_interpolate_linearly_and_clamp_outside_the_path() {
    let path = two_rows(10.0, 50.0);
    let quarter = path.sample(12.5);
    assert_eq!(quarter.position, DVec3::new(250.0, -125.0, 875.0));
    assert_eq!((quarter.heading_deg, quarter.pitch_deg, quarter.roll_deg), (20.0, -5.0, 10.0));
    assert_eq!(path.sample(20.0), path.waypoints()[1].pose);
    assert_eq!(path.sample(-1e9), path.waypoints()[0].pose, "before the start: the first pose");
    assert_eq!(
        path.sample(f64::INFINITY),
        path.waypoints()[1].pose,
        "after the end: the last pose"
    );
    assert_eq!(path.sample(f64::NAN), path.waypoints()[0].pose);
}

#[test]
fn heading_takes_the_shorter_arc_through_north() {
    let half = |from, to| two_rows(from, to).sample(15.0).heading_deg;
    assert_eq!(half(359.0, 1.0), 0.0);
    assert_eq!(half(1.0, 359.0), 0.0);
    assert_eq!(half(350.0, 30.0), 10.0);
    assert_eq!(half(-10.0, 10.0), 0.0, "negative headings are headings too");
    assert_eq!(half(720.0 - 361.0, 5.0), 2.0);
    assert!(
        (two_rows(359.0, 1.0).sample(14.0).heading_deg - 359.8).abs() < 1e-9,
        "heading comes back in [0, 360)"
    );
}

#[test]
fn sample_finds_the_right_leg_of_many() {
    let path = FlightPath::new(
        (0..10)
            .map(|k| waypoint(k as f64 * k as f64, [k as f64 * 100.0, 0.0, 1000.0], 0.0, 0.0, 0.0))
            .collect(),
    )
    .unwrap();
    for k in 0..9 {
        let (t0, t1) = ((k * k) as f64, ((k + 1) * (k + 1)) as f64);
        let x = path.sample((t0 + t1) / 2.0).position.x;
        assert!((x - (k as f64 * 100.0 + 50.0)).abs() < 1e-9, "leg {k}: {x}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn heading_stays_on_the_shorter_arc(from in -360.0..360.0f64, to in -360.0..360.0f64, t in 10.0..20.0f64) {
        let heading = two_rows(from, to).sample(t).heading_deg;
        prop_assert!((0.0..360.0).contains(&heading));
        let whole = heading_difference(from, to).abs();
        let split = heading_difference(from, heading).abs() + heading_difference(heading, to).abs();
        prop_assert!((split - whole).abs() < 1e-6, "{from} -> {heading} -> {to}");
    }
}

#[test]
fn frame_times_are_evenly_spaced_from_first_to_last() {
    let path = two_rows(0.0, 0.0);
    assert_eq!(path.frame_times(0).count(), 0);
    assert_eq!(path.frame_times(1).collect::<Vec<_>>(), vec![10.0]);
    assert_eq!(path.frame_times(2).collect::<Vec<_>>(), vec![10.0, 20.0]);
    assert_eq!(path.frame_times(5).collect::<Vec<_>>(), vec![10.0, 12.5, 15.0, 17.5, 20.0]);
    let odd = FlightPath::new(vec![
        waypoint(0.1, [0.0; 3], 0.0, 0.0, 0.0),
        waypoint(0.7, [0.0; 3], 0.0, 0.0, 0.0),
    ])
    .unwrap();
    assert_eq!(odd.frame_times(7).last(), Some(0.7), "the last frame is exactly the last row");
    let single = FlightPath::new(vec![waypoint(3.0, [0.0; 3], 0.0, 0.0, 0.0)]).unwrap();
    assert_eq!(single.frame_times(3).collect::<Vec<_>>(), vec![3.0; 3]);
}

#[test]
fn constructed_paths_obey_the_same_rules_as_files() {
    assert_eq!(FlightPath::new(vec![]), Err(InvalidPath::Empty));
    let nan =
        FlightPath::new(vec![waypoint(0.0, [0.0, f64::NAN, 0.0], 0.0, 0.0, 0.0)]).unwrap_err();
    assert!(nan.to_string().contains("`y`") && nan.to_string().contains("NaN"), "{nan}");
    let steep = FlightPath::new(vec![waypoint(0.0, [0.0; 3], 0.0, 91.0, 0.0)]).unwrap_err();
    assert!(steep.to_string().contains("`pitch`"), "{steep}");
    let back = FlightPath::new(vec![
        waypoint(1.0, [0.0; 3], 0.0, 0.0, 0.0),
        waypoint(1.0, [0.0; 3], 0.0, 0.0, 0.0),
    ]);
    assert!(matches!(back, Err(InvalidPath::TimeNotIncreasing { index: 1, .. })));
}

#[test]
fn a_pose_makes_a_valid_camera() {
    let pose = two_rows(10.0, 50.0).sample(15.0);
    let camera = pose.camera(60.0, [640, 480]);
    camera.validate().unwrap();
    assert_eq!(
        (camera.position, camera.heading_deg, camera.fov_x_deg, camera.viewport),
        (pose.position, 30.0, 60.0, [640, 480])
    );
}

/// Rolling terrain with a 2 900 m ridge across the middle of a 90 km x 70 km
/// dataset: slopes below 1 so that the test's samples, which fall between the
/// builder's, see at most a few metres of difference.
fn ridged(x: f64, y: f64) -> f32 {
    let rolling = 600.0 + 400.0 * (x / 3000.0).sin() * (y / 4000.0).cos();
    let ridge = 2300.0 * (-((x + y - 40_000.0) / 2500.0).powi(2)).exp();
    (rolling + ridge) as f32
}

const EXTENT: [f64; 2] = [90_000.0, 70_000.0];

/// Lowest clearance over terrain along the path, sampled every 0.05 s.
fn lowest_clearance(path: &FlightPath, height_at: &dyn Fn(f64, f64) -> f32) -> f64 {
    let frames = (path.duration() / 0.05) as u32 + 1;
    path.frame_times(frames)
        .map(|t| {
            let p = path.sample(t).position;
            p.z - height_at(p.x, p.y) as f64
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn builtin_approach_descends_and_turns_without_touching_the_terrain() {
    let path = builtin_approach(EXTENT, &ridged);
    let waypoints = path.waypoints();
    assert!((60.0..=90.0).contains(&path.duration()) && path.duration() == APPROACH_SECONDS);
    let clearance = lowest_clearance(&path, &ridged);
    assert!(clearance >= MIN_CLEARANCE_M - 20.0, "clearance {clearance}");
    assert!(
        waypoints.windows(2).all(|w| w[1].pose.position.z <= w[0].pose.position.z),
        "never climbs"
    );

    let (first, last) = (&waypoints[0].pose, &waypoints[waypoints.len() - 1].pose);
    assert!(
        first.position.z - last.position.z > 1000.0,
        "descends: {} -> {}",
        first.position.z,
        last.position.z
    );
    let centre = DVec3::new(EXTENT[0] / 2.0, EXTENT[1] / 2.0, 0.0);
    let to_centre = |p: DVec3| (p - centre).truncate().length();
    assert!(
        to_centre(last.position) < to_centre(first.position) - 10_000.0,
        "heads into the middle"
    );
    assert!(
        first.position.x < EXTENT[0] * 0.2 && first.position.y < EXTENT[1] * 0.2,
        "starts in the SW corner region"
    );

    assert!(heading_difference(first.heading_deg, last.heading_deg) > 10.0, "turns right");
    assert_eq!((first.roll_deg, last.roll_deg), (0.0, 0.0), "wings level at both ends");
    let max_bank = waypoints.iter().map(|w| w.pose.roll_deg).fold(0.0, f64::max);
    assert!(max_bank > 3.0 && max_bank <= MAX_BANK_DEG, "banks right into the turn: {max_bank}");
    for w in waypoints {
        assert!(
            (-MAX_PITCH_DOWN_DEG..=-1.0).contains(&w.pose.pitch_deg),
            "nose a few degrees down: {}",
            w.pose.pitch_deg
        );
    }
}

#[test]
fn builtin_approach_starts_above_the_highest_terrain_and_ends_low_over_flat_ground() {
    let flat = |_: f64, _: f64| 250.0f32;
    let path = builtin_approach([8000.0, 6000.0], &flat);
    let waypoints = path.waypoints();
    assert_eq!(waypoints[0].pose.position.z, 250.0 + START_ABOVE_HIGHEST_M);
    assert_eq!(waypoints[waypoints.len() - 1].pose.position.z, 250.0 + END_ABOVE_TERRAIN_M);
    let end = waypoints[waypoints.len() - 1].pose.position;
    assert!(
        (end.x - 4000.0).abs() < 1.0 && (end.y - 3000.0).abs() < 1.0,
        "a small dataset is crossed to its centre: {end}"
    );
}

#[test]
fn builtin_approach_holds_altitude_over_a_wall_near_the_end() {
    // A 4 000 m wall just before the centre of a small dataset, lower terrain everywhere else.
    let wall =
        |x: f64, y: f64| if (x - 3500.0).abs() < 300.0 && y > 2000.0 { 4000.0f32 } else { 100.0 };
    let path = builtin_approach([8000.0, 6000.0], &wall);
    let clearance = lowest_clearance(&path, &wall);
    assert!(clearance >= MIN_CLEARANCE_M - 1e-9, "clearance {clearance}");
    let altitudes: Vec<f64> = path.waypoints().iter().map(|w| w.pose.position.z).collect();
    let nominal_drop =
        (altitudes[0] - (100.0 + END_ABOVE_TERRAIN_M)) / (altitudes.len() - 1) as f64;
    for leg in altitudes.windows(2) {
        let drop = leg[0] - leg[1];
        assert!(
            (0.0..=MAX_DESCENT_RATIO * nominal_drop + 0.1).contains(&drop),
            "{drop} m in one leg: {altitudes:?}"
        );
    }
}

#[test]
fn builtin_approach_is_deterministic_and_its_csv_reads_back_identically() {
    let path = builtin_approach(EXTENT, &ridged);
    assert_eq!(builtin_approach(EXTENT, &ridged), path);
    let text = builtin_approach_csv(EXTENT, &ridged);
    assert!(text.starts_with("# Ridgeline built-in approach"));
    let parsed = FlightPath::parse_csv(
        Path::new("builtin.csv"),
        &text,
        &GeoRef::local([30.0, 30.0]),
        [3001, 2334],
    )
    .unwrap();
    assert_eq!(parsed, path);
    assert!(text.lines().nth(4).unwrap().len() < 60, "rounded numbers keep rows short: {text}");
}

#[test]
fn builtin_approach_survives_voids_and_absurd_extents() {
    let voids = |x: f64, _: f64| if x < 20_000.0 { f32::NAN } else { 500.0 };
    let path = builtin_approach(EXTENT, &voids);
    assert!(lowest_clearance(&path, &|x, y| if voids(x, y).is_nan() { 0.0 } else { 500.0 }) > 0.0);
    let absurd = |_: f64, _: f64| 1e30f32;
    for extent in [[0.0, 0.0], [f64::INFINITY, f64::NAN], [1e300, -5.0], [1.0, 1e9]] {
        let path = builtin_approach(extent, &absurd);
        assert!(path.waypoints().iter().all(|w| w.pose.position.is_finite()), "{extent:?}");
    }
}
