//! One frame's row of `stats.json` and what it records besides the
//! frame's own statistics: the pose drawn, the live input's state, the wall
//! time. Shared by path runs (`fly`) and live runs (`live`).

use std::time::{SystemTime, UNIX_EPOCH};

use ridgeline::input::{GeoPose, StaleReason};
use ridgeline::pipeline::FrameStats;

/// One row of stats.json: its keys are this struct's serde output, no
/// other (`tests/fly_cli.rs` checks them against `FrameStats`').
#[derive(serde::Serialize)]
pub struct Row {
    /// The frame's number, from 0.
    pub frame: u32,
    /// Seconds along the flight.
    pub t: f64,
    #[serde(flatten)]
    pub stats: FrameStats,
    /// `pose`, `input` and `wall_time`.
    #[serde(flatten)]
    pub record: FrameRecord,
}

/// What one frame of `stats.json` says about where the aircraft was and
/// where that came from (`pose`, `input`, `wall_time`).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct FrameRecord {
    /// The pose drawn, geodetic (`null`: withdrawn, or a dataset without
    /// a geographic frame).
    pub pose: Option<GeoPose>,
    /// The live input's state at the frame (`null`: a path was flown).
    pub input: Option<InputFrame>,
    /// Unix seconds when the frame was drawn.
    pub wall_time: f64,
}

/// A frame's view of the live input.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct InputFrame {
    /// The protocol.
    pub source: &'static str,
    /// Age of the newest sample when the frame was drawn, ms (`null`: none yet).
    pub age_ms: Option<f64>,
    /// Whether the terrain was withdrawn.
    pub stale: bool,
    /// Why, when it was.
    pub reason: Option<StaleReason>,
    /// Frame drawn minus newest sample received, ms.
    pub latency_ms: Option<f64>,
    /// Datagrams taken so far.
    pub taken: u64,
}

/// Unix time now, seconds.
pub fn wall_time() -> f64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}
