//! The GDL 90 messages a synthetic-vision display uses, decoded from and
//! encoded to their bytes (message ID first, FCS removed):
//!
//! - Heartbeat, ID 0 (ICD §3.1): status byte 1 bit 7, GPS position valid.
//! - Ownship Report, ID 10 (§3.4, fields §3.5.1): 28 bytes; latitude and
//!   longitude 24-bit signed semicircles (180/2^23 degrees), pressure
//!   altitude 12 bits of 25 ft offset by -1000 ft (0xFFF invalid),
//!   miscellaneous bits (bits 1-0: track/heading type), NIC and NACp,
//!   horizontal velocity 12 bits of 1 kt (0xFFF unavailable), vertical
//!   velocity 12 bits signed of 64 ft/min (0x800 unavailable),
//!   track/heading 8 bits of 360/256 degrees. No valid fix: latitude,
//!   longitude and NIC all zero.
//! - Ownship Geometric Altitude, ID 11 (§3.8): signed 16 bits of 5 ft,
//!   height above the WGS 84 ellipsoid (MSL where the ForeFlight ID
//!   message says so).
//! - ForeFlight ID, 0x65 sub-ID 0, and AHRS, 0x65 sub-ID 1 (ForeFlight's
//!   "GDL 90 Extended Specification"): ID capabilities bit 0 = geometric
//!   altitude is MSL; AHRS roll, pitch in 0.1° (0x7FFF invalid), heading
//!   in 0.1° with bit 15 set for magnetic (0xFFFF invalid), big-endian.
//! - Stratux AHRS, `0x4C 0x45 0x01 0x01` (Stratux `main/gps.go`,
//!   `makeAHRSGDL90Report`): 24 bytes, big-endian signed 16 bits: roll,
//!   pitch, heading, slip/skid, yaw rate (all 0.1 units), G, airspeed,
//!   pressure altitude (ft + 5000), vertical speed (ft/min); 0x7FFF invalid.

use crate::input::pose::Attitude;
use crate::input::update::{Bytes, Ignored};

/// Knots to metres a second.
pub const KNOT: f64 = 1852.0 / 3600.0;
/// Feet to metres.
pub const FOOT: f64 = 0.3048;
/// One unit of latitude or longitude, degrees.
pub const SEMICIRCLE_LSB_DEG: f64 = 180.0 / (1u32 << 23) as f64;
/// One unit of track, degrees.
pub const TRACK_LSB_DEG: f64 = 360.0 / 256.0;

/// The ownship report's fields a display uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ownship {
    /// Latitude and longitude, degrees; `None` when the fix is invalid.
    pub lat_lon_deg: Option<[f64; 2]>,
    /// Pressure altitude (29.92 inHg), feet; `None` when invalid.
    pub pressure_altitude_ft: Option<f64>,
    /// Ground speed, knots; `None` when unavailable.
    pub ground_speed_kt: Option<f64>,
    /// Vertical velocity, feet a minute; `None` when unavailable.
    pub vertical_fpm: Option<f64>,
    /// True track angle, degrees; `None` unless the report says the
    /// track/heading field is a true track.
    pub true_track_deg: Option<f64>,
    /// True heading, degrees, when the field says it is one.
    pub true_heading_deg: Option<f64>,
}

/// An AHRS report: attitude (heading `None` when invalid or magnetic) and
/// what else it gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ahrs {
    /// Roll and pitch, degrees.
    pub roll_pitch_deg: [f64; 2],
    /// True heading, degrees.
    pub heading_deg: Option<f64>,
    /// Turn (heading) rate, degrees a second.
    pub turn_rate_dps: Option<f64>,
    /// Barometric vertical speed, feet a minute.
    pub vertical_fpm: Option<f64>,
}

/// One decoded message.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Message {
    /// Heartbeat: whether the GPS position is valid.
    Heartbeat {
        /// Status byte 1, bit 7.
        gps_valid: bool,
    },
    /// Ownship report.
    Ownship(Ownship),
    /// Ownship geometric altitude, feet.
    GeoAltitude {
        /// Feet, above the WGS 84 ellipsoid (or MSL, see [`Message::ForeFlightId`]).
        feet: f64,
    },
    /// ForeFlight ID: whether the geometric altitude is MSL.
    ForeFlightId {
        /// Capabilities bit 0.
        geo_altitude_msl: bool,
    },
    /// An AHRS report whose roll and pitch are valid.
    Ahrs(Ahrs),
    /// An AHRS report flagging its attitude invalid.
    AhrsInvalid,
    /// A message a display has no use for (traffic, uplink, status).
    Other,
}

