//! FlightGear's native FDM packet (`FGNetFDM`), as FlightGear sends it with
//! `--native-fdm=socket,out,HZ,HOST,PORT,udp` and JSBSim with
//! `<output type="FLIGHTGEAR" protocol="UDP" ...>`.
//!
//! The layout is FlightGear's `src/Network/net_fdm.hxx` (version 24, 408
//! bytes; FlightGear 2020.2 and earlier, and again since the bump to 25 was
//! reverted) and JSBSim's `src/input_output/net_fdm.hxx` and
//! `FGOutputFG.cpp`, which split the struct in three to also send version
//! 25 (FlightGear 2020.3): 144 bytes of tank data (`FGNetFDM2`) inserted
//! after the first 304, 552 bytes in all. Every field is big-endian
//! (network order: `htonl`, and `htond` swaps a double's words and each
//! word's bytes). The fields read here sit in the common first part:
//!
//! | offset | field | type | unit |
//! |---|---|---|---|
//! | 0 | version | u32 | 24 or 25 |
//! | 8, 16, 24 | longitude, latitude, altitude | f64 | radians, radians, metres MSL |
//! | 36, 40, 44 | phi, theta, psi (roll, pitch, true heading) | f32 | radians |
//! | 56, 60, 64 | phidot, thetadot, psidot (Euler angle rates) | f32 | radians/s |
//! | 76, 80, 84 | v_north, v_east, v_down | f32 | feet/s |

use super::pose::{Attitude, Position, Track, Turning};
use super::update::{Bytes, Ignored, Update};

/// Version 24's packet, bytes.
pub const V24_BYTES: usize = 408;
/// Version 25's packet, bytes (version 24's plus `FGNetFDM2`).
pub const V25_BYTES: usize = 552;
const FEET: f64 = 0.3048;

/// Decodes one datagram: its length must be its version's.
pub fn decode(datagram: &[u8]) -> Result<Update, Ignored> {
    if datagram.len() < 4 {
        return Err(Ignored::Length);
    }
    let bytes = Bytes::big(datagram);
    let expected = match bytes.u32(0) {
        24 => V24_BYTES,
        25 => V25_BYTES,
        _ => return Err(Ignored::Version),
    };
    if datagram.len() != expected {
        return Err(Ignored::Length);
    }
    let position = Position {
        lon_deg: bytes.f64(8).to_degrees(),
        lat_deg: bytes.f64(16).to_degrees(),
        alt_m: bytes.f64(24),
    };
    let attitude = Attitude {
        roll_deg: bytes.f32(36).to_degrees(),
        pitch_deg: bytes.f32(40).to_degrees(),
        heading_deg: crate::flight::pose::normalize_heading(bytes.f32(44).to_degrees()),
    };
    let rates = [bytes.f32(64), bytes.f32(60), bytes.f32(56)].map(f64::to_degrees);
    let velocity = [bytes.f32(76), bytes.f32(80), bytes.f32(84)].map(|v| v * FEET);
    Ok(Update {
        track: Some(Track { position, velocity_ned: Some(velocity), vertical_known: true }),
        turning: Some(Turning { attitude, rates_dps: Some(rates) }),
        ..Update::default()
    })
}

/// A packet of `version` (24 or 25) carrying `track` and `turning`, as
/// FlightGear writes it (other fields zero): for simulators written in
/// Rust, and for tests.
pub fn encode(version: u32, track: &Track, turning: &Turning) -> Vec<u8> {
    let mut packet = vec![0u8; if version == 25 { V25_BYTES } else { V24_BYTES }];
    let mut put = |at: usize, bytes: &[u8]| packet[at..at + bytes.len()].copy_from_slice(bytes);
    put(0, &version.to_be_bytes());
    let p = &track.position;
    put(8, &p.lon_deg.to_radians().to_be_bytes());
    put(16, &p.lat_deg.to_radians().to_be_bytes());
    put(24, &p.alt_m.to_be_bytes());
    let a = &turning.attitude;
    let f32s = |v: f64| (v as f32).to_be_bytes();
    put(36, &f32s(a.roll_deg.to_radians()));
    put(40, &f32s(a.pitch_deg.to_radians()));
    put(44, &f32s(a.heading_deg.to_radians()));
    let [heading, pitch, roll] = turning.rates_dps.unwrap_or_default();
    put(56, &f32s(roll.to_radians()));
    put(60, &f32s(pitch.to_radians()));
    put(64, &f32s(heading.to_radians()));
    let [north, east, down] = track.velocity_ned.unwrap_or_default();
    put(72, &f32s(-down / FEET));
    put(76, &f32s(north / FEET));
    put(80, &f32s(east / FEET));
    put(84, &f32s(down / FEET));
    packet
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (Track, Turning) {
        let track = Track {
            position: Position { lat_deg: 39.61, lon_deg: 40.12, alt_m: 2750.5 },
            velocity_ned: Some([60.0, -12.0, 3.0]),
            vertical_known: true,
        };
        let turning = Turning {
            attitude: Attitude { heading_deg: 348.5, pitch_deg: -2.5, roll_deg: 15.0 },
            rates_dps: Some([2.0, -0.5, 1.0]),
        };
        (track, turning)
    }

    #[test]
    fn both_versions_round_trip() {
        let (track, turning) = sample();
        for version in [24, 25] {
            let update = decode(&encode(version, &track, &turning)).expect("decoded");
            let got = update.track.unwrap();
            assert!((got.position.lat_deg - 39.61).abs() < 1e-12);
            assert!((got.position.alt_m - 2750.5).abs() < 1e-9);
            let v = got.velocity_ned.unwrap();
            assert!((v[0] - 60.0).abs() < 1e-4 && (v[1] + 12.0).abs() < 1e-4, "{v:?}");
            let a = update.turning.unwrap();
            assert!((a.attitude.heading_deg - 348.5).abs() < 1e-4, "{a:?}");
            assert!((a.rates_dps.unwrap()[0] - 2.0).abs() < 1e-5);
        }
    }

    #[test]
    fn byte_order_is_network_order() {
        let (track, turning) = sample();
        let packet = encode(24, &track, &turning);
        assert_eq!(&packet[..4], &[0, 0, 0, 24]);
        // The latitude's sign and exponent come first.
        assert_eq!(packet[16], 0x3F, "{:02x?}", &packet[16..24]);
    }

    #[test]
    fn wrong_versions_and_lengths_are_refused() {
        let (track, turning) = sample();
        let mut packet = encode(24, &track, &turning);
        assert_eq!(decode(&packet[..407]), Err(Ignored::Length));
        assert_eq!(decode(&packet[..3]), Err(Ignored::Length));
        packet[3] = 23;
        assert_eq!(decode(&packet), Err(Ignored::Version));
        let mut long = encode(24, &track, &turning);
        long.push(0);
        assert_eq!(decode(&long), Err(Ignored::Length));
        // A version 25 word on a version 24 packet is the wrong length.
        let mut mixed = encode(24, &track, &turning);
        mixed[3] = 25;
        assert_eq!(decode(&mixed), Err(Ignored::Length));
    }
}
