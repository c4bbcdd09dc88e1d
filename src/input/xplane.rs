//! X-Plane's UDP output: the `RPOS` position stream and `DATA` groups 17
//! (pitch, roll, headings) and 20 (latitude, longitude, altitude).
//!
//! Layouts from X-Plane's "Exchanging Data with X-Plane" (in the
//! simulator's `Instructions` folder) as XPPython3's UDP notes correct them
//! for X-Plane 11.55 and 12 (the fifth header byte is `'4'` in practice,
//! not the documented NUL; either is taken). Little-endian throughout.
//!
//! `RPOS` (69 bytes; X-Plane sends it after an `RPOS\0` + rate-as-text
//! request to its port 49000, from the port it should answer to):
//!
//! | offset | field | type | unit |
//! |---|---|---|---|
//! | 0 | `RPOS` + one byte | | |
//! | 5, 13, 21 | dat_lon, dat_lat, dat_ele (MSL) | f64 | degrees, degrees, metres |
//! | 29 | y_agl_mtr | f32 | metres |
//! | 33, 37, 41 | veh_the_loc, veh_psi_loc, veh_phi_loc (pitch, true heading, roll) | f32 | degrees |
//! | 45, 49, 53 | vx_wrl, vy_wrl, vz_wrl (east, up, south) | f32 | m/s |
//! | 57, 61, 65 | Prad, Qrad, Rrad (body roll, pitch, yaw rates) | f32 | rad/s |
//!
//! `DATA` (set up in X-Plane's Data Output screen, "Network via UDP"):
//! `DATA` + one byte, then records of 36 bytes, an i32 group index and
//! eight f32 values. Group 17: pitch, roll, true heading, magnetic heading
//! (degrees). Group 20: latitude, longitude (degrees), altitude (feet MSL),
//! altitude AGL (feet), ... `DATA` carries no velocity: without it no
//! flight path marker is drawn and the position holds between samples.

use super::pose::{euler_rates, Attitude, Position, Track, Turning};
use super::update::{Bytes, Ignored, Update};

/// An `RPOS` packet, bytes.
pub const RPOS_BYTES: usize = 69;
/// One `DATA` record, bytes.
pub const DATA_RECORD_BYTES: usize = 36;
const HEADER_BYTES: usize = 5;
const FEET: f64 = 0.3048;

/// Decodes one `RPOS` or `DATA` datagram (each stands alone: X-Plane
/// sends every selected `DATA` group in one datagram).
pub fn decode(datagram: &[u8]) -> Result<Update, Ignored> {
    match datagram.get(..4) {
        Some(b"RPOS") => decode_rpos(datagram),
        Some(b"DATA") => decode_data(datagram),
        _ if datagram.len() < HEADER_BYTES => Err(Ignored::Length),
        _ => Err(Ignored::Header),
    }
}

fn decode_rpos(datagram: &[u8]) -> Result<Update, Ignored> {
    if datagram.len() != RPOS_BYTES {
        return Err(Ignored::Length);
    }
    let b = Bytes::little(datagram);
    let position = Position { lon_deg: b.f64(5), lat_deg: b.f64(13), alt_m: b.f64(21) };
    let attitude = Attitude {
        pitch_deg: b.f32(33),
        heading_deg: crate::flight::pose::normalize_heading(b.f32(37)),
        roll_deg: b.f32(41),
    };
    let (east, up, south) = (b.f32(45), b.f32(49), b.f32(53));
    let rates = euler_rates(&attitude, b.f32(57), b.f32(61), b.f32(65));
    Ok(Update {
        track: Some(Track {
            position,
            velocity_ned: Some([-south, east, -up]),
            vertical_known: true,
        }),
        turning: Some(Turning { attitude, rates_dps: Some(rates) }),
        ..Update::default()
    })
}

fn decode_data(datagram: &[u8]) -> Result<Update, Ignored> {
    let records = &datagram[HEADER_BYTES.min(datagram.len())..];
    if records.is_empty() || records.len() % DATA_RECORD_BYTES != 0 {
        return Err(Ignored::Length);
    }
    let mut update = Update::default();
    for record in records.chunks_exact(DATA_RECORD_BYTES) {
        let b = Bytes::little(record);
        let value = |k: usize| b.f32(4 + 4 * k);
        match b.i32(0) {
            17 => {
                let attitude = Attitude {
                    pitch_deg: value(0),
                    roll_deg: value(1),
                    heading_deg: crate::flight::pose::normalize_heading(value(2)),
                };
                update.turning = Some(Turning { attitude, rates_dps: None });
            }
            20 => {
                let position =
                    Position { lat_deg: value(0), lon_deg: value(1), alt_m: value(2) * FEET };
                update.track = Some(Track { position, velocity_ned: None, vertical_known: false });
            }
            _ => {}
        }
    }
    if update.is_empty() {
        return Err(Ignored::Unused);
    }
    Ok(update)
}