const INVALID_16: i16 = 0x7FFF;

/// Decodes one message (ID and data). Lengths are checked against the
/// message's definition.
pub fn decode(message: &[u8]) -> Result<Message, Ignored> {
    let need = |n: usize| if message.len() == n { Ok(()) } else { Err(Ignored::Length) };
    match message {
        [0x00, ..] => {
            need(7)?;
            Ok(Message::Heartbeat { gps_valid: message[1] & 0x80 != 0 })
        }
        [0x0A, ..] => {
            need(28)?;
            Ok(Message::Ownship(ownship(&message[1..])))
        }
        [0x0B, ..] => {
            need(5)?;
            Ok(Message::GeoAltitude { feet: Bytes::big(message).i16(1) as f64 * 5.0 })
        }
        [0x65, 0x00, ..] => {
            need(39)?;
            Ok(Message::ForeFlightId { geo_altitude_msl: message[38] & 1 != 0 })
        }
        [0x65, 0x01, ..] => {
            need(12)?;
            Ok(foreflight_ahrs(Bytes::big(message)))
        }
        [0x4C, 0x45, 0x01, 0x01, ..] => {
            need(24)?;
            Ok(stratux_ahrs(Bytes::big(message)))
        }
        _ => Ok(Message::Other),
    }
}

/// The 27 bytes after the ID (§3.5.1, "st aa aa aa ll ll ll nn nn nn dd
/// dm ia hh hv vv tt ee cc..").
fn ownship(data: &[u8]) -> Ownship {
    let semicircles = |at: usize| {
        let raw = (data[at] as i32) << 16 | (data[at + 1] as i32) << 8 | data[at + 2] as i32;
        ((raw << 8) >> 8) as f64 * SEMICIRCLE_LSB_DEG
    };
    let (lat, lon) = (semicircles(4), semicircles(7));
    let nic = data[12] >> 4;
    let no_fix = nic == 0 && data[4..10].iter().all(|&b| b == 0);
    let altitude = (data[10] as u16) << 4 | (data[11] >> 4) as u16;
    let misc = data[11] & 0x0F;
    let speed = (data[13] as u16) << 4 | (data[14] >> 4) as u16;
    let vertical = (data[14] as u16 & 0x0F) << 8 | data[15] as u16;
    let angle = data[16] as f64 * TRACK_LSB_DEG;
    Ownship {
        lat_lon_deg: (!no_fix && nic != 0).then_some([lat, lon]),
        pressure_altitude_ft: (altitude != 0xFFF).then_some(altitude as f64 * 25.0 - 1000.0),
        ground_speed_kt: (speed != 0xFFF).then_some(speed as f64),
        // 12-bit two's complement.
        vertical_fpm: (vertical != 0x800).then_some((((vertical << 4) as i16) >> 4) as f64 * 64.0),
        true_track_deg: (misc & 0b11 == 0b01).then_some(angle),
        true_heading_deg: (misc & 0b11 == 0b11).then_some(angle),
    }
}

fn tenths(bytes: &Bytes<'_>, at: usize) -> Option<f64> {
    let raw = bytes.i16(at);
    (raw != INVALID_16).then(|| raw as f64 / 10.0)
}

fn foreflight_ahrs(b: Bytes<'_>) -> Message {
    let (Some(roll), Some(pitch)) = (tenths(&b, 2), tenths(&b, 4)) else {
        return Message::AhrsInvalid;
    };
    let heading = b.u16(6);
    // Bit 15 set: magnetic, which a conformal display cannot use without
    // the local variation; 0xFFFF: invalid.
    let heading_deg = (heading & 0x8000 == 0).then(|| heading as i16 as f64 / 10.0);
    Message::Ahrs(Ahrs {
        roll_pitch_deg: [roll, pitch],
        heading_deg,
        turn_rate_dps: None,
        vertical_fpm: None,
    })
}

fn stratux_ahrs(b: Bytes<'_>) -> Message {
    let (Some(roll), Some(pitch)) = (tenths(&b, 4), tenths(&b, 6)) else {
        return Message::AhrsInvalid;
    };
    let vertical = b.i16(20);
    Message::Ahrs(Ahrs {
        roll_pitch_deg: [roll, pitch],
        heading_deg: tenths(&b, 8),
        turn_rate_dps: tenths(&b, 12),
        vertical_fpm: (vertical != INVALID_16).then_some(vertical as f64),
    })
}

