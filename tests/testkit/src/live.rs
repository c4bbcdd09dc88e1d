//! A scripted flight for the live-input tests: a steady climbing turn over
//! the built-in terrain whose pose and velocity are known in closed form
//! at any time, and its encoding as each protocol's datagrams.

use std::f64::consts::PI;

use ridgeline::geo::metres_per_degree;
use ridgeline::input::gdl90::{frame::frame, messages};
use ridgeline::input::{flightgear, xplane, Attitude, GeoPose, Position, Track, Turning};

/// A steady climbing turn: constant ground speed, climb, turn rate, pitch
/// and roll; the heading is the track (no wind).
#[derive(Clone, Copy, Debug)]
pub struct Script {
    /// Where it starts, degrees and metres MSL.
    pub start: Position,
    /// Heading at t = 0, degrees.
    pub heading_deg: f64,
    /// Ground speed, m/s.
    pub speed_mps: f64,
    /// Climb, m/s.
    pub climb_mps: f64,
    /// Turn rate, degrees a second (positive right).
    pub turn_dps: f64,
    /// Pitch, degrees.
    pub pitch_deg: f64,
    /// Roll, degrees.
    pub roll_deg: f64,
}

/// The scripted flight: 70 m/s over the built-in SRTM tile (Erzincan),
/// climbing 2 m/s in a 1.5°/s right turn.
pub const SCRIPT: Script = Script {
    start: Position { lat_deg: 39.55, lon_deg: 40.35, alt_m: 3200.0 },
    heading_deg: 60.0,
    speed_mps: 70.0,
    climb_mps: 2.0,
    turn_dps: 1.5,
    pitch_deg: 3.0,
    roll_deg: 15.0,
};

impl Script {
    /// The pose at `t` seconds.
    pub fn pose(&self, t: f64) -> GeoPose {
        let (north, east) = self.displacement(t);
        let [east_per_deg, north_per_deg] = metres_per_degree(self.start.lat_deg);
        GeoPose {
            lat_deg: self.start.lat_deg + north / north_per_deg,
            lon_deg: self.start.lon_deg + east / east_per_deg,
            alt_m: self.start.alt_m + self.climb_mps * t,
            heading_deg: self.heading(t),
            pitch_deg: self.pitch_deg,
            roll_deg: self.roll_deg,
        }
    }

    fn heading(&self, t: f64) -> f64 {
        (self.heading_deg + self.turn_dps * t).rem_euclid(360.0)
    }

    /// Metres north and east of the start at `t` (the turn's arc, integrated).
    fn displacement(&self, t: f64) -> (f64, f64) {
        let (h0, w) = (self.heading_deg.to_radians(), self.turn_dps.to_radians());
        let h = h0 + w * t;
        let r = self.speed_mps / w;
        (r * (h.sin() - h0.sin()), r * (h0.cos() - h.cos()))
    }

    /// Velocity north, east, down at `t`, m/s.
    pub fn velocity(&self, t: f64) -> [f64; 3] {
        let h = self.heading(t).to_radians();
        [self.speed_mps * h.cos(), self.speed_mps * h.sin(), -self.climb_mps]
    }

    /// The track and turning the sources report at `t`.
    pub fn sample(&self, t: f64) -> (Track, Turning) {
        let pose = self.pose(t);
        let position = Position { lat_deg: pose.lat_deg, lon_deg: pose.lon_deg, alt_m: pose.alt_m };
        let attitude = Attitude { heading_deg: pose.heading_deg, pitch_deg: pose.pitch_deg, roll_deg: pose.roll_deg };
        let track = Track { position, velocity_ned: Some(self.velocity(t)), vertical_known: true };
        (track, Turning { attitude, rates_dps: Some([self.turn_dps, 0.0, 0.0]) })
    }

    /// FlightGear's packet of `version` at `t`.
    pub fn flightgear(&self, version: u32, t: f64) -> Vec<u8> {
        let (track, turning) = self.sample(t);
        flightgear::encode(version, &track, &turning)
    }

    /// X-Plane's `RPOS` at `t`, the turn as body rates.
    pub fn rpos(&self, t: f64) -> Vec<u8> {
        let (track, turning) = self.sample(t);
        // The Euler heading rate ψ' as body rates at roll φ and pitch θ:
        // q = ψ' cos θ sin φ, r = ψ' cos θ cos φ, p = -ψ' sin θ.
        let (phi, theta) = (self.roll_deg.to_radians(), self.pitch_deg.to_radians());
        let psi_dot = self.turn_dps * PI / 180.0;
        let body = [-psi_dot * theta.sin(), psi_dot * theta.cos() * phi.sin(), psi_dot * theta.cos() * phi.cos()];
        xplane::encode_rpos(&track, &turning, body)
    }

    /// A GDL 90 datagram with the ownship report and geometric altitude
    /// (MSL: the box's ID message says so) at `t`.
    pub fn gdl90_ownship(&self, t: f64) -> Vec<u8> {
        let pose = self.pose(t);
        let [north, east, down] = self.velocity(t);
        let knots = north.hypot(east) / messages::KNOT;
        let track = east.atan2(north).to_degrees();
        let fpm = -down / messages::FOOT * 60.0;
        let feet = pose.alt_m / messages::FOOT;
        let mut datagram = frame(&messages::encode_foreflight_id(true));
        datagram.extend(frame(&messages::encode_ownship(pose.lat_deg, pose.lon_deg, feet, knots, track, fpm)));
        datagram.extend(frame(&messages::encode_geo_altitude(feet)));
        datagram
    }

    /// A GDL 90 datagram with Stratux's AHRS report at `t`.
    pub fn gdl90_stratux_ahrs(&self, t: f64) -> Vec<u8> {
        let pose = self.pose(t);
        let attitude = Attitude { heading_deg: pose.heading_deg, pitch_deg: pose.pitch_deg, roll_deg: pose.roll_deg };
        frame(&messages::encode_stratux_ahrs(&attitude, self.turn_dps, self.climb_mps / messages::FOOT * 60.0))
    }

    /// A GDL 90 datagram with ForeFlight's AHRS report at `t`.
    pub fn gdl90_foreflight_ahrs(&self, t: f64) -> Vec<u8> {
        let pose = self.pose(t);
        let attitude = Attitude { heading_deg: pose.heading_deg, pitch_deg: pose.pitch_deg, roll_deg: pose.roll_deg };
        frame(&messages::encode_foreflight_ahrs(&attitude))
    }
}

/// Horizontal and vertical distance between two poses, metres, and the
/// largest attitude difference, degrees (headings across north wrap).
pub fn pose_error(a: &GeoPose, b: &GeoPose) -> (f64, f64, f64) {
    let [east_per_deg, north_per_deg] = metres_per_degree(a.lat_deg);
    let north = (b.lat_deg - a.lat_deg) * north_per_deg;
    let east = (b.lon_deg - a.lon_deg) * east_per_deg;
    let heading = ((b.heading_deg - a.heading_deg + 180.0).rem_euclid(360.0) - 180.0).abs();
    let attitude = heading.max((b.pitch_deg - a.pitch_deg).abs()).max((b.roll_deg - a.roll_deg).abs());
    (north.hypot(east), (b.alt_m - a.alt_m).abs(), attitude)
}
