//! `ridgeline fly` as a user runs it headless: the built-in cruise flight
//! over the procedural earth writes a `stats.json` that names the flight,
//! the default memory budget and what the run took of it, and every frame's
//! bound; a budget the display cannot work in, and `--frame-ms`'s target,
//! are handled by name.

use std::collections::BTreeSet;
use std::path::Path;

use ridgeline::pipeline::FrameStats;
use serde_json::Value;
use testkit::cli::{Ridgeline, Run};
use testkit::fresh_dir;

/// Headless `ridgeline fly` writing into `out`, one snapshot.
fn fly(out: &Path) -> Run {
    Ridgeline::new(env!("CARGO_BIN_EXE_ridgeline"))
        .args(["fly", "--backend", "egl", "--snapshots", "1", "--out"])
        .arg(out)
}

fn stats(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("stats.json")).expect("stats.json written");
    serde_json::from_str(&text).expect("stats.json is JSON")
}

#[test]
fn cruise_over_the_procedural_earth_reports_its_flight_memory_and_bound() {
    let out = fresh_dir("cli-fly-cruise");
    let args =
        ["--dataset", "procedural", "--flight", "cruise", "--frames", "4", "--size", "160x90"];
    fly(&out).args(args).ok();
    let json = stats(&out);
    assert_eq!(json["flight"], "cruise");
    let memory = &json["memory"];
    let budget = memory["budget_bytes"].as_u64().expect("the default budget is set");
    assert_eq!(budget, 64 << 20, "{memory}");
    let own = memory["own_bytes"].as_u64().unwrap();
    assert!(own <= budget, "own {own} bytes exceed the default budget: {memory}");
    assert!(memory["atlas_budget_bytes"].as_u64().unwrap() > 0, "{memory}");
    let frames = json["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 4);
    let mut loosened = 0;
    for frame in frames {
        assert_keys_are_frame_stats(frame);
        let bound = frame["bound_px"].as_f64().expect("bound_px per frame");
        let tau = frame["tau_px"].as_f64().unwrap();
        assert!(bound >= tau, "the bound is never below the achieved tau: {frame}");
        loosened += (bound > frame["tau_requested_px"].as_f64().unwrap()) as u64;
        assert!(frame["nodes_over_budget"].is_u64() && frame["fallback_tiles"].is_u64());
    }
    assert_eq!(json["tau_loosened_frames"], loosened);
}

/// The keys a frame row adds to `FrameStats`' own: its number and time
/// (`Row`), and where the aircraft was (`FrameRecord`).
const ROW_KEYS: [&str; 5] = ["frame", "t", "pose", "input", "wall_time"];

/// A frame of stats.json has exactly `FrameStats`' serde keys, nested
/// objects included, besides `ROW_KEYS`: a key written by hand beside
/// them, or one renamed or dropped, fails here.
fn assert_keys_are_frame_stats(frame: &Value) {
    let own = serde_json::to_value(FrameStats::default()).expect("FrameStats serialises");
    let mut expected = keys(&own);
    expected.extend(ROW_KEYS.map(String::from));
    assert_eq!(keys(frame), expected, "{frame}");
    for (key, value) in own.as_object().expect("an object") {
        if value.is_object() {
            assert_eq!(keys(&frame[key]), keys(value), "{key} in {frame}");
        }
    }
}

fn keys(value: &Value) -> BTreeSet<String> {
    value.as_object().map(|o| o.keys().cloned().collect()).unwrap_or_default()
}

#[test]
fn without_a_budget_stats_json_says_so() {
    let out = fresh_dir("cli-fly-no-budget");
    fly(&out).args(["--frames", "2", "--memory-mb", "0", "--size", "160x90"]).ok();
    let memory = &stats(&out)["memory"];
    assert!(memory["budget_bytes"].is_null() && memory["atlas_budget_bytes"].is_null(), "{memory}");
}

#[test]
fn budgets_the_display_cannot_work_in_are_refused_by_name() {
    let out = fresh_dir("cli-fly-refused");
    for (args, says) in [
        (&["--memory-mb", "2"][..], "--memory-mb 2 must be between"),
        (&["--memory-mb", "9", "--size", "1280x720"][..], "go to snapshots at 1280x720"),
        (&["--frame-ms", "0"][..], "--frame-ms 0 must be"),
        (&["--flight", "sideways"][..], "sideways"),
    ] {
        fly(&out).args(args).refused(&[says]);
    }
}

/// A budget too small for the data's nodes names the least that would do,
/// and that budget flies.
#[test]
fn a_refused_budget_names_one_that_flies() {
    let out = fresh_dir("cli-fly-least");
    let run = fly(&out).args(["--frames", "2", "--memory-mb", "8", "--size", "160x90"]);
    let text = run.refused(&[]).stderr();
    let least: u64 = text
        .split("need at least ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no least budget named: {text}"));
    // Headless snapshots at 160x90 take 8 bytes a pixel on top.
    let mb = (least + 8 * 160 * 90).div_ceil(1 << 20);
    let mb = mb.to_string();
    fly(&out).args(["--frames", "2", "--memory-mb", &mb, "--size", "160x90"]).ok();
}

#[test]
fn a_frame_time_target_is_recorded_and_every_frame_says_its_tau() {
    let out = fresh_dir("cli-fly-frame-ms");
    let run = fly(&out).args(["--frames", "6", "--frame-ms", "1", "--size", "160x90"]).ok();
    let json = stats(&out);
    assert_eq!(json["frame_ms_target"], 1.0);
    let frames = json["frames"].as_array().unwrap();
    // 1 ms is out of reach on any machine: the controller raises tau and says so.
    let last = frames.last().unwrap();
    assert!(last["tau_px"].as_f64().unwrap() > 1.0, "tau never rose: {last}");
    assert!(last["bound_px"].as_f64() > last["tau_requested_px"].as_f64(), "{last}");
    assert!(json["tau_loosened_frames"].as_u64() > Some(0), "{json}");
    let summary = run.stdout();
    assert!(summary.contains("LOOSENED"), "{summary}");
}