/// A heartbeat message.
pub fn encode_heartbeat(gps_valid: bool) -> Vec<u8> {
    vec![0x00, 0x01 | if gps_valid { 0x80 } else { 0 }, 0x01, 0, 0, 0, 0]
}

/// An ownship report at `lat`, `lon` degrees, pressure altitude `feet`,
/// ground speed `knots` along true track `track_deg`, vertical speed
/// `fpm`, NIC 10 and NACp 9 (the ICD example's).
pub fn encode_ownship(
    lat: f64,
    lon: f64,
    feet: f64,
    knots: f64,
    track_deg: f64,
    fpm: f64,
) -> Vec<u8> {
    let semicircles = |deg: f64| {
        let raw = (deg / SEMICIRCLE_LSB_DEG).round() as i32 & 0xFF_FFFF;
        [(raw >> 16) as u8, (raw >> 8) as u8, raw as u8]
    };
    let altitude = (((feet + 1000.0) / 25.0).round() as i32).clamp(0, 0xFFE) as u16;
    let speed = (knots.round() as i32).clamp(0, 0xFFE) as u16;
    let vertical = ((fpm / 64.0).round() as i32).clamp(-510, 510) as u16 & 0xFFF;
    let track = ((track_deg.rem_euclid(360.0) / TRACK_LSB_DEG).round() as u32 % 256) as u8;
    let mut m = vec![0x0A, 0x00, 0xAB, 0x45, 0x49];
    m.extend(semicircles(lat));
    m.extend(semicircles(lon));
    m.push((altitude >> 4) as u8);
    m.push(((altitude & 0xF) << 4) as u8 | 0x09); // airborne, true track
    m.push(0xA9);
    m.push((speed >> 4) as u8);
    m.push(((speed & 0xF) << 4) as u8 | (vertical >> 8) as u8);
    m.push(vertical as u8);
    m.push(track);
    m.push(0x01);
    m.extend_from_slice(b"RIDGELN ");
    m.push(0x00);
    m
}

/// An ownship geometric altitude message of `feet`.
pub fn encode_geo_altitude(feet: f64) -> Vec<u8> {
    let units = ((feet / 5.0).round() as i32).clamp(-32768, 32767) as i16;
    let [hi, lo] = units.to_be_bytes();
    vec![0x0B, hi, lo, 0x00, 0x0A]
}

/// A ForeFlight ID message saying the geometric altitude is MSL or not.
pub fn encode_foreflight_id(geo_altitude_msl: bool) -> Vec<u8> {
    let mut m = vec![0x65, 0x00, 0x01];
    m.extend_from_slice(&[0xFF; 8]);
    m.extend_from_slice(b"Ridgelin");
    m.extend_from_slice(b"Ridgeline test  ");
    m.extend_from_slice(&[0, 0, 0, geo_altitude_msl as u8]);
    m
}

fn tenths_bytes(deg: f64) -> [u8; 2] {
    ((deg * 10.0).round() as i16).to_be_bytes()
}

/// A ForeFlight AHRS message of `attitude` (true heading).
pub fn encode_foreflight_ahrs(attitude: &Attitude) -> Vec<u8> {
    let mut m = vec![0x65, 0x01];
    m.extend(tenths_bytes(attitude.roll_deg));
    m.extend(tenths_bytes(attitude.pitch_deg));
    let heading = attitude.heading_deg.rem_euclid(360.0);
    m.extend((((heading * 10.0).round() as u16) % 3600).to_be_bytes());
    m.extend_from_slice(&[0xFF, 0xFF, 0xFF, 0xFF]);
    m
}

