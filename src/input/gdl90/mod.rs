//! GDL 90 over UDP (as a Stratux, a ForeFlight Sentry or a GDL 90 box
//! sends it to port 4000): framing ([`frame`]), messages ([`messages`]),
//! and the state that turns them into a pose.
//!
//! A pose needs messages of two kinds and rates: the ownship report
//! (position, pressure altitude, ground speed, true track, vertical speed;
//! once a second) and an AHRS report (attitude; ForeFlight's at 5 Hz,
//! Stratux's at about 10-20 Hz). The altitude is the geometric one when an
//! Ownship Geometric Altitude message came within
//! [`GEO_ALTITUDE_FRESH_S`], carried forward by the vertical speed,
//! otherwise the pressure altitude. The geometric altitude is height above
//! the WGS 84 ellipsoid (ICD §3.8) unless the ForeFlight ID message says
//! it is MSL; ellipsoid heights become MSL by subtracting the configured
//! geoid height ([`Gdl90::new`]). The heading is the AHRS's true heading;
//! where the AHRS gives none (Stratux's ForeFlight AHRS sends 0xFFFF) or a
//! magnetic one, the ownship's true track stands in, as electronic flight
//! bags do without a heading source.

pub mod frame;
pub mod messages;

use std::time::Instant;

use messages::{Ahrs, Message, Ownship, FOOT, KNOT};

use super::pose::{Attitude, Position, Track, Turning};
use super::update::{Ignored, Update};

/// How often the ownship report comes, seconds (ICD §3.4: once a second).
pub const OWNSHIP_INTERVAL_S: f64 = 1.0;

/// How long a geometric altitude stays usable, seconds (it comes once a
/// second, after each ownship report).
pub const GEO_ALTITUDE_FRESH_S: f64 = 2.5;

/// The GDL 90 decoder: what earlier messages said that later ones need.
#[derive(Clone, Debug)]
pub struct Gdl90 {
    /// Geoid height above the ellipsoid, metres, subtracted from an
    /// ellipsoidal geometric altitude to give MSL.
    geoid_m: f64,
    geo_altitude_msl: bool,
    /// The last geometric altitude (metres MSL) and when it came.
    geo_altitude: Option<(f64, Instant)>,
    /// The last ownship report and when it came.
    ownship: Option<(Ownship, Instant)>,
    /// The last AHRS vertical speed, metres a second, and when it came.
    ahrs_vertical: Option<(f64, Instant)>,
    heartbeat_gps_valid: bool,
}

impl Gdl90 {
    /// A decoder that takes `geoid_m` (the geoid's height above the WGS 84
    /// ellipsoid where the aircraft flies) off ellipsoidal altitudes.
    pub fn new(geoid_m: f64) -> Gdl90 {
        Gdl90 {
            geoid_m,
            geo_altitude_msl: false,
            geo_altitude: None,
            ownship: None,
            ahrs_vertical: None,
            heartbeat_gps_valid: true,
        }
    }

    /// Decodes one datagram received at `now`.
    pub fn decode(&mut self, datagram: &[u8], now: Instant) -> Result<Update, Ignored> {
        let mut update = Update::default();
        let mut problem = None;
        let framed = frame::for_each_message(datagram, |message| match messages::decode(message) {
            Ok(message) => update.merge(self.apply(message, now)),
            Err(reason) => problem = problem.or(Some(reason)),
        });
        if !update.is_empty() {
            return Ok(update);
        }
        framed?;
        Err(problem.unwrap_or(Ignored::Unused))
    }

