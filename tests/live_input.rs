//! Live input on localhost, as `ridgeline fly --input` receives it: a
//! scripted flight (a climbing turn over the built-in terrain,
//! `testkit::live`) played in real time as FlightGear packets (versions 24
//! and 25), X-Plane `RPOS` and GDL 90 (ownship and geometric altitude at
//! 1 Hz with Stratux's or ForeFlight's AHRS), read every frame at 30 Hz
//! the way the display does (a snapshot that never waits, then the view
//! at the frame's time). Each frame's pose must match the script at the
//! sample's time plus the extrapolation the display made (its age, at
//! most 0.5 s): within 1 m and 0.01° for FlightGear and X-Plane, within
//! GDL 90's quantisation for GDL 90.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use ridgeline::input::pose::MAX_EXTRAPOLATION_S;
use ridgeline::input::receiver::ReceiverOptions;
use ridgeline::input::{InputSpec, LiveInput, LiveView};
use testkit::live::{pose_error, SCRIPT};

const STALE: Duration = Duration::from_millis(1000);

/// One datagram of the script: when it is sent (script seconds), what it
/// carries, its bytes.
struct Datagram {
    t: f64,
    position: bool,
    attitude: bool,
    bytes: Vec<u8>,
}

/// How close each frame must come, metres and degrees; GDL 90's AHRS
/// without rates also lags by the turn over the sample's age.
struct Tolerance {
    horizontal_m: f64,
    vertical_m: f64,
    attitude_deg: f64,
    attitude_lag_dps: f64,
}

const EXACT: Tolerance =
    Tolerance { horizontal_m: 1.0, vertical_m: 1.0, attitude_deg: 0.01, attitude_lag_dps: 0.0 };

/// GDL 90: latitude and longitude in 180/2^23 degree steps (±1.2 m), the
/// track in 360/256 degree steps and speed in knots over up to 0.5 s of
/// extrapolation (±0.6 m), 5 ft of geometric altitude (±0.8 m) and
/// 64 ft/min of vertical speed, attitude in 0.1 degree steps (±0.05°).
const GDL90: Tolerance =
    Tolerance { horizontal_m: 3.0, vertical_m: 1.5, attitude_deg: 0.06, attitude_lag_dps: 0.0 };

/// Plays `datagrams` to a receiver for `kind` and checks a frame every
/// 1/30 s; returns the frames checked and the worst errors.
fn play(
    kind: &str,
    datagrams: Vec<Datagram>,
    seconds: f64,
    tolerance: &Tolerance,
) -> (u32, [f64; 3]) {
    let spec: InputSpec = format!("{kind}:127.0.0.1:0").parse().unwrap();
    let options = ReceiverOptions { stale: STALE, ..ReceiverOptions::default() };
    let mut input = LiveInput::start(&spec, &options).expect("listening");
    let to = input.local_addr();
    let start = Instant::now() + Duration::from_millis(50);
    let times: Vec<(f64, bool, bool)> =
        datagrams.iter().map(|d| (d.t, d.position, d.attitude)).collect();
    let sent = datagrams.len() as u64;
    let sender = std::thread::spawn(move || {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        for d in datagrams {
            let due = start + Duration::from_secs_f64(d.t);
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
            socket.send_to(&d.bytes, to).unwrap();
        }
    });
    let (mut frames, mut worst) = (0, [0.0f64; 3]);
    let mut next = start + Duration::from_millis(200);
    while next < start + Duration::from_secs_f64(seconds) {
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        next += Duration::from_secs_f64(1.0 / 30.0);
        let state = input.snapshot();
        let now = Instant::now();
        let LiveView::Live { pose, .. } = state.view(now, STALE) else {
            panic!(
                "{kind}: frame {frames} is stale with data flowing: {:?}",
                state.view(now, STALE)
            );
        };
        // The samples taken so far are the first `taken` datagrams (none is
        // lost on the loopback: checked below).
        let taken = &times[..state.taken as usize];
        let t_position = taken.iter().rev().find(|d| d.1).expect("a position").0;
        let t_attitude = taken.iter().rev().find(|d| d.2).expect("an attitude").0;
        let (position_at, attitude_at) = state.received();
        let age = |at: Option<Instant>| {
            now.duration_since(at.unwrap()).as_secs_f64().min(MAX_EXTRAPOLATION_S)
        };
        let (age_p, age_a) = (age(position_at), age(attitude_at));
        let expected_position = SCRIPT.pose(t_position + age_p);
        let expected_attitude = SCRIPT.pose(t_attitude + age_a);
        let (horizontal, vertical, _) = pose_error(&expected_position, &pose);
        let (_, _, attitude) = pose_error(&expected_attitude, &pose);
        let attitude_limit = tolerance.attitude_deg + tolerance.attitude_lag_dps * age_a;
        assert!(
            horizontal <= tolerance.horizontal_m && vertical <= tolerance.vertical_m && attitude <= attitude_limit,
            "{kind}, frame {frames}: off the script by {horizontal:.3} m, {vertical:.3} m up, {attitude:.4}° \
             (samples {age_p:.3} s and {age_a:.3} s old)"
        );
        worst = [worst[0].max(horizontal), worst[1].max(vertical), worst[2].max(attitude)];
        frames += 1;
    }
    sender.join().unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    while input.counts().datagrams() < sent && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(5));
    }
    let counts = input.counts();
    assert_eq!((counts.taken, counts.ignored_total()), (sent, 0), "{kind}: every datagram taken");
    println!(
        "{kind}: {frames} frames, worst {:.3} m, {:.3} m up, {:.4}°; {counts:?}",
        worst[0], worst[1], worst[2]
    );
    (frames, worst)
}