/// A Stratux AHRS message of `attitude`, turn rate `turn_dps` and vertical
/// speed `fpm`.
pub fn encode_stratux_ahrs(attitude: &Attitude, turn_dps: f64, fpm: f64) -> Vec<u8> {
    let mut m = vec![0x4C, 0x45, 0x01, 0x01];
    m.extend(tenths_bytes(attitude.roll_deg));
    m.extend(tenths_bytes(attitude.pitch_deg));
    let heading = attitude.heading_deg.rem_euclid(360.0);
    m.extend((((heading * 10.0).round() as i16) % 3600).to_be_bytes());
    m.extend(INVALID_16.to_be_bytes()); // slip/skid
    m.extend(tenths_bytes(turn_dps));
    m.extend(10i16.to_be_bytes()); // 1.0 G
    m.extend(INVALID_16.to_be_bytes()); // airspeed
    m.extend(0xFFFFu16.to_be_bytes()); // pressure altitude
    m.extend((fpm.round() as i16).to_be_bytes());
    m.extend(INVALID_16.to_be_bytes());
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// §3.5.2's traffic report, sent as an ownship report (same fields).
    const ICD_REPORT: [u8; 28] = [
        0x0A, 0x00, 0xAB, 0x45, 0x49, 0x1F, 0xEF, 0x15, 0xA8, 0x89, 0x78, 0x0F, 0x09, 0xA9, 0x07,
        0xB0, 0x01, 0x20, 0x01, 0x4E, 0x38, 0x32, 0x35, 0x56, 0x20, 0x20, 0x20, 0x00,
    ];

    #[test]
    fn the_icd_example_report_decodes() {
        let Message::Ownship(o) = decode(&ICD_REPORT).unwrap() else { panic!("not an ownship") };
        let [lat, lon] = o.lat_lon_deg.unwrap();
        assert!((lat - 44.90708).abs() < 2e-5 && (lon + 122.99488).abs() < 2e-5, "{lat} {lon}");
        assert_eq!(o.pressure_altitude_ft, Some(5000.0));
        assert_eq!(o.ground_speed_kt, Some(123.0));
        assert_eq!(o.vertical_fpm, Some(64.0));
        assert_eq!(o.true_track_deg, Some(45.0));
        let encoded = encode_ownship(lat, lon, 5000.0, 123.0, 45.0, 64.0);
        assert_eq!(&encoded[5..19], &ICD_REPORT[5..19], "the encoder writes the same fields");
    }

    #[test]
    fn special_values_mean_unavailable() {
        let mut m = encode_ownship(-33.5, 151.0, 1200.0, 0.0, 0.0, -640.0);
        let Message::Ownship(o) = decode(&m).unwrap() else { panic!() };
        assert_eq!(o.vertical_fpm, Some(-640.0), "negative 12-bit velocities");
        assert!((o.lat_lon_deg.unwrap()[0] + 33.5).abs() < 3e-5);
        m[11] = 0xFF;
        m[12] = 0xF9;
        m[14] = 0xFF;
        m[15] = 0xF8;
        m[16] = 0x00;
        let Message::Ownship(o) = decode(&m).unwrap() else { panic!() };
        assert_eq!((o.pressure_altitude_ft, o.ground_speed_kt, o.vertical_fpm), (None, None, None));
        m[5..11].fill(0);
        m[13] = 0x09; // NIC 0
        let Message::Ownship(o) = decode(&m).unwrap() else { panic!() };
        assert_eq!(o.lat_lon_deg, None, "no fix");
    }

    #[test]
    fn ahrs_messages_round_trip_and_flag_invalid() {
        let a = Attitude { heading_deg: 271.3, pitch_deg: -4.2, roll_deg: 25.6 };
        let Message::Ahrs(ff) = decode(&encode_foreflight_ahrs(&a)).unwrap() else { panic!() };
        assert_eq!(ff.roll_pitch_deg, [25.6, -4.2]);
        assert_eq!(ff.heading_deg, Some(271.3));
        let mut magnetic = encode_foreflight_ahrs(&a);
        magnetic[6] |= 0x80;
        let Message::Ahrs(m) = decode(&magnetic).unwrap() else { panic!() };
        assert_eq!(m.heading_deg, None, "a magnetic heading is not used");
        let Message::Ahrs(sx) = decode(&encode_stratux_ahrs(&a, 3.0, -500.0)).unwrap() else {
            panic!()
        };
        assert_eq!(
            (sx.heading_deg, sx.turn_rate_dps, sx.vertical_fpm),
            (Some(271.3), Some(3.0), Some(-500.0))
        );
        let mut invalid = encode_stratux_ahrs(&a, 0.0, 0.0);
        invalid[4..6].copy_from_slice(&INVALID_16.to_be_bytes());
        assert_eq!(decode(&invalid), Ok(Message::AhrsInvalid));
        assert_eq!(decode(&encode_foreflight_ahrs(&a)[..11]), Err(Ignored::Length));
    }

    #[test]
    fn geometric_altitude_and_id_decode() {
        assert_eq!(decode(&[0x0B, 0xFF, 0x38, 0, 0]), Ok(Message::GeoAltitude { feet: -1000.0 }));
        assert_eq!(decode(&encode_geo_altitude(9875.0)), Ok(Message::GeoAltitude { feet: 9875.0 }));
        assert_eq!(
            decode(&encode_foreflight_id(true)),
            Ok(Message::ForeFlightId { geo_altitude_msl: true })
        );
        assert_eq!(decode(&[0x14; 28]), Ok(Message::Other));
    }
}
