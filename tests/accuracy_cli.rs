//! `ridgeline accuracy` as a user runs it: over an imported terrain it
//! prints the JSON report with every field the issue names, writes the heat
//! map, confirms the bound, and refuses impossible options by name.

use std::path::Path;
use std::process::{Command, Output};

use testkit::fresh_dir;

fn ridgeline(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ridgeline")).args(args).output().expect("run ridgeline")
}

fn import(cache: &Path) {
    let out = ridgeline(&["import", "--synthetic", "257", "--out", cache.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn accuracy_json_reports_the_measured_error_and_writes_the_heat_map() {
    let dir = fresh_dir("cli-accuracy");
    let cache = dir.join("terrain");
    import(&cache);
    let out_dir = dir.join("out");
    let args = [
        "accuracy",
        "--dataset",
        cache.to_str().unwrap(),
        "--views",
        "2",
        "--size",
        "160x90",
        "--tau",
        "2",
        "--json",
        "--out",
    ];
    let run = Command::new(env!("CARGO_BIN_EXE_ridgeline"))
        .args(args)
        .arg(&out_dir)
        .output()
        .expect("run ridgeline");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let json: serde_json::Value = serde_json::from_slice(&run.stdout).expect("--json prints JSON");
    for field in [
        "tau_px",
        "p50_px",
        "p99_px",
        "p999_px",
        "max_px",
        "coverage_mismatch",
        "triangles_lod",
        "triangles_truth",
        "views",
    ] {
        assert!(json[field].is_number(), "{field} missing in {json}");
    }
    assert_eq!(json["views"], 2);
    assert!(json["p999_px"].as_f64().unwrap() <= 2.0, "the bound holds: {json}");
    assert!(
        json["triangles_truth"].as_f64().unwrap() >= json["triangles_lod"].as_f64().unwrap() / 2.0
    );
    let heat_map = image::open(out_dir.join("heat_map.png")).expect("heat map written");
    assert_eq!((heat_map.width(), heat_map.height()), (160, 90));
    assert!(out_dir.join("accuracy.json").is_file());
}

#[test]
fn accuracy_refuses_impossible_options_by_name() {
    for (args, named) in [
        (["accuracy", "--tau", "NaN"], "--tau"),
        (["accuracy", "--tau", "0"], "--tau"),
        (["accuracy", "--fov", "180"], "--fov"),
        (["accuracy", "--backend", "window"], "--backend window"),
        (["accuracy", "--triangle-budget", "0"], "--triangle-budget"),
        (["accuracy", "--frame-ms", "NaN"], "--frame-ms"),
        (["accuracy", "--frame-ms", "-2"], "--frame-ms"),
        (["accuracy", "--frame-ms", "0"], "--frame-ms"),
        (["accuracy", "--max-speed", "-1"], "--max-speed"),
        (["accuracy", "--max-speed", "inf"], "--max-speed"),
    ] {
        let out = ridgeline(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(named), "{args:?}: {stderr}");
    }
}
