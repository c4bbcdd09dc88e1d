//! The live pose record: where the aircraft is and how it moves, in
//! geodetic terms (latitude and longitude in degrees, altitude in metres
//! above mean sea level, attitude in degrees), and its bounded
//! extrapolation to a frame's time.
//!
//! Every input protocol decodes into these types; the display converts them
//! to its own frame only at the last moment ([`super::place`]).

use crate::flight::pose::normalize_heading;
use crate::geo::metres_per_degree;

/// How far ahead of its sample a pose is ever extrapolated, seconds: past
/// it the pose holds until the data go stale.
pub const MAX_EXTRAPOLATION_S: f64 = 0.5;

/// Where the aircraft is: geodetic latitude and longitude (WGS 84),
/// altitude above mean sea level.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Position {
    /// Latitude, degrees north, in [-90, 90].
    pub lat_deg: f64,
    /// Longitude, degrees east, in [-180, 180].
    pub lon_deg: f64,
    /// Altitude above mean sea level, metres.
    pub alt_m: f64,
}

/// How the aircraft is turned, in the camera's conventions.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Attitude {
    /// True heading, degrees clockwise from north, in [0, 360).
    pub heading_deg: f64,
    /// Pitch, degrees nose up, in [-90, 90].
    pub pitch_deg: f64,
    /// Roll, degrees right wing down, in [-180, 180].
    pub roll_deg: f64,
}

/// A position with the velocity it moves at.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Track {
    /// Where the aircraft was when the sample was taken.
    pub position: Position,
    /// Velocity over the ground, metres a second: north, east, down.
    /// `None` when the source gave none (the position then holds).
    pub velocity_ned: Option<[f64; 3]>,
    /// Whether the vertical component of `velocity_ned` was measured (a
    /// GDL 90 box may give ground speed and track but no vertical speed:
    /// the position then moves level, and no flight path marker is drawn).
    pub vertical_known: bool,
}

/// An attitude with the rates it changes at.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Turning {
    /// The attitude when the sample was taken.
    pub attitude: Attitude,
    /// Euler angle rates, degrees a second: heading, pitch, roll. `None`
    /// when the source gave none; a zero stands for a rate not given.
    pub rates_dps: Option<[f64; 3]>,
}

/// One instant's pose, extrapolated or as received.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct GeoPose {
    /// Latitude, degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Altitude above mean sea level, metres.
    pub alt_m: f64,
    /// True heading, degrees.
    pub heading_deg: f64,
    /// Pitch, degrees nose up.
    pub pitch_deg: f64,
    /// Roll, degrees right wing down.
    pub roll_deg: f64,
}

impl GeoPose {
    /// The pose of `position` and `attitude`.
    pub fn new(position: Position, attitude: Attitude) -> GeoPose {
        GeoPose {
            lat_deg: position.lat_deg,
            lon_deg: position.lon_deg,
            alt_m: position.alt_m,
            heading_deg: attitude.heading_deg,
            pitch_deg: attitude.pitch_deg,
            roll_deg: attitude.roll_deg,
        }
    }
}

/// `dt_s` clamped to the extrapolation horizon: never back in time (a
/// sample stamped after the frame), never past [`MAX_EXTRAPOLATION_S`].
pub fn horizon(dt_s: f64) -> f64 {
    if dt_s.is_nan() {
        return 0.0;
    }
    dt_s.clamp(0.0, MAX_EXTRAPOLATION_S)
}

impl Track {
    /// The position `dt_s` seconds after the sample (clamped by
    /// [`horizon`]), moved along the velocity on the WGS 84 ellipsoid's
    /// local scales.
    pub fn at(&self, dt_s: f64) -> Position {
        let dt = horizon(dt_s);
        let Some([north, east, down]) = self.velocity_ned.filter(|_| dt > 0.0) else {
            return self.position;
        };
        let [east_m_per_deg, north_m_per_deg] = metres_per_degree(self.position.lat_deg);
        let lat = (self.position.lat_deg + north * dt / north_m_per_deg).clamp(-90.0, 90.0);
        // Over half a second the east scale hardly changes; near a pole it
        // vanishes, so the longitude step is bounded there.
        let lon_step = east * dt / east_m_per_deg.max(1.0);
        Position {
            lat_deg: lat,
            lon_deg: wrap_longitude(self.position.lon_deg + lon_step),
            alt_m: self.position.alt_m - down * dt,
        }
    }