/// An `RPOS` packet of `track` and `turning` with body rates
/// `body_rates` (p, q, r about the body axes, radians a second), as
/// X-Plane writes it: for tests and bridges.
pub fn encode_rpos(track: &Track, turning: &Turning, body_rates: [f64; 3]) -> Vec<u8> {
    let mut packet = Vec::with_capacity(RPOS_BYTES);
    packet.extend_from_slice(b"RPOS4");
    let p = &track.position;
    for v in [p.lon_deg, p.lat_deg, p.alt_m] {
        packet.extend_from_slice(&v.to_le_bytes());
    }
    let a = &turning.attitude;
    let [north, east, down] = track.velocity_ned.unwrap_or_default();
    let [p_rate, q_rate, r_rate] = body_rates;
    for v in [30.0, a.pitch_deg, a.heading_deg, a.roll_deg, east, -down, -north] {
        packet.extend_from_slice(&(v as f32).to_le_bytes());
    }
    for v in [p_rate, q_rate, r_rate] {
        packet.extend_from_slice(&(v as f32).to_le_bytes());
    }
    debug_assert_eq!(packet.len(), RPOS_BYTES);
    packet
}

/// A `DATA` packet with groups 17 and 20 of `position` and `attitude`.
pub fn encode_data(position: &Position, attitude: &Attitude) -> Vec<u8> {
    let mut packet = b"DATA*".to_vec();
    let groups: [(i32, [f64; 8]); 2] = [
        (
            17,
            [
                attitude.pitch_deg,
                attitude.roll_deg,
                attitude.heading_deg,
                0.0,
                -999.0,
                -999.0,
                -999.0,
                -999.0,
            ],
        ),
        (20, [position.lat_deg, position.lon_deg, position.alt_m / FEET, 0.0, 0.0, 0.0, 0.0, 0.0]),
    ];
    for (index, values) in groups {
        packet.extend_from_slice(&index.to_le_bytes());
        for v in values {
            packet.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
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
        let attitude = Attitude { heading_deg: 348.5, pitch_deg: -2.5, roll_deg: 0.0 };
        (track, Turning { attitude, rates_dps: None })
    }

    #[test]
    fn rpos_round_trips_with_x_plane_axes() {
        let (track, turning) = sample();
        let packet = encode_rpos(&track, &turning, [0.0, 0.0, 0.05]);
        assert_eq!(packet.len(), RPOS_BYTES);
        let update = decode(&packet).expect("decoded");
        let got = update.track.unwrap();
        assert_eq!(got.position, track.position, "doubles are exact");
        let v = got.velocity_ned.unwrap();
        assert!(
            (v[0] - 60.0).abs() < 1e-5 && (v[1] + 12.0).abs() < 1e-5 && (v[2] - 3.0).abs() < 1e-5
        );
        let t = update.turning.unwrap();
        assert!((t.attitude.heading_deg - 348.5).abs() < 1e-4);
        // Wings level, a body yaw rate turns the heading at r / cos(pitch).
        let expected = 0.05f64.to_degrees() / 2.5f64.to_radians().cos();
        assert!((t.rates_dps.unwrap()[0] - expected).abs() < 1e-4, "{:?}", t.rates_dps);
    }

    #[test]
    fn data_groups_17_and_20_are_read() {
        let (track, turning) = sample();
        let update = decode(&encode_data(&track.position, &turning.attitude)).expect("decoded");
        let p = update.track.unwrap().position;
        assert!((p.lat_deg - 39.61).abs() < 1e-5 && (p.alt_m - 2750.5).abs() < 1e-3, "{p:?}");
        assert!(update.track.unwrap().velocity_ned.is_none());
        assert!((update.turning.unwrap().attitude.pitch_deg + 2.5).abs() < 1e-6);
    }

    #[test]
    fn bad_packets_are_refused_by_reason() {
        let (track, turning) = sample();
        let rpos = encode_rpos(&track, &turning, [0.0; 3]);
        assert_eq!(decode(&rpos[..68]), Err(Ignored::Length));
        assert_eq!(decode(b"RPO"), Err(Ignored::Length));
        assert_eq!(decode(b"XPOS4xxxxxxxx"), Err(Ignored::Header));
        let mut data = encode_data(&track.position, &turning.attitude);
        data.pop();
        assert_eq!(decode(&data), Err(Ignored::Length));
        let mut other = b"DATA*".to_vec();
        other.extend_from_slice(&3i32.to_le_bytes());
        other.extend_from_slice(&[0; 32]);
        assert_eq!(decode(&other), Err(Ignored::Unused));
        assert_eq!(decode(b"DATA*"), Err(Ignored::Length));
    }
}
