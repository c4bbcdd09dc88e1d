//! Untrusted input: 10^5 random and mutated datagrams sent to the three
//! receivers over the loopback while a valid stream keeps each one live.
//! Every bad datagram is ignored and counted by its reason, none panics
//! (the receiver thread is alive and answering at the end), none is taken,
//! and the display's side keeps reading fresh, valid data throughout: a
//! frame only ever copies the newest state the thread published (it never
//! waits for it: `input::receiver`'s test holds the lock and shows it),
//! so the flood cannot reach the frame's time. Every mutation here is
//! invalid by construction: a random datagram (wrong header, length or
//! frame check), a truncated or extended packet, a flipped bit under the
//! version word, header or GDL 90 frame check, a NaN, a latitude beyond
//! 90°, a position that jumps 550 km.

use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use ridgeline::input::gdl90::{frame::frame, messages};
use ridgeline::input::receiver::ReceiverOptions;
use ridgeline::input::{Counts, Ignored, InputKind, InputSpec, LiveInput, LiveView};
use testkit::live::SCRIPT;

const FUZZED: usize = 100_000;
const BATCH: usize = 250;

/// A bad datagram for `kind`, and the valid one it was made from.
fn mutate(kind: InputKind, rng: &mut StdRng, t: f64) -> Vec<u8> {
    let valid = match kind {
        InputKind::Flightgear => SCRIPT.flightgear(24, t),
        InputKind::Xplane => SCRIPT.rpos(t),
        InputKind::Gdl90 => SCRIPT.gdl90_stratux_ahrs(t),
    };
    match rng.random_range(0..7) {
        0 => {
            let length = rng.random_range(0..1600);
            let mut random: Vec<u8> = (0..length).map(|_| rng.random()).collect();
            // Random bytes that would start a valid header are nudged off it.
            if let Some(first) = random.first_mut() {
                *first = first.wrapping_add(match kind {
                    InputKind::Gdl90 if *first == 0x7E => 1,
                    InputKind::Xplane if matches!(*first, b'R' | b'D') => 1,
                    _ => 0,
                });
            }
            if kind == InputKind::Flightgear && random.len() >= 4 {
                random[0] = 0xFF;
            }
            random
        }
        1 => {
            let mut cut = valid.clone();
            cut.truncate(rng.random_range(0..valid.len() - 1));
            cut
        }
        2 => {
            // Extra bytes: past the packet, or inside the GDL 90 frame.
            let mut long = valid.clone();
            let at = if kind == InputKind::Gdl90 { long.len() - 1 } else { long.len() };
            for _ in 0..rng.random_range(1..64) {
                long.insert(at, rng.random_range(0..0x7D));
            }
            long
        }
        3 => flip(kind, valid, rng),
        4 => with_value(kind, t, f64::NAN),
        5 => with_value(kind, t, 95.0),
        _ => with_value(kind, t, 5.0 + SCRIPT.start.lat_deg),
    }
}

/// One bit flipped where it must be noticed: FlightGear's version word,
/// X-Plane's header, anything inside a GDL 90 frame (the CRC catches
/// every one-bit error).
fn flip(kind: InputKind, mut packet: Vec<u8>, rng: &mut StdRng) -> Vec<u8> {
    let range = match kind {
        InputKind::Flightgear => 0..4,
        InputKind::Xplane => 0..4,
        InputKind::Gdl90 => 1..packet.len() - 1,
    };
    let at = rng.random_range(range);
    packet[at] ^= 1 << rng.random_range(0..8);
    packet
}

/// A well-formed datagram whose latitude is `lat` (a NaN, beyond 90°, or
/// 5° from the flight: a jump).
fn with_value(kind: InputKind, t: f64, lat: f64) -> Vec<u8> {
    let (mut track, turning) = SCRIPT.sample(t);
    track.position.lat_deg = lat;
    match kind {
        InputKind::Flightgear => ridgeline::input::flightgear::encode(25, &track, &turning),
        InputKind::Xplane => ridgeline::input::xplane::encode_rpos(&track, &turning, [0.0; 3]),
        InputKind::Gdl90 => {
            let p = track.position;
            let feet = p.alt_m / messages::FOOT;
            let lat = if lat.is_nan() { 95.0 } else { lat };
            frame(&messages::encode_ownship(lat, p.lon_deg, feet, 136.0, 60.0, 0.0))
        }
    }
}

