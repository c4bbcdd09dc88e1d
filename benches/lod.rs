//! Run time against measured error (issue 5): the built-in approach over the
//! built-in terrain at 1280x720, headless EGL, for a sweep of the error bound
//! tau (0.5 to 8 px) and of the tile parameters (grid size, morph range,
//! Kühnert's view distance). Every point records, in one run:
//! - at N views along the approach (16, or 4 with `--quick`): the measured
//!   per-pixel error of `ridgeline accuracy` (p99, p99.9), surface triangles,
//!   and the frame time of the LOD display and of the brute-force
//!   full-resolution mesh drawn in the same context right after it;
//! - over consecutive frames 1/10 s apart from mid-approach (60, or 20 with
//!   `--quick`): draw calls, bytes uploaded and transfers per frame, CPU
//!   milliseconds per frame (clipmap, selection, tiles, draw list) and frame
//!   milliseconds to glFinish; and the same frames drawn by plain Chunked LOD
//!   (one vertex buffer, upload and bind per tile: `ChunkedBaseline`) from a
//!   display of its own, for the tau points.
//!
//! Ratios against the brute-force mesh are per view, so machine noise hits
//! both sides alike. Prints the table, writes target/bench/lod.json and
//! target/bench/lod.svg (frame time against measured p99 error).

mod support;

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glam::UVec2;
use ridgeline::camera::Camera;
use ridgeline::clipmap::LoaderMode;
use ridgeline::dataset;
use ridgeline::display::measure::{measure_flight, AccuracyRun};
use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::flight::{default_flight, FlightPath};
use ridgeline::gl::{
    BaselineFrameStats, ChunkedBaseline, GlBackend, TruthMesh, TruthPass, TruthRegion,
};
use ridgeline::lod::LodConfig;
use ridgeline::node::NodeSource;
use ridgeline::pipeline::FrameStats;
use ridgeline::pyramid::{Pyramid, Silent};
use ridgeline::render::RenderBackend;
use ridgeline::scene::TerrainSummary;
use serde_json::json;
use support::{print_table, write_json, write_svg, BenchArgs, Panel, Series};

const SIZE: UVec2 = UVec2::new(1280, 720);
const FOV_X_DEG: f64 = 60.0;
/// Frames of the flight part are this often: a low-power board's rate.
const FLIGHT_RATE_HZ: f64 = 10.0;

/// One point of the sweep.
#[derive(Clone, Copy, serde::Serialize)]
struct Point {
    name: &'static str,
    #[serde(flatten)]
    lod: LodConfigRow,
    /// Also draw the flight by plain Chunked LOD.
    baseline: bool,
}

#[derive(Clone, Copy, serde::Serialize)]
struct LodConfigRow {
    tau_px: f64,
    grid_size: u32,
    morph_range: f64,
    view_distance: f64,
}

impl Point {
    fn new(
        name: &'static str,
        tau_px: f64,
        alter: impl Fn(&mut LodConfig),
        baseline: bool,
    ) -> Point {
        let mut lod = LodConfig { tau_px, ..LodConfig::default() };
        alter(&mut lod);
        let row = LodConfigRow {
            tau_px,
            grid_size: lod.grid_size,
            morph_range: lod.morph_range,
            view_distance: lod.view_distance,
        };
        Point { name, lod: row, baseline }
    }

    fn apply(&self, lod: &mut LodConfig) {
        lod.tau_px = self.lod.tau_px;
        lod.grid_size = self.lod.grid_size;
        lod.morph_range = self.lod.morph_range;
        lod.view_distance = self.lod.view_distance;
    }
}

fn points() -> Vec<Point> {
    let keep = |_: &mut LodConfig| {};
    let mut points: Vec<Point> = [0.5, 1.0, 2.0, 4.0, 8.0]
        .into_iter()
        .map(|tau| Point::new("tau sweep", tau, keep, true))
        .collect();
    // Beyond the sweep: how low the frame time goes as triangles vanish (the fill floor).
    for tau in [16.0, 64.0] {
        points.push(Point::new("coarse", tau, keep, false));
    }
    for tau in [1.0, 4.0] {
        points.push(Point::new("grid 16", tau, |l| l.grid_size = 16, false));
        points.push(Point::new("grid 64", tau, |l| l.grid_size = 64, false));
    }
    points.push(Point::new("morph 0.15", 4.0, |l| l.morph_range = 0.15, false));
    points.push(Point::new("morph 0.5", 4.0, |l| l.morph_range = 0.5, false));
    points.push(Point::new("view distance 2", 4.0, |l| l.view_distance = 2.0, false));
    points.push(Point::new("view distance 5", 4.0, |l| l.view_distance = 5.0, false));
    points
}

