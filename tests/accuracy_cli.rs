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

/// A UTM grid (zone 37 N, 60 m posts, hills) 3.3 degrees east of its
/// central meridian, where grid north is 2.1 degrees off true north,
/// written as a GeoTIFF tagged EPSG:32637 and imported.
fn import_utm(dir: &Path) -> std::path::PathBuf {
    use testkit::dem::{projected_keys, write_tiff_strips, GeoTags};
    use tiff::encoder::{colortype, Compression, Predictor};
    const SIDE: u32 = 257;
    const SPACING: f64 = 60.0;
    let heights: Vec<f32> = (0..SIDE * SIDE)
        .map(|k| ((k % SIDE) as f32, (k / SIDE) as f32))
        .map(|(c, r)| 1500.0 + 300.0 * (c / 19.0).sin() * (r / 23.0).cos() + 2.0 * c)
        .collect();
    let geo = GeoTags {
        scale: Some([SPACING, SPACING, 0.0]),
        tiepoint: Some([0.0, 0.0, 0.0, 780_000.0, 4_400_000.0, 0.0]),
        keys: projected_keys(32637),
        ..GeoTags::default()
    };
    let tif = dir.join("utm37n.tif");
    let none = (Compression::Uncompressed, Predictor::None);
    write_tiff_strips::<colortype::Gray32Float>(
        &tif, [SIDE; 2], &heights, none.0, none.1, 16, &geo,
    );
    let cache = dir.join("utm");
    let args = ["import", "--out", cache.to_str().unwrap(), tif.to_str().unwrap()];
    let out = ridgeline(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    cache
}

/// A projected grid is drawn where the earth has it (issue 26): over the
/// UTM grid above, the geodetic truth's p99.9 holds tau on the ellipsoid;
/// in the chart (`--chart`, the projection's plane, headings from grid
/// north) it does not, the picture turned by the grid's convergence.
#[test]
fn a_utm_grid_holds_the_bound_against_the_earth_on_the_ellipsoid() {
    let dir = fresh_dir("cli-accuracy-utm");
    let cache = import_utm(&dir);
    let earth_p999 = |chart: bool| {
        let mut args = vec!["accuracy", "--dataset", cache.to_str().unwrap()];
        args.extend(["--views", "2", "--size", "320x180", "--earth-stride", "2", "--json"]);
        if chart {
            args.push("--chart");
        }
        let out = ridgeline(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        assert_eq!(json["earth"]["holes"], 0, "{json}");
        json["earth"]["p999_px"].as_f64().expect("the earth's p99.9")
    };
    let (ellipsoid, chart) = (earth_p999(false), earth_p999(true));
    println!(
        "against the earth, p99.9: {ellipsoid:.3} px on the ellipsoid, {chart:.3} px in the chart"
    );
    assert!(ellipsoid <= 1.0, "on the ellipsoid: {ellipsoid} px");
    assert!(chart > 2.0, "the chart's turn shows: {chart} px");
}
