//! A camera path: poses at strictly increasing times, sampled by interpolation.

use glam::DVec3;

use crate::earth::GridPlacement;

use super::columns::{Column, ValueProblem};
use super::pose::{normalize_heading, Pose};

/// A pose at a time (seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Waypoint {
    /// Time, seconds.
    pub t: f64,
    /// Where the aircraft is and how it is turned at `t`.
    pub pose: Pose,
}

/// Poses at strictly increasing times; at least one.
///
/// Invariants (checked by [`FlightPath::new`] and the CSV reader): every value
/// is finite and inside its [`Column`]'s range, and `t` strictly increases.
#[derive(Clone, Debug, PartialEq)]
pub struct FlightPath {
    waypoints: Vec<Waypoint>,
    /// What the CSV reader did with the rows' longitudes, when it moved any.
    longitude_note: Option<String>,
}

/// Why waypoints do not make a path.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InvalidPath {
    /// No waypoints were given.
    #[error("a camera path needs at least one waypoint")]
    Empty,
    /// A waypoint value is not finite or outside its column's range.
    #[error("waypoint {index}, `{}`: {problem}", column.name())]
    Value {
        /// Position of the waypoint, from 0.
        index: usize,
        /// The column of the value.
        column: Column,
        /// What is wrong with it.
        problem: ValueProblem,
    },
    /// A waypoint's time is not later than the one before it.
    #[error("waypoint {index}: time {t} s does not come after the previous {previous} s")]
    TimeNotIncreasing {
        /// Position of the waypoint, from 0.
        index: usize,
        /// Its time, seconds.
        t: f64,
        /// The previous waypoint's time, seconds.
        previous: f64,
    },
}

impl FlightPath {
    /// A path through `waypoints`, refusing NaN, infinities, values outside
    /// their column's range and times that do not strictly increase.
    pub fn new(waypoints: Vec<Waypoint>) -> Result<Self, InvalidPath> {
        if waypoints.is_empty() {
            return Err(InvalidPath::Empty);
        }
        for (index, waypoint) in waypoints.iter().enumerate() {
            for (column, value) in waypoint_values(waypoint) {
                column.check(value).map_err(|problem| InvalidPath::Value {
                    index,
                    column,
                    problem,
                })?;
            }
        }
        for (index, pair) in waypoints.windows(2).enumerate() {
            if pair[1].t <= pair[0].t {
                return Err(InvalidPath::TimeNotIncreasing {
                    index: index + 1,
                    t: pair[1].t,
                    previous: pair[0].t,
                });
            }
        }
        Ok(FlightPath { waypoints, longitude_note: None })
    }

    /// For readers that have checked every value themselves.
    pub(super) fn from_checked(waypoints: Vec<Waypoint>) -> Self {
        debug_assert!(!waypoints.is_empty());
        debug_assert!(waypoints.windows(2).all(|pair| pair[0].t < pair[1].t));
        debug_assert!(waypoints
            .iter()
            .all(|w| waypoint_values(w).iter().all(|(_, v)| v.is_finite())));
        FlightPath { waypoints, longitude_note: None }
    }

    /// This path, saying what became of its rows' longitudes.
    pub(super) fn with_longitude_note(self, note: Option<String>) -> Self {
        FlightPath { longitude_note: note, ..self }
    }

    /// What the CSV reader did with the rows' longitudes (normalised into
    /// the grid's turn, followed across a wrapping grid's seam), if anything.
    pub fn longitude_note(&self) -> Option<&str> {
        self.longitude_note.as_deref()
    }

    /// The waypoints, in time order.
    pub fn waypoints(&self) -> &[Waypoint] {
        &self.waypoints
    }

    /// Time of the first waypoint, seconds.
    pub fn start_time(&self) -> f64 {
        self.waypoints[0].t
    }

    /// Time of the last waypoint, seconds.
    pub fn end_time(&self) -> f64 {
        self.waypoints[self.waypoints.len() - 1].t
    }

    /// Seconds from the first waypoint to the last.
    pub fn duration(&self) -> f64 {
        self.end_time() - self.start_time()
    }