    /// Ground speed, metres a second (0 without a velocity).
    pub fn ground_speed(&self) -> f64 {
        self.velocity_ned.map_or(0.0, |[n, e, _]| n.hypot(e))
    }
}

impl Turning {
    /// The attitude `dt_s` seconds after the sample (clamped by
    /// [`horizon`]), turned at the sample's rates.
    pub fn at(&self, dt_s: f64) -> Attitude {
        let dt = horizon(dt_s);
        let Some([heading, pitch, roll]) = self.rates_dps else { return self.attitude };
        let a = self.attitude;
        Attitude {
            heading_deg: normalize_heading(a.heading_deg + heading * dt),
            pitch_deg: (a.pitch_deg + pitch * dt).clamp(-90.0, 90.0),
            roll_deg: wrap_roll(a.roll_deg + roll * dt),
        }
    }
}

/// `degrees` brought into [-180, 180] (left as it is when inside, so a
/// longitude that did not move is bit for bit the same).
pub fn wrap_longitude(degrees: f64) -> f64 {
    if (-180.0..=180.0).contains(&degrees) {
        return degrees;
    }
    (degrees + 180.0).rem_euclid(360.0) - 180.0
}

/// A roll angle brought into [-180, 180] (unchanged when inside).
pub fn wrap_roll(degrees: f64) -> f64 {
    wrap_longitude(degrees)
}

/// Euler angle rates (heading, pitch, roll; degrees a second) of body
/// rates `p`, `q`, `r` (roll, pitch and yaw rate about the body axes,
/// radians a second) at `attitude`: the standard kinematic relation
/// (Stevens & Lewis, eq. 1.3-22), bounded near pitch ±90° where the
/// heading rate is undefined.
pub fn euler_rates(attitude: &Attitude, p: f64, q: f64, r: f64) -> [f64; 3] {
    let phi = attitude.roll_deg.to_radians();
    let theta = attitude.pitch_deg.to_radians().clamp(-1.55, 1.55);
    let roll_rate = p + (q * phi.sin() + r * phi.cos()) * theta.tan();
    let pitch_rate = q * phi.cos() - r * phi.sin();
    let heading_rate = (q * phi.sin() + r * phi.cos()) / theta.cos();
    [heading_rate.to_degrees(), pitch_rate.to_degrees(), roll_rate.to_degrees()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(velocity: Option<[f64; 3]>) -> Track {
        Track {
            position: Position { lat_deg: 39.5, lon_deg: 40.2, alt_m: 3000.0 },
            velocity_ned: velocity,
            vertical_known: true,
        }
    }

    #[test]
    fn a_track_moves_along_its_velocity_and_stops_at_the_horizon() {
        let t = track(Some([100.0, 0.0, -5.0]));
        let [_, north] = metres_per_degree(39.5);
        let p = t.at(0.25);
        assert!(((p.lat_deg - 39.5) * north - 25.0).abs() < 1e-6, "{p:?}");
        assert!((p.alt_m - 3001.25).abs() < 1e-9);
        assert_eq!(t.at(0.5), t.at(3.0), "held past the horizon");
        assert_eq!(t.at(-1.0), t.position, "never back in time");
        assert_eq!(t.at(f64::NAN), t.position);
        assert_eq!(track(None).at(0.4), track(None).position);
    }

    #[test]
    fn attitude_turns_at_its_rates_and_wraps() {
        let turning = Turning {
            attitude: Attitude { heading_deg: 359.0, pitch_deg: 89.0, roll_deg: 179.0 },
            rates_dps: Some([4.0, 10.0, 6.0]),
        };
        let a = turning.at(0.5);
        assert!((a.heading_deg - 1.0).abs() < 1e-9, "{a:?}");
        assert_eq!(a.pitch_deg, 90.0);
        assert!((a.roll_deg + 178.0).abs() < 1e-9, "{a:?}");
    }

    #[test]
    fn body_rates_become_euler_rates() {
        let level = Attitude::default();
        let [h, p, r] = euler_rates(&level, 0.1, 0.0, 0.0);
        assert!(h.abs() < 1e-12 && p.abs() < 1e-12 && (r - 0.1f64.to_degrees()).abs() < 1e-9);
        // Banked 90 degrees right, a body pitch rate turns the heading.
        let banked = Attitude { roll_deg: 90.0, ..level };
        let [h, p, _] = euler_rates(&banked, 0.0, 0.05, 0.0);
        assert!((h - 0.05f64.to_degrees()).abs() < 1e-9 && p.abs() < 1e-9, "{h} {p}");
    }
}
