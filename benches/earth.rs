//! The frame's CPU cost on the ellipsoid against the chart (issue 26: within
//! 10 % on the default flight). Two pipelines over one terrain, one drawing
//! on the WGS 84 ellipsoid (`fly`'s default) and one in the chart
//! (`--chart`), fly the same flight through the null backend, frame by
//! frame interleaved (the order swapped every frame), so load on a shared
//! machine falls on both alike. Nodes are loaded inline before each frame
//! (`settle`, not timed), so both draw the same complete view; what is
//! compared is each stage's CPU time in `FrameStats` (clipmap, select,
//! tiles, draw list) and the process's CPU time over `frame()` (all
//! threads, the null backend included; no GL).
//!
//! Terrains: the built-in one (the default flight, node meshes, 1280x720,
//! tau 1) and a synthetic UTM grid (zone 37 N, 75 m posts, 77 km, 1.1 to
//! 2.0 degrees east of the central meridian), placed by its nodes' series,
//! flown by the same approach.
//!
//! Per terrain and stage: the mean ms a frame in each frame and their
//! ratio, and the median of the frames' paired ratios (robust to a frame
//! disturbed in one run only). `-- --quick`: 40 frames, one round; else
//! 120 frames, three rounds (fresh pipelines each). Prints a table, writes
//! target/bench/earth.json and target/bench/earth.svg (CPU ms per frame
//! along each flight).

mod support;

use std::sync::Arc;

use glam::UVec2;
use ridgeline::clipmap::LoaderMode;
use ridgeline::dem::ElevationGrid;
use ridgeline::display::DisplayConfig;
use ridgeline::earth::GridPlacement;
use ridgeline::flight::{builtin_approach_over, default_flight, FlightPath};
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::gl::GlBackend;
use ridgeline::node::NodeSource;
use ridgeline::pipeline::{FramePipeline, FrameStats};
use ridgeline::pyramid::{BuildOptions, Pyramid};
use ridgeline::render::{CostModel, NullBackend};
use ridgeline::scene::TerrainSummary;
use serde_json::json;
use support::{print_table, process_cpu_ns, write_json, write_svg, BenchArgs, Panel, Series};

const SIZE: UVec2 = UVec2::new(1280, 720);
const FOV_X_DEG: f64 = 60.0;
/// `fly`'s default memory budget.
const MEMORY_BYTES: u64 = 64 << 20;

/// One terrain and its flight.
struct Case {
    name: &'static str,
    source: Arc<dyn NodeSource>,
    summary: TerrainSummary,
    placement: GridPlacement,
    path: FlightPath,
}

/// A frame's CPU times, ms: clipmap, select, tiles, draw list, and the
/// process's CPU time over the whole `frame()`.
#[derive(Clone, Copy, Default)]
struct Times([f64; 5]);

const STAGES: [&str; 5] = ["clipmap", "select", "tiles", "draw list", "frame CPU"];

impl Times {
    fn of(stats: &FrameStats, cpu_ms: f64) -> Times {
        let c = &stats.scene.cpu_ms;
        Times([stats.clipmap_ms, c.select_ms, c.tiles_ms, c.draw_list_ms, cpu_ms])
    }
}

fn main() {
    let args = BenchArgs::parse();
    let (frames, rounds) = if args.quick { (40, 1) } else { (120, 3) };
    let cases = [builtin(), utm()];
    let mut rows = Vec::new();
    let mut report = Vec::new();
    let mut panels = Vec::new();
    for case in &cases {
        let (mut chart, mut earth) = (Vec::new(), Vec::new());
        for round in 0..rounds {
            let (c, e) = fly_interleaved(case, frames, round);
            chart.extend(c);
            earth.extend(e);
        }
        let mut stages = Vec::new();
        for (s, stage) in STAGES.iter().enumerate() {
            let mean = |t: &[Times]| t.iter().map(|t| t.0[s]).sum::<f64>() / t.len() as f64;
            let (mc, me) = (mean(&chart), mean(&earth));
            let mut paired: Vec<f64> = chart
                .iter()
                .zip(&earth)
                .filter(|(c, _)| c.0[s] > 0.0)
                .map(|(c, e)| e.0[s] / c.0[s])
                .collect();
            paired.sort_by(f64::total_cmp);
            let median = paired.get(paired.len() / 2).copied().unwrap_or(f64::NAN);
            rows.push(vec![
                case.name.to_string(),
                stage.to_string(),
                format!("{mc:.3}"),
                format!("{me:.3}"),
                format!("{:.3}", me / mc),
                format!("{median:.3}"),
            ]);
            stages.push(json!({
                "stage": stage, "chart_ms": mc, "ellipsoid_ms": me,
                "ratio_of_means": me / mc, "median_paired_ratio": median,
            }));
        }
        report.push(json!({
            "terrain": case.name, "frames": frames, "rounds": rounds, "stages": stages,
        }));
        let series = |label: &str, t: &[Times]| Series {
            label: label.to_string(),
            points: t[..frames as usize]
                .iter()
                .enumerate()
                .map(|(k, t)| (k as f64, t.0[4]))
                .collect(),
        };
        panels.push(Panel {
            title: format!("{}: CPU ms per frame (round 1)", case.name),
            x_label: "frame".into(),
            y_label: "ms".into(),
            log_x: false,
            log_y: false,
            series: vec![series("chart", &chart), series("ellipsoid", &earth)],
        });
    }
    print_table(
        "CPU ms per frame, ellipsoid against chart (means; paired: median of per-frame ratios)",
        &["terrain", "stage", "chart", "ellipsoid", "ratio", "paired"],
        &rows,
    );
    let json_path = write_json("earth", &json!({ "size": [SIZE.x, SIZE.y], "cases": report }));
    let svg_path = write_svg("earth", &panels);
    println!("\nwrote {} and {}", json_path.display(), svg_path.display());
}

