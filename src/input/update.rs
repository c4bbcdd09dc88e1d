//! What one datagram contributes to the live state ([`Update`]), why one
//! is ignored ([`Ignored`]), and the plausibility checks every update passes
//! before it is taken: finite numbers, angles on the earth and the
//! aircraft, altitudes an aircraft flies at.

use super::pose::{Track, Turning};

/// What one datagram contributes: a new position with its velocity, a new
/// attitude with its rates, and the source's word on whether either is
/// valid (GDL 90's heartbeat and integrity fields, its AHRS's invalid
/// values). A datagram that contributes nothing is ignored as unused.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Update {
    /// A new position.
    pub track: Option<Track>,
    /// A new attitude.
    pub turning: Option<Turning>,
    /// The source flags its position valid (`Some(true)`) or invalid.
    pub position_valid: Option<bool>,
    /// The source flags its attitude valid (`Some(true)`) or invalid.
    pub attitude_valid: Option<bool>,
    /// How often the source reports its position, seconds, when it is
    /// slower than the frame rate (GDL 90's ownship report: once a
    /// second): the position goes stale that much later, so a report a
    /// little late does not withdraw the terrain.
    pub position_interval_s: Option<f64>,
}

impl Update {
    /// Whether the update carries anything at all.
    pub fn is_empty(&self) -> bool {
        self.track.is_none()
            && self.turning.is_none()
            && self.position_valid.is_none()
            && self.attitude_valid.is_none()
    }

    /// `other`'s parts over this one's (the later message wins).
    pub fn merge(&mut self, other: Update) {
        self.track = other.track.or(self.track);
        self.turning = other.turning.or(self.turning);
        self.position_valid = other.position_valid.or(self.position_valid);
        self.attitude_valid = other.attitude_valid.or(self.attitude_valid);
        self.position_interval_s = other.position_interval_s.or(self.position_interval_s);
    }
}

/// Why a datagram was ignored. Each is counted; none stops the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ignored {
    /// Shorter or longer than the protocol's packet.
    Length,
    /// FlightGear's version word is neither 24 nor 25.
    Version,
    /// Not this protocol's header (X-Plane's `RPOS`/`DATA`, GDL 90's flag
    /// byte or a message ID above 127).
    Header,
    /// GDL 90 framing broken: an escape at the end, a frame with no
    /// closing flag, a frame longer than any message.
    Framing,
    /// GDL 90 frame check sequence wrong.
    Crc,
    /// A value is NaN or infinite.
    NotFinite,
    /// A value no aircraft has: latitude beyond ±90°, longitude beyond
    /// ±180°, pitch beyond ±90°, an altitude outside
    /// [`MIN_ALTITUDE_M`]..[`MAX_ALTITUDE_M`], a speed above [`MAX_SPEED_MPS`].
    OutOfRange,
    /// A position further from the last one than any aircraft flies in the time between.
    Jump,
    /// Well formed, but nothing in it is used (GDL 90 traffic and
    /// weather, X-Plane DATA without groups 17 and 20).
    Unused,
    /// Larger than the receive buffer.
    Oversize,
}

impl Ignored {
    /// Every reason, in counting order.
    pub const ALL: [Ignored; 10] = [
        Ignored::Length,
        Ignored::Version,
        Ignored::Header,
        Ignored::Framing,
        Ignored::Crc,
        Ignored::NotFinite,
        Ignored::OutOfRange,
        Ignored::Jump,
        Ignored::Unused,
        Ignored::Oversize,
    ];

    /// The reason's name in stats.json and the summary.
    pub fn name(self) -> &'static str {
        match self {
            Ignored::Length => "length",
            Ignored::Version => "version",
            Ignored::Header => "header",
            Ignored::Framing => "framing",
            Ignored::Crc => "crc",
            Ignored::NotFinite => "not_finite",
            Ignored::OutOfRange => "out_of_range",
            Ignored::Jump => "jump",
            Ignored::Unused => "unused",
            Ignored::Oversize => "oversize",
        }
    }
}

/// The lowest altitude taken, metres MSL (the Dead Sea shore is at -430 m).
pub const MIN_ALTITUDE_M: f64 = -1_000.0;
/// The highest altitude taken, metres MSL (above any aircraft's ceiling).
pub const MAX_ALTITUDE_M: f64 = 40_000.0;
/// The fastest ground speed taken, metres a second (Mach 3.5 at altitude,
/// beyond any aircraft a synthetic-vision display flies in).
pub const MAX_SPEED_MPS: f64 = 1_200.0;
/// The fastest climb or descent taken, metres a second.
pub const MAX_VERTICAL_SPEED_MPS: f64 = 500.0;