    /// The fastest the camera moves, metres a second: positions are
    /// interpolated linearly, so the fastest leg's speed (0 for one waypoint).
    pub fn max_speed(&self) -> f64 {
        self.max_speed_over(None)
    }

    /// [`Self::max_speed`] on the earth where `placement` places the chart
    /// (`None`: in the chart). A leg straight in the chart is not straight
    /// on the earth, nor at one speed: its speed is taken as the fastest of
    /// 32 pieces' (ECEF chords over their time). The chart's scale differs
    /// from the earth's by up to 2 to 1 (a global grid at 60 N), so a
    /// display drawn on the ellipsoid declares its valid life's travel
    /// from this.
    pub fn max_speed_over(&self, placement: Option<&GridPlacement>) -> f64 {
        const PIECES: usize = 32;
        let leg = |pair: &[Waypoint]| {
            let (a, b) = (pair[0].pose.position, pair[1].pose.position);
            let dt = pair[1].t - pair[0].t;
            let Some(placement) = placement else { return a.distance(b) / dt };
            let at = |s: f64| {
                let p = a.lerp(b, s);
                placement.ecef_of_chart([p.x, p.y], p.z)
            };
            (0..PIECES)
                .map(|k| at(k as f64 / PIECES as f64).distance(at((k + 1) as f64 / PIECES as f64)))
                .fold(0.0, f64::max)
                * PIECES as f64
                / dt
        };
        self.waypoints.windows(2).map(leg).fold(0.0, f64::max)
    }

    /// The most the camera moves between two of `n` evenly spaced frames
    /// ([`FlightPath::frame_times`]), metres, with a margin of one part in a
    /// thousand against rounding: the valid life's declared travel.
    pub fn max_travel_per_frame(&self, n: u32) -> f64 {
        self.max_travel_per_frame_over(n, None)
    }

    /// [`Self::max_travel_per_frame`] on the earth where `placement` places
    /// the chart ([`Self::max_speed_over`]).
    pub fn max_travel_per_frame_over(&self, n: u32, placement: Option<&GridPlacement>) -> f64 {
        let interval = self.duration() / n.saturating_sub(1).max(1) as f64;
        self.max_speed_over(placement) * interval * 1.001
    }

    /// The pose at time `t`, interpolated between the waypoints around it (see
    /// [`Pose::lerp`]). Times before the first or after the last waypoint give
    /// that waypoint's pose; a NaN time gives the first.
    pub fn sample(&self, t: f64) -> Pose {
        let t = if t.is_nan() {
            self.start_time()
        } else {
            t.clamp(self.start_time(), self.end_time())
        };
        // First waypoint strictly after t; 0 is impossible once t is clamped.
        let after = self.waypoints.partition_point(|w| w.t <= t);
        let Some(next) = self.waypoints.get(after) else {
            return with_normalized_heading(self.waypoints[after - 1].pose);
        };
        let previous = &self.waypoints[after - 1];
        let s = (t - previous.t) / (next.t - previous.t);
        previous.pose.lerp(&next.pose, s)
    }

    /// `n` evenly spaced times from the first waypoint's to the last's, both
    /// included (one frame: the first time; none: nothing).
    pub fn frame_times(&self, n: u32) -> impl Iterator<Item = f64> + use<> {
        let (start, end) = (self.start_time(), self.end_time());
        let last = n.saturating_sub(1).max(1) as f64;
        (0..n).map(
            move |k| if k as f64 == last { end } else { start + (end - start) * (k as f64 / last) },
        )
    }
}

fn with_normalized_heading(pose: Pose) -> Pose {
    Pose { heading_deg: normalize_heading(pose.heading_deg), ..pose }
}

/// The waypoint's values with the column that bounds each.
fn waypoint_values(waypoint: &Waypoint) -> [(Column, f64); 7] {
    let Pose { position: DVec3 { x, y, z }, heading_deg, pitch_deg, roll_deg } = waypoint.pose;
    [
        (Column::Time, waypoint.t),
        (Column::X, x),
        (Column::Y, y),
        (Column::Altitude, z),
        (Column::Heading, heading_deg),
        (Column::Pitch, pitch_deg),
        (Column::Roll, roll_deg),
    ]
}