    fn apply(&mut self, message: Message, now: Instant) -> Update {
        match message {
            Message::Heartbeat { gps_valid } => {
                self.heartbeat_gps_valid = gps_valid;
                let valid = gps_valid && self.ownship.is_some_and(|(o, _)| o.lat_lon_deg.is_some());
                Update { position_valid: Some(valid), ..Update::default() }
            }
            Message::Ownship(ownship) => {
                self.ownship = Some((ownship, now));
                self.position_update(now)
            }
            Message::GeoAltitude { feet } => {
                let datum = if self.geo_altitude_msl { 0.0 } else { self.geoid_m };
                self.geo_altitude = Some((feet * FOOT - datum, now));
                // The geometric altitude follows its ownship report: the
                // position is sent again with it.
                match self.ownship {
                    Some((_, at)) if seconds(at, now) < 1.5 => self.position_update(now),
                    _ => Update::default(),
                }
            }
            Message::ForeFlightId { geo_altitude_msl } => {
                self.geo_altitude_msl = geo_altitude_msl;
                Update::default()
            }
            Message::Ahrs(ahrs) => self.attitude_update(&ahrs, now),
            Message::AhrsInvalid => Update { attitude_valid: Some(false), ..Update::default() },
            Message::Other => Update::default(),
        }
    }

    /// The last ownship report as a track at `now`.
    fn position_update(&self, now: Instant) -> Update {
        let Some((ownship, at)) = self.ownship else { return Update::default() };
        let velocity = self.velocity(&ownship, now);
        let altitude = match self.geo_altitude {
            Some((metres, when)) if seconds(when, now) < GEO_ALTITUDE_FRESH_S => {
                let climb = velocity.filter(|(_, known)| *known).map_or(0.0, |([.., d], _)| -d);
                Some(metres + climb * seconds(when, now))
            }
            _ => ownship.pressure_altitude_ft.map(|ft| ft * FOOT),
        };
        let (Some([lat, lon]), Some(alt_m)) = (ownship.lat_lon_deg, altitude) else {
            return Update { position_valid: Some(false), ..Update::default() };
        };
        let track = Track {
            position: Position { lat_deg: lat, lon_deg: lon, alt_m },
            velocity_ned: velocity.map(|(v, _)| v),
            vertical_known: velocity.is_some_and(|(_, known)| known),
        };
        // A report re-sent with its geometric altitude has moved on since.
        let track = Track { position: track.at(seconds(at, now)), ..track };
        Update {
            track: Some(track),
            position_valid: Some(self.heartbeat_gps_valid),
            position_interval_s: Some(OWNSHIP_INTERVAL_S),
            ..Update::default()
        }
    }

    /// Ground velocity (north, east, down; m/s) from the ownship's speed
    /// and true track, the vertical from its vertical velocity or the
    /// AHRS's; and whether the vertical was measured.
    fn velocity(&self, ownship: &Ownship, now: Instant) -> Option<([f64; 3], bool)> {
        let (speed, track) = (ownship.ground_speed_kt?, ownship.true_track_deg?);
        let (north, east) =
            (speed * KNOT * track.to_radians().cos(), speed * KNOT * track.to_radians().sin());
        let ahrs = self.ahrs_vertical.filter(|(_, at)| seconds(*at, now) < 1.0).map(|(v, _)| v);
        let up = ownship.vertical_fpm.map(|fpm| fpm * FOOT / 60.0).or(ahrs);
        Some(([north, east, -up.unwrap_or(0.0)], up.is_some()))
    }

    fn attitude_update(&mut self, ahrs: &Ahrs, now: Instant) -> Update {
        if let Some(fpm) = ahrs.vertical_fpm {
            self.ahrs_vertical = Some((fpm * FOOT / 60.0, now));
        }
        let track = self.ownship.and_then(|(o, _)| o.true_track_deg.or(o.true_heading_deg));
        let Some(heading) = ahrs.heading_deg.or(track) else {
            // No heading from anywhere: the attitude cannot be drawn.
            return Update { attitude_valid: Some(false), ..Update::default() };
        };
        let [roll, pitch] = ahrs.roll_pitch_deg;
        let attitude = Attitude {
            heading_deg: crate::flight::pose::normalize_heading(heading),
            pitch_deg: pitch,
            roll_deg: roll,
        };
        let rates = ahrs.turn_rate_dps.map(|turn| [turn, 0.0, 0.0]);
        Update {
            turning: Some(Turning { attitude, rates_dps: rates }),
            attitude_valid: Some(true),
            ..Update::default()
        }
    }
}