/// Refuses an update whose numbers no aircraft can have.
pub fn check(update: &Update) -> Result<(), Ignored> {
    if let Some(track) = &update.track {
        let p = &track.position;
        let velocity = track.velocity_ned.unwrap_or_default();
        finite(&[p.lat_deg, p.lon_deg, p.alt_m])?;
        finite(&velocity)?;
        let speed = velocity[0].hypot(velocity[1]);
        let in_range = p.lat_deg.abs() <= 90.0
            && p.lon_deg.abs() <= 180.0
            && (MIN_ALTITUDE_M..=MAX_ALTITUDE_M).contains(&p.alt_m)
            && speed <= MAX_SPEED_MPS
            && velocity[2].abs() <= MAX_VERTICAL_SPEED_MPS;
        if !in_range {
            return Err(Ignored::OutOfRange);
        }
    }
    if let Some(turning) = &update.turning {
        let a = &turning.attitude;
        finite(&[a.heading_deg, a.pitch_deg, a.roll_deg])?;
        finite(&turning.rates_dps.unwrap_or_default())?;
        // Headings wrap (some sources send -180..180 or 0..720); pitch cannot.
        let in_range = a.pitch_deg.abs() <= 90.0
            && a.roll_deg.abs() <= 360.0
            && a.heading_deg.abs() <= 720.0
            && turning.rates_dps.unwrap_or_default().iter().all(|r| r.abs() <= 720.0);
        if !in_range {
            return Err(Ignored::OutOfRange);
        }
    }
    Ok(())
}

fn finite(values: &[f64]) -> Result<(), Ignored> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Ignored::NotFinite)
    }
}

/// Reads big- or little-endian numbers at byte offsets of a slice whose
/// length the caller has checked (every read is in bounds by then; a read
/// past the end would be a bug, and panics).
pub(crate) struct Bytes<'a> {
    bytes: &'a [u8],
    big_endian: bool,
}

impl<'a> Bytes<'a> {
    pub fn big(bytes: &'a [u8]) -> Self {
        Bytes { bytes, big_endian: true }
    }

    pub fn little(bytes: &'a [u8]) -> Self {
        Bytes { bytes, big_endian: false }
    }

    fn array<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut out = [0; N];
        out.copy_from_slice(&self.bytes[at..at + N]);
        out
    }

    pub fn u32(&self, at: usize) -> u32 {
        let raw = self.array::<4>(at);
        if self.big_endian {
            u32::from_be_bytes(raw)
        } else {
            u32::from_le_bytes(raw)
        }
    }

    pub fn i32(&self, at: usize) -> i32 {
        self.u32(at) as i32
    }

    pub fn f32(&self, at: usize) -> f64 {
        f32::from_bits(self.u32(at)) as f64
    }

    pub fn f64(&self, at: usize) -> f64 {
        let raw = self.array::<8>(at);
        if self.big_endian {
            f64::from_be_bytes(raw)
        } else {
            f64::from_le_bytes(raw)
        }
    }

    pub fn i16(&self, at: usize) -> i16 {
        let raw = self.array::<2>(at);
        if self.big_endian {
            i16::from_be_bytes(raw)
        } else {
            i16::from_le_bytes(raw)
        }
    }

    pub fn u16(&self, at: usize) -> u16 {
        self.i16(at) as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::pose::{Attitude, Position};

    fn update(lat: f64, pitch: f64) -> Update {
        Update {
            track: Some(Track {
                position: Position { lat_deg: lat, lon_deg: 10.0, alt_m: 100.0 },
                velocity_ned: Some([50.0, 0.0, 0.0]),
                vertical_known: true,
            }),
            turning: Some(Turning {
                attitude: Attitude { heading_deg: 10.0, pitch_deg: pitch, roll_deg: 0.0 },
                rates_dps: None,
            }),
            ..Update::default()
        }
    }

    #[test]
    fn impossible_and_non_finite_updates_are_refused() {
        assert_eq!(check(&update(45.0, 5.0)), Ok(()));
        assert_eq!(check(&update(90.5, 5.0)), Err(Ignored::OutOfRange));
        assert_eq!(check(&update(45.0, 91.0)), Err(Ignored::OutOfRange));
        assert_eq!(check(&update(f64::NAN, 5.0)), Err(Ignored::NotFinite));
        assert_eq!(check(&update(45.0, f64::INFINITY)), Err(Ignored::NotFinite));
        let mut fast = update(45.0, 0.0);
        fast.track.as_mut().unwrap().velocity_ned = Some([2000.0, 0.0, 0.0]);
        assert_eq!(check(&fast), Err(Ignored::OutOfRange));
    }

    #[test]
    fn merging_keeps_the_later_parts() {
        let mut a = update(45.0, 1.0);
        let b = Update { position_valid: Some(false), ..Update::default() };
        a.merge(b);
        assert!(a.track.is_some() && a.position_valid == Some(false));
        assert!(Update::default().is_empty() && !a.is_empty());
    }
}