/// Means over a flight of consecutive frames.
#[derive(Clone, Copy, Default, serde::Serialize)]
struct FlightRow {
    frames: usize,
    triangles: f64,
    draw_calls: f64,
    bytes_uploaded: f64,
    transfers: f64,
    cpu_ms: f64,
    frame_ms: f64,
}

impl FlightRow {
    fn of(frames: &[FrameStats]) -> FlightRow {
        let n = frames.len().max(1) as f64;
        let mean = |f: &dyn Fn(&FrameStats) -> f64| frames.iter().map(f).sum::<f64>() / n;
        FlightRow {
            frames: frames.len(),
            triangles: mean(&|s| s.scene.triangles as f64),
            draw_calls: mean(&|s| s.draw_calls as f64),
            bytes_uploaded: mean(&|s| s.scene.bytes_uploaded as f64),
            transfers: mean(&|s| s.scene.transfers as f64),
            cpu_ms: mean(&|s| {
                s.clipmap_ms
                    + s.scene.cpu_ms.select_ms
                    + s.scene.cpu_ms.tiles_ms
                    + s.scene.cpu_ms.draw_list_ms
            }),
            frame_ms: mean(&|s| s.frame_ms),
        }
    }
}

/// Everything measured at one point.
#[derive(serde::Serialize)]
struct PointResult {
    point: Point,
    p99_px: f64,
    p999_px: f64,
    max_px: f64,
    coverage_mismatch: f64,
    /// Means over the views.
    triangles_lod: f64,
    triangles_truth: f64,
    lod_frame_ms: f64,
    truth_frame_ms: f64,
    /// Per-view truth/LOD ratios, averaged.
    truth_over_lod_triangles: f64,
    truth_over_lod_frame: f64,
    flight: FlightRow,
    /// Plain Chunked LOD over the same flight, and its uploads per frame.
    chunked: Option<FlightRow>,
    chunked_uploads_per_frame: Option<f64>,
    /// Clear and sky alone at the flight's first pose: the fill floor no
    /// triangle count goes below on this driver.
    sky_only_ms: f64,
}

fn main() {
    let args = BenchArgs::parse();
    let (view_count, flight_frames) = if args.quick { (4, 20) } else { (16, 60) };
    let pyramid =
        Arc::new(dataset::open(None, Path::new("cache"), &Silent).expect("the built-in terrain"));
    let layout = *pyramid.layout();
    let path = default_flight(&pyramid);
    let views: Vec<(f64, Camera)> =
        path.frame_times(view_count).map(|t| (t, camera_at(&path, t))).collect();
    let source: Arc<dyn NodeSource> = pyramid.clone();
    // As `ridgeline accuracy`: a window of level 0 around the views (a
    // layered pyramid's level 0 spans its whole base).
    let positions = views.iter().map(|(_, c)| [c.position.x, c.position.y]);
    let region = TruthRegion::around_positions(&layout, LodConfig::default().grid_size, positions);
    let mesh = TruthMesh::load(source.as_ref(), region).expect("truth mesh");
    let mut results = Vec::new();
    for point in points() {
        let result = measure_point(&point, &pyramid, &mesh, &path, &views, flight_frames);
        println!(
            "  {:<16} tau {:>3}: p99.9 {:.3} px, {:.0} triangles, {:.1} ms (truth {:.1} ms)",
            point.name,
            point.lod.tau_px,
            result.p999_px,
            result.triangles_lod,
            result.lod_frame_ms,
            result.truth_frame_ms
        );
        results.push(result);
    }
    report(&args, &results, view_count);
}

fn camera_at(path: &FlightPath, t: f64) -> Camera {
    path.sample(t).camera(FOV_X_DEG, [SIZE.x, SIZE.y])
}

fn display_for(point: &Point, pyramid: &Arc<Pyramid>) -> DisplayParts {
    let mut config = DisplayConfig::new(GlBackend::Egl, SIZE);
    point.apply(&mut config.scene.lod);
    config.fov_x_deg = FOV_X_DEG;
    config.loader = LoaderMode::Inline;
    config.load_budget = 64;
    let source: Arc<dyn NodeSource> = pyramid.clone();
    DisplayParts::open(&config, source, TerrainSummary::from_pyramid(pyramid.info()))
        .expect("headless EGL display")
}

