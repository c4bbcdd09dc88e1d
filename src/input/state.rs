//! The live state: the newest position and attitude taken, when each came,
//! the source's validity flags, and what a frame at a given time makes of
//! them ([`LiveState::view`]): an extrapolated pose, or the reason the
//! display is stale.
//!
//! Staleness is decided per frame from the frame's own time: a frame drawn
//! `stale_ms` after the newest valid sample of either kind is stale (a
//! position reported once a second, GDL 90's, that second later), the
//! first such frame included, and the first frame after a valid sample
//! returns is live again. Nothing else is carried: recovery is automatic.

use std::time::{Duration, Instant};

use super::pose::{GeoPose, Track, Turning};
use super::update::{Ignored, Update, MAX_SPEED_MPS, MAX_VERTICAL_SPEED_MPS};

/// The shortest time a jump is judged over, seconds: two datagrams
/// received together (a burst after a network stall) may hold positions
/// that far apart in the source's time.
pub const MIN_JUMP_INTERVAL_S: f64 = 0.25;
/// Distance a position may move beyond what the speed allows, metres
/// (GDL 90's 2.4 m quantisation, rounding in the sources).
pub const JUMP_SLACK_M: f64 = 50.0;

/// Why the display is stale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StaleReason {
    /// No valid position and attitude have come yet.
    NoData,
    /// The newest valid sample is older than the stale time.
    Timeout,
    /// The source flags its position invalid.
    PositionInvalid,
    /// The source flags its attitude invalid.
    AttitudeInvalid,
}

impl StaleReason {
    /// The words on the failure flag.
    pub fn flag_text(self) -> &'static str {
        match self {
            StaleReason::NoData => "NO DATA",
            StaleReason::Timeout => "STALE DATA",
            StaleReason::PositionInvalid => "POSITION INVALID",
            StaleReason::AttitudeInvalid => "ATTITUDE INVALID",
        }
    }
}

/// What one frame makes of the live state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LiveView {
    /// Fresh, valid data: the pose extrapolated to the frame's time.
    Live {
        /// The pose at the frame's time.
        pose: GeoPose,
        /// Ground velocity north, east, down (m/s), when the source gave
        /// one with its vertical component.
        velocity_ned: Option<[f64; 3]>,
        /// Age of the newest sample at the frame's time, seconds.
        age_s: f64,
    },
    /// Stale or invalid: the terrain is withdrawn.
    Stale {
        /// Why.
        reason: StaleReason,
        /// Age of the newest sample, seconds (`None`: none came).
        age_s: Option<f64>,
    },
}

/// The newest data taken.
#[derive(Clone, Copy, Debug, Default)]
pub struct LiveState {
    track: Option<(Track, Instant)>,
    turning: Option<(Turning, Instant)>,
    position_valid: bool,
    attitude_valid: bool,
    /// The source's position report interval, seconds (0: streaming).
    position_interval: Duration,
    /// Samples taken (datagrams that changed the state).
    pub taken: u64,
}

impl LiveState {
    /// Takes `update`, received at `now`, unless its position jumps
    /// further from the last one than an aircraft flies in the time
    /// between. After a silence longer than `stale` the last position is
    /// not trusted to judge a jump (a simulator reset moves the aircraft).
    pub fn take(&mut self, update: &Update, now: Instant, stale: Duration) -> Result<(), Ignored> {
        if let (Some(new), Some((old, at))) = (&update.track, &self.track) {
            let dt = now.saturating_duration_since(*at);
            if dt <= stale && jumps(old, new, dt.as_secs_f64()) {
                return Err(Ignored::Jump);
            }
        }
        if let Some(track) = update.track {
            self.track = Some((track, now));
            self.position_valid = true;
        }
        if let Some(turning) = update.turning {
            self.turning = Some((turning, now));
            self.attitude_valid = true;
        }
        if let Some(valid) = update.position_valid {
            self.position_valid = valid;
        }
        if let Some(valid) = update.attitude_valid {
            self.attitude_valid = valid;
        }
        if let Some(interval) = update.position_interval_s.filter(|s| (0.0..=10.0).contains(s)) {
            self.position_interval = Duration::from_secs_f64(interval);
        }
        self.taken += 1;
        Ok(())
    }

    /// The newest position and attitude as received, with the time of the
    /// later one (for recording): `None` until both have come.
    pub fn sample(&self) -> Option<(GeoPose, Instant)> {
        let ((track, a), (turning, b)) = (self.track?, self.turning?);
        Some((GeoPose::new(track.position, turning.attitude), a.max(b)))
    }

    /// When the newest position and the newest attitude came.
    pub fn received(&self) -> (Option<Instant>, Option<Instant>) {
        (self.track.map(|(_, at)| at), self.turning.map(|(_, at)| at))
    }

    /// When the newest sample of either kind came.
    pub fn newest(&self) -> Option<Instant> {
        match (self.track, self.turning) {
            (Some((_, a)), Some((_, b))) => Some(a.max(b)),
            (Some((_, a)), None) | (None, Some((_, a))) => Some(a),
            (None, None) => None,
        }
    }