fn seconds(from: Instant, to: Instant) -> f64 {
    to.saturating_duration_since(from).as_secs_f64()
}

#[cfg(test)]
mod tests {
    use super::*;
    use frame::frame;
    use messages::*;

    fn datagram(parts: &[Vec<u8>]) -> Vec<u8> {
        parts.iter().flat_map(|m| frame(m)).collect()
    }

    #[test]
    fn ownship_and_ahrs_make_a_pose_with_geometric_altitude_in_msl() {
        let mut gdl = Gdl90::new(30.0);
        let now = Instant::now();
        let first = gdl
            .decode(
                &datagram(&[
                    encode_heartbeat(true),
                    encode_ownship(39.6, 40.1, 9000.0, 120.0, 90.0, 640.0),
                ]),
                now,
            )
            .unwrap();
        let track = first.track.unwrap();
        assert!((track.position.alt_m - 9000.0 * FOOT).abs() < 1e-9, "pressure altitude first");
        let v = track.velocity_ned.unwrap();
        assert!(
            v[0].abs() < 1e-9
                && (v[1] - 120.0 * KNOT).abs() < 1e-9
                && (v[2] + 640.0 * FOOT / 60.0).abs() < 1e-9
        );
        let geo = gdl.decode(&datagram(&[encode_geo_altitude(9500.0)]), now).unwrap();
        assert!(
            (geo.track.unwrap().position.alt_m - (9500.0 * FOOT - 30.0)).abs() < 1e-9,
            "ellipsoid to MSL"
        );
        gdl.decode(&datagram(&[encode_foreflight_id(true)]), now).unwrap_err();
        let geo = gdl.decode(&datagram(&[encode_geo_altitude(9500.0)]), now).unwrap();
        assert!((geo.track.unwrap().position.alt_m - 9500.0 * FOOT).abs() < 1e-9, "already MSL");
        let a = Attitude { heading_deg: 93.0, pitch_deg: 2.0, roll_deg: -10.0 };
        let ahrs = gdl.decode(&datagram(&[encode_stratux_ahrs(&a, 1.5, 0.0)]), now).unwrap();
        let t = ahrs.turning.unwrap();
        assert_eq!(t.attitude.heading_deg, 93.0);
        assert_eq!(t.rates_dps, Some([1.5, 0.0, 0.0]));
    }

    #[test]
    fn a_missing_heading_takes_the_true_track_and_invalid_flags_pass_through() {
        let mut gdl = Gdl90::new(0.0);
        let now = Instant::now();
        gdl.decode(&datagram(&[encode_ownship(39.6, 40.1, 9000.0, 120.0, 45.0, 0.0)]), now)
            .unwrap();
        let mut ahrs = encode_foreflight_ahrs(&Attitude::default());
        ahrs[6..8].copy_from_slice(&[0xFF, 0xFF]);
        let t = gdl.decode(&datagram(&[ahrs]), now).unwrap().turning.unwrap();
        assert_eq!(t.attitude.heading_deg, 45.0);
        let off = gdl.decode(&datagram(&[encode_heartbeat(false)]), now).unwrap();
        assert_eq!(off.position_valid, Some(false));
        let mut invalid = encode_foreflight_ahrs(&Attitude::default());
        invalid[2..4].copy_from_slice(&[0x7F, 0xFF]);
        assert_eq!(gdl.decode(&datagram(&[invalid]), now).unwrap().attitude_valid, Some(false));
    }

    #[test]
    fn datagrams_without_anything_usable_say_why() {
        let mut gdl = Gdl90::new(0.0);
        let now = Instant::now();
        assert_eq!(gdl.decode(&datagram(&[vec![0x14; 28]]), now), Err(Ignored::Unused));
        assert_eq!(gdl.decode(&[1, 2, 3], now), Err(Ignored::Header));
        let mut bad = datagram(&[encode_heartbeat(true)]);
        bad[2] ^= 4;
        assert_eq!(gdl.decode(&bad, now), Err(Ignored::Crc));
        assert_eq!(gdl.decode(&datagram(&[vec![0x0A; 20]]), now), Err(Ignored::Length));
    }
}