/// Waits (bounded) until `input` has counted `n` datagrams.
fn caught_up(input: &LiveInput, n: u64) -> Counts {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let counts = input.counts();
        if counts.datagrams() >= n || Instant::now() > deadline {
            return counts;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
}

#[test]
fn a_hundred_thousand_bad_datagrams_are_all_ignored_and_counted() {
    let kinds = [InputKind::Flightgear, InputKind::Xplane, InputKind::Gdl90];
    let mut inputs: Vec<LiveInput> = kinds
        .iter()
        .map(|kind| {
            let spec: InputSpec = format!("{}:127.0.0.1:0", kind.name()).parse().unwrap();
            LiveInput::start(&spec, &ReceiverOptions::default()).unwrap()
        })
        .collect();
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut rng = StdRng::seed_from_u64(23);
    let mut valid = [0u64; 3];
    let mut fuzzed = [0u64; 3];
    let start = Instant::now();
    let mut live_frames = 0;
    for batch in 0..FUZZED / BATCH {
        let t = start.elapsed().as_secs_f64();
        for (k, input) in inputs.iter_mut().enumerate() {
            // A valid sample first (GDL 90: ownship and AHRS), so the state
            // stays fresh and a jump has a position to jump from.
            send_valid(&socket, kinds[k], input.local_addr(), t, &mut valid[k]);
            for _ in 0..BATCH / 3 + usize::from(k < BATCH % 3) {
                socket.send_to(&mutate(kinds[k], &mut rng, t), input.local_addr()).unwrap();
                fuzzed[k] += 1;
            }
        }
        for (k, input) in inputs.iter_mut().enumerate() {
            let counts = caught_up(input, valid[k] + fuzzed[k]);
            assert_eq!(
                counts.datagrams(),
                valid[k] + fuzzed[k],
                "{:?}, batch {batch}: all counted",
                kinds[k]
            );
            // The frame's side: a snapshot at once, live data.
            let state = input.snapshot();
            assert!(matches!(
                state.view(Instant::now(), Duration::from_secs(1)),
                LiveView::Live { .. }
            ));
            live_frames += 1;
        }
    }
    let total: u64 = fuzzed.iter().sum();
    assert_eq!(total, FUZZED as u64);
    for (k, input) in inputs.into_iter().enumerate() {
        let counts = input.counts();
        assert_eq!(
            counts.taken, valid[k],
            "{:?}: only the valid stream was taken: {counts:?}",
            kinds[k]
        );
        assert_eq!(counts.ignored_total(), fuzzed[k], "{:?}: every bad datagram ignored", kinds[k]);
        let reasons: Vec<String> = Ignored::ALL
            .iter()
            .filter(|&&r| counts.ignored_for(r) > 0)
            .map(|&r| format!("{} {}", r.name(), counts.ignored_for(r)))
            .collect();
        println!(
            "{}: {} valid taken, {} ignored ({})",
            kinds[k].name(),
            counts.taken,
            counts.ignored_total(),
            reasons.join(", ")
        );
        let malformed = if kinds[k] == InputKind::Gdl90 { Ignored::Crc } else { Ignored::Length };
        for reason in [malformed, Ignored::OutOfRange, Ignored::Jump] {
            assert!(
                counts.ignored_for(reason) > 0,
                "{:?}: no datagram ignored for {reason:?}",
                kinds[k]
            );
        }
        input.stop().expect("the receiver thread ended cleanly, no panic");
    }
    println!(
        "{total} bad datagrams in {:.1} s, {live_frames} frame reads all live",
        start.elapsed().as_secs_f64()
    );
}

fn send_valid(socket: &UdpSocket, kind: InputKind, to: SocketAddr, t: f64, count: &mut u64) {
    let datagrams = match kind {
        InputKind::Flightgear => vec![SCRIPT.flightgear(24, t)],
        InputKind::Xplane => vec![SCRIPT.rpos(t)],
        InputKind::Gdl90 => vec![SCRIPT.gdl90_ownship(t), SCRIPT.gdl90_stratux_ahrs(t)],
    };
    for datagram in datagrams {
        socket.send_to(&datagram, to).unwrap();
        *count += 1;
    }
}