/// Datagrams at `hz` for `seconds`, each a whole sample.
fn stream(hz: f64, seconds: f64, encode: impl Fn(f64) -> Vec<u8>) -> Vec<Datagram> {
    (0..(seconds * hz) as usize)
        .map(|k| k as f64 / hz)
        .map(|t| Datagram { t, position: true, attitude: true, bytes: encode(t) })
        .collect()
}

#[test]
fn flightgear_v24_and_v25_follow_the_script() {
    for version in [24, 25] {
        let (frames, _) =
            play("flightgear", stream(60.0, 3.0, |t| SCRIPT.flightgear(version, t)), 3.0, &EXACT);
        assert!(frames >= 60, "{frames} frames checked");
    }
}

#[test]
fn x_plane_rpos_follows_the_script() {
    let (frames, _) = play("xplane", stream(60.0, 3.0, |t| SCRIPT.rpos(t)), 3.0, &EXACT);
    assert!(frames >= 60);
}

/// GDL 90 as a Stratux sends it: ownship and geometric altitude once a
/// second, AHRS (with its turn rate) at 20 Hz. Between ownship reports
/// the position is extrapolated for 0.5 s and then held.
#[test]
fn gdl90_ownship_and_stratux_ahrs_follow_the_script() {
    let (frames, _) =
        play("gdl90", gdl90_schedule(20.0, |t| SCRIPT.gdl90_stratux_ahrs(t)), 3.5, &GDL90);
    assert!(frames >= 70);
}

/// ForeFlight's AHRS has no rates: between its 5 Hz reports the attitude
/// holds, lagging the turn by its rate times the report's age.
#[test]
fn gdl90_ownship_and_foreflight_ahrs_follow_the_script() {
    let tolerance = Tolerance { attitude_lag_dps: SCRIPT.turn_dps, ..GDL90 };
    let (frames, _) =
        play("gdl90", gdl90_schedule(5.0, |t| SCRIPT.gdl90_foreflight_ahrs(t)), 3.5, &tolerance);
    assert!(frames >= 70);
}

/// Ownship reports at 0, 1, 2, 3 s and AHRS reports at `hz` in between,
/// the first AHRS a moment after the first ownship.
fn gdl90_schedule(hz: f64, ahrs: impl Fn(f64) -> Vec<u8>) -> Vec<Datagram> {
    let mut datagrams: Vec<Datagram> = (0..4)
        .map(|k| k as f64)
        .map(|t| Datagram { t, position: true, attitude: false, bytes: SCRIPT.gdl90_ownship(t) })
        .collect();
    datagrams.extend((0..(3.5 * hz) as usize).map(|k| 0.01 + k as f64 / hz).map(|t| Datagram {
        t,
        position: false,
        attitude: true,
        bytes: ahrs(t),
    }));
    datagrams.sort_by(|a, b| a.t.total_cmp(&b.t));
    datagrams
}

/// X-Plane's `DATA` groups 17 and 20 carry no velocity or rates: the pose
/// is the sample's, held (no flight path marker can be drawn).
#[test]
fn x_plane_data_groups_give_a_held_pose() {
    let spec: InputSpec = "xplane:127.0.0.1:0".parse().unwrap();
    let mut input = LiveInput::start(&spec, &ReceiverOptions::default()).unwrap();
    let (track, turning) = SCRIPT.sample(0.0);
    let packet = ridgeline::input::xplane::encode_data(&track.position, &turning.attitude);
    UdpSocket::bind("127.0.0.1:0").unwrap().send_to(&packet, input.local_addr()).unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    while input.counts().taken == 0 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(2));
    }
    let state = input.snapshot();
    let later = Instant::now() + Duration::from_millis(300);
    let LiveView::Live { pose, velocity_ned, .. } = state.view(later, STALE) else {
        panic!("stale")
    };
    assert_eq!(velocity_ned, None);
    let (horizontal, vertical, attitude) = pose_error(&SCRIPT.pose(0.0), &pose);
    assert!(
        horizontal < 1.0 && vertical < 0.01 && attitude < 1e-4,
        "{horizontal} {vertical} {attitude}"
    );
}