fn measure_point(
    point: &Point,
    pyramid: &Arc<Pyramid>,
    mesh: &TruthMesh,
    path: &FlightPath,
    views: &[(f64, Camera)],
    flight_frames: u32,
) -> PointResult {
    let mut display = display_for(point, pyramid);
    let truth = TruthPass::new(display.context.gl(), mesh).expect("truth pass");
    let exact = |x: f64, y: f64| pyramid.exact_height(x, y);
    let run = measure_flight(&mut display, &truth, &exact, pyramid.layout().spacing_m, views)
        .expect("accuracy views");
    let (flight, _) = fly(&mut display, None, path, flight_frames);
    let sky_only_ms = sky_only(&mut display, &views[0].1);
    drop(truth);
    drop(display);
    let (chunked, chunked_uploads_per_frame) = if point.baseline {
        let mut display = display_for(point, pyramid);
        let mut baseline =
            ChunkedBaseline::new(display.context.gl(), point.lod.grid_size).expect("baseline");
        let (frames, transfers) = fly(&mut display, Some(&mut baseline), path, flight_frames);
        let n = transfers.len().max(1) as f64;
        let uploads = transfers.iter().map(|t| t.uploads as f64).sum::<f64>() / n;
        // The scene's own upload figures are what the batched renderer
        // would have sent; the baseline's are its per-tile uploads.
        let mut row = FlightRow::of(&frames);
        row.bytes_uploaded = transfers.iter().map(|t| t.bytes_uploaded as f64).sum::<f64>() / n;
        row.transfers = uploads;
        (Some(row), Some(uploads))
    } else {
        (None, None)
    };
    let mut result =
        summarise(point, &run, FlightRow::of(&flight), chunked, chunked_uploads_per_frame);
    result.sky_only_ms = sky_only_ms;
    result
}

/// Mean of 5 frames of clear and sky only, to glFinish, with the uniforms
/// of a frame drawn at `camera`.
fn sky_only(display: &mut DisplayParts, camera: &Camera) -> f64 {
    display.frame(camera).expect("frame");
    let frame = display.pipeline.draw_list().uniforms.expect("frame uniforms");
    let start = Instant::now();
    for _ in 0..5 {
        display.renderer.draw_background(&frame).expect("sky");
        display.renderer.finish();
    }
    start.elapsed().as_secs_f64() * 1e3 / 5.0
}

/// `frames` consecutive frames 1/10 s apart from mid-approach, by the
/// display or (given `baseline`) by plain Chunked LOD, after paging in and
/// drawing the first pose unrecorded, so both start from the same state.
fn fly(
    display: &mut DisplayParts,
    mut baseline: Option<&mut ChunkedBaseline>,
    path: &FlightPath,
    frames: u32,
) -> (Vec<FrameStats>, Vec<BaselineFrameStats>) {
    let start = path.start_time() + path.duration() / 2.0;
    let camera = |k: u32| camera_at(path, start + k as f64 / FLIGHT_RATE_HZ);
    display.pipeline.settle(&camera(0), 10_000).expect("settle");
    let mut stats = Vec::with_capacity(frames as usize);
    let mut transfers = Vec::with_capacity(frames as usize);
    for k in 0..=frames {
        let (frame, base) = match baseline.as_deref_mut() {
            Some(baseline) => {
                display.context.bind_target();
                let frame = display.pipeline.frame(&camera(k), baseline).expect("baseline frame");
                (frame, baseline.last_frame())
            }
            None => (display.frame(&camera(k)).expect("LOD frame"), BaselineFrameStats::default()),
        };
        if k > 0 {
            stats.push(frame);
            transfers.push(base);
        }
    }
    (stats, transfers)
}

fn summarise(
    point: &Point,
    run: &AccuracyRun,
    flight: FlightRow,
    chunked: Option<FlightRow>,
    uploads: Option<f64>,
) -> PointResult {
    let n = run.views.len().max(1) as f64;
    let mean = |f: &dyn Fn(&ridgeline::display::measure::ViewRow) -> f64| {
        run.views.iter().map(f).sum::<f64>() / n
    };
    PointResult {
        point: *point,
        p99_px: run.summary.p99_px,
        p999_px: run.summary.p999_px,
        max_px: run.summary.max_px,
        coverage_mismatch: run.coverage_mismatch,
        triangles_lod: mean(&|v| v.triangles_lod as f64),
        triangles_truth: mean(&|v| v.triangles_truth as f64),
        lod_frame_ms: mean(&|v| v.lod_frame_ms),
        truth_frame_ms: mean(&|v| v.truth_frame_ms),
        truth_over_lod_triangles: mean(&|v| {
            v.triangles_truth as f64 / v.triangles_lod.max(1) as f64
        }),
        truth_over_lod_frame: mean(&|v| v.truth_frame_ms / v.lod_frame_ms),
        flight,
        chunked,
        chunked_uploads_per_frame: uploads,
        sky_only_ms: 0.0,
    }
}