    /// What a frame drawn at `now` shows, with `stale` the stale time.
    pub fn view(&self, now: Instant, stale: Duration) -> LiveView {
        let age = |at: Instant| now.saturating_duration_since(at);
        let newest = self.newest().map(|at| age(at).as_secs_f64());
        let (Some((track, track_at)), Some((turning, turning_at))) = (self.track, self.turning)
        else {
            return LiveView::Stale { reason: StaleReason::NoData, age_s: newest };
        };
        let reason = if !self.position_valid {
            Some(StaleReason::PositionInvalid)
        } else if !self.attitude_valid {
            Some(StaleReason::AttitudeInvalid)
        } else if age(track_at) > stale + self.position_interval || age(turning_at) > stale {
            Some(StaleReason::Timeout)
        } else {
            None
        };
        if let Some(reason) = reason {
            return LiveView::Stale { reason, age_s: newest };
        }
        let position = track.at(age(track_at).as_secs_f64());
        let attitude = turning.at(age(turning_at).as_secs_f64());
        LiveView::Live {
            pose: GeoPose::new(position, attitude),
            velocity_ned: track.velocity_ned.filter(|_| track.vertical_known),
            age_s: newest.unwrap_or(0.0),
        }
    }
}

/// Whether `new` lies further from `old` than the fastest aircraft goes in
/// `dt_s` seconds (at least [`MIN_JUMP_INTERVAL_S`]), horizontally or
/// vertically.
fn jumps(old: &Track, new: &Track, dt_s: f64) -> bool {
    let dt = dt_s.max(MIN_JUMP_INTERVAL_S);
    let (a, b) = (&old.position, &new.position);
    let [east_per_deg, north_per_deg] = crate::geo::metres_per_degree(a.lat_deg);
    let north = (b.lat_deg - a.lat_deg) * north_per_deg;
    let east = super::pose::wrap_longitude(b.lon_deg - a.lon_deg) * east_per_deg;
    let horizontal = north.hypot(east);
    let vertical = (b.alt_m - a.alt_m).abs();
    horizontal > MAX_SPEED_MPS * dt + JUMP_SLACK_M
        || vertical > MAX_VERTICAL_SPEED_MPS * dt + JUMP_SLACK_M
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::pose::{Attitude, Position};

    const STALE: Duration = Duration::from_millis(1000);

    fn update(lat: f64) -> Update {
        Update {
            track: Some(Track {
                position: Position { lat_deg: lat, lon_deg: 40.0, alt_m: 2000.0 },
                velocity_ned: Some([100.0, 0.0, 0.0]),
                vertical_known: true,
            }),
            turning: Some(Turning { attitude: Attitude::default(), rates_dps: None }),
            ..Update::default()
        }
    }

    #[test]
    fn a_frame_goes_stale_the_moment_the_data_are_older_than_the_stale_time() {
        let mut state = LiveState::default();
        let t0 = Instant::now();
        assert!(matches!(
            state.view(t0, STALE),
            LiveView::Stale { reason: StaleReason::NoData, age_s: None }
        ));
        state.take(&update(39.0), t0, STALE).unwrap();
        let ms = |n: u64| t0 + Duration::from_millis(n);
        let LiveView::Live { pose, age_s, .. } = state.view(ms(200), STALE) else { panic!() };
        assert!((age_s - 0.2).abs() < 1e-9);
        assert!(pose.lat_deg > 39.0, "extrapolated north");
        assert!(matches!(state.view(ms(1000), STALE), LiveView::Live { .. }));
        assert!(matches!(
            state.view(ms(1001), STALE),
            LiveView::Stale { reason: StaleReason::Timeout, .. }
        ));
        state.take(&update(39.0), ms(1500), STALE).unwrap();
        assert!(matches!(state.view(ms(1500), STALE), LiveView::Live { .. }), "recovers by itself");
    }

    #[test]
    fn jumps_are_refused_until_the_data_were_stale_anyway() {
        let mut state = LiveState::default();
        let t0 = Instant::now();
        state.take(&update(39.0), t0, STALE).unwrap();
        let later = t0 + Duration::from_millis(100);
        // 0.01 degree (1.1 km) in 0.1 s: 11 km/s.
        assert_eq!(state.take(&update(39.01), later, STALE), Err(Ignored::Jump));
        assert_eq!(
            state.take(&update(39.0005), later, STALE),
            Ok(()),
            "55 m is a fast aircraft's 0.1 s"
        );
        let reset = t0 + Duration::from_millis(1200);
        assert_eq!(state.take(&update(45.0), reset, STALE), Ok(()), "a reposition after silence");
    }

    #[test]
    fn invalid_flags_make_the_display_stale() {
        let mut state = LiveState::default();
        let t0 = Instant::now();
        state.take(&update(39.0), t0, STALE).unwrap();
        let flag = Update { position_valid: Some(false), ..Update::default() };
        state.take(&flag, t0, STALE).unwrap();
        assert!(matches!(
            state.view(t0, STALE),
            LiveView::Stale { reason: StaleReason::PositionInvalid, .. }
        ));
        state.take(&update(39.0), t0, STALE).unwrap();
        assert!(matches!(state.view(t0, STALE), LiveView::Live { .. }));
    }
}