/// Flies `case` once in both frames, interleaved; per frame their times.
fn fly_interleaved(case: &Case, frames: u32, round: u32) -> (Vec<Times>, Vec<Times>) {
    let mut chart = Flyer::new(case, None);
    let mut earth = Flyer::new(case, Some(case.placement));
    let (mut c, mut e) = (Vec::new(), Vec::new());
    for (k, t) in case.path.frame_times(frames).enumerate() {
        let camera = case.path.sample(t).camera(FOV_X_DEG, SIZE.into());
        if (k as u32 + round) % 2 == 0 {
            c.push(chart.frame(&camera));
            e.push(earth.frame(&camera));
        } else {
            e.push(earth.frame(&camera));
            c.push(chart.frame(&camera));
        }
    }
    (c, e)
}

/// A pipeline and its null backend.
struct Flyer {
    pipeline: FramePipeline,
    backend: NullBackend,
}

impl Flyer {
    fn new(case: &Case, earth: Option<GridPlacement>) -> Flyer {
        let mut config = DisplayConfig::new(GlBackend::Egl, SIZE);
        config.fov_x_deg = FOV_X_DEG;
        config.memory_budget_bytes = Some(MEMORY_BYTES);
        let travel = case.path.max_travel_per_frame_over(120, earth.as_ref());
        config.scene.lod.max_travel_m = Some(travel.max(1.0));
        config.scene.earth = earth;
        let mut pipeline = config.pipeline();
        pipeline.loader = LoaderMode::Inline;
        pipeline.load_budget = 4096;
        let pipeline = FramePipeline::new(&pipeline, case.source.clone(), case.summary.clone())
            .expect("pipeline");
        let backend =
            NullBackend::new(&pipeline.buffer_plan(), CostModel { vertex_arrays: true, sky: true });
        Flyer { pipeline, backend }
    }

    fn frame(&mut self, camera: &ridgeline::camera::Camera) -> Times {
        self.pipeline.settle(camera, 10_000).expect("settle");
        let start = process_cpu_ns();
        let stats = self.pipeline.frame(camera, &mut self.backend).expect("frame");
        let spent = start.zip(process_cpu_ns()).map(|(a, b)| b.saturating_sub(a));
        Times::of(&stats, spent.map_or(f64::NAN, |ns| ns as f64 / 1e6))
    }
}

/// The built-in terrain with its node meshes and the default flight.
fn builtin() -> Case {
    let pyramid = testkit::builtin_pyramid();
    let source = testkit::builtin_terrain();
    let summary = testkit::summary_of(&source);
    let info = pyramid.info();
    let placement = GridPlacement::new(&info.georef, info.layout.posts, info.layout.spacing_m);
    let path = default_flight(&pyramid);
    Case { name: "default flight", source, summary, placement, path }
}

/// A synthetic UTM grid (zone 37 N) with its node meshes, and the
/// built-in approach over it.
fn utm() -> Case {
    let posts = [1025u32, 1025];
    let (origin, spacing) = ([600_000.0, 4_350_000.0], [75.0, 75.0]);
    let heights = (0..posts[1])
        .flat_map(|j| (0..posts[0]).map(move |i| (i as f64 * 75.0, j as f64 * 75.0)))
        .map(|(x, y)| {
            let ridges = 600.0 * (x / 3100.0).sin() * (y / 4300.0).cos();
            (1500.0 + ridges + 150.0 * ((x + y) / 900.0).sin()) as f32
        })
        .collect();
    let georef = GeoRef { crs: Crs::Projected { epsg: Some(32637) }, origin, spacing };
    let grid =
        ElevationGrid { width: posts[0], height: posts[1], heights, georef, voids_filled: 0 };
    let dir = testkit::target_tmp().join("bench-earth-utm37n");
    let pyramid = match Pyramid::open(&dir) {
        Ok(pyramid) => pyramid,
        Err(_) => {
            std::fs::create_dir_all(&dir).expect("bench directory");
            testkit::pyramid::build_and_write(&grid, BuildOptions::default(), &dir);
            Pyramid::open(&dir).expect("the UTM pyramid")
        }
    };
    let pyramid = Arc::new(pyramid);
    let source = Arc::new(testkit::meshed(pyramid.clone()));
    let summary = testkit::summary_of(&source);
    let info = pyramid.info();
    let placement = GridPlacement::new(&info.georef, info.layout.posts, info.layout.spacing_m);
    assert!(placement.projected_lattice().is_some(), "placed by its projection");
    let height = |x: f64, y: f64| pyramid.exact_height(x, y).unwrap_or(0.0);
    let (area_origin, extent) = pyramid.finest_area_m();
    let path = builtin_approach_over(area_origin, extent, &height);
    Case { name: "UTM 37 N grid", source, summary, placement, path }
}