fn report(args: &BenchArgs, results: &[PointResult], views: u32) {
    let header = [
        "point",
        "tau",
        "p99 px",
        "p99.9 px",
        "triangles",
        "truth/LOD tri",
        "truth/LOD ms",
        "LOD ms",
        "truth ms",
        "draws",
        "KB up/frame",
        "xfers/frame",
        "CPU ms",
        "flight ms",
        "chunked ms",
        "chunked up/frame",
    ];
    let rows: Vec<Vec<String>> = results
        .iter()
        .map(|r| {
            let f = &r.flight;
            vec![
                r.point.name.to_string(),
                format!("{}", r.point.lod.tau_px),
                format!("{:.4}", r.p99_px),
                format!("{:.4}", r.p999_px),
                format!("{:.0}", r.triangles_lod),
                format!("{:.2}", r.truth_over_lod_triangles),
                format!("{:.2}", r.truth_over_lod_frame),
                format!("{:.1}", r.lod_frame_ms),
                format!("{:.1}", r.truth_frame_ms),
                format!("{:.0}", f.draw_calls),
                format!("{:.1}", f.bytes_uploaded / 1e3),
                format!("{:.2}", f.transfers),
                format!("{:.2}", f.cpu_ms),
                format!("{:.1}", f.frame_ms),
                r.chunked.map_or("-".into(), |c| format!("{:.1}", c.frame_ms)),
                r.chunked_uploads_per_frame.map_or("-".into(), |u| format!("{u:.1}")),
            ]
        })
        .collect();
    print_table(
        &format!("LOD against measured error: {views} views, 1280x720, built-in approach"),
        &header,
        &rows,
    );
    let brute = results.iter().map(|r| r.truth_frame_ms).sum::<f64>() / results.len().max(1) as f64;
    println!(
        "\n  brute force (every post, {} triangles): {brute:.1} ms per frame, 0 px by definition",
        results[0].triangles_truth
    );
    let floor = results.iter().map(|r| r.sky_only_ms).sum::<f64>() / results.len().max(1) as f64;
    println!("  clear and sky alone (the fill floor): {floor:.1} ms per frame");
    let json_path = write_json(
        "lod",
        &json!({ "quick": args.quick, "views": views, "size": [SIZE.x, SIZE.y], "brute_force_frame_ms": brute, "points": results }),
    );
    let sweep: Vec<&PointResult> = results.iter().filter(|r| r.point.baseline).collect();
    let errors = results.iter().map(|r| r.p99_px.max(1e-4));
    let (x_min, x_max) = errors.fold((f64::MAX, 0.0f64), |(lo, hi), e| (lo.min(e), hi.max(e)));
    let series = vec![
        Series {
            label: "UDLOD, tau 0.5..8 px".into(),
            points: sweep.iter().map(|r| (r.p99_px.max(1e-4), r.flight.frame_ms)).collect(),
        },
        Series {
            label: "plain Chunked LOD (same tiles)".into(),
            points: sweep
                .iter()
                .filter_map(|r| r.chunked.map(|c| (r.p99_px.max(1e-4), c.frame_ms)))
                .collect(),
        },
        Series {
            label: "tile parameters".into(),
            points: results
                .iter()
                .filter(|r| !r.point.baseline)
                .map(|r| (r.p99_px.max(1e-4), r.flight.frame_ms))
                .collect(),
        },
        // Its error is 0, off a log axis: drawn as a line across the plot.
        Series {
            label: "brute force (0 px), every post".into(),
            points: vec![(x_min, brute), (x_max, brute)],
        },
    ];
    let panel = Panel {
        title: "frame time against measured p99 error".into(),
        x_label: "measured p99 screen-space error (px; below 1e-4 drawn at 1e-4)".into(),
        y_label: "frame ms (to glFinish)".into(),
        log_x: true,
        log_y: false,
        series,
    };
    let svg = write_svg("lod", &[panel]);
    println!("\nwrote {} and {}", json_path.display(), svg.display());
}
