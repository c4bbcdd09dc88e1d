//! What the LOD display buys: frame time and triangles of the default flight
//! (the built-in approach over the built-in terrain, 1280x720, headless EGL)
//! against a brute-force full-resolution mesh of the same views, drawn in the
//! same context and interleaved view by view (the order alternates), so the
//! ratios come from one run. Frames are timed up to glFinish.
//!
//! Two parts:
//! - views: N poses evenly spaced along the approach (60, or 12 with
//!   `--quick`); before each the clipmap is settled (paging is timed apart),
//!   then the LOD frame and the truth frame are drawn and read back, and the
//!   share of pixels that differ is kept as a check that both show the same
//!   view;
//! - display rate: consecutive frames 1/60 s apart from the middle of the
//!   approach, LOD only, loading on the loader thread as `fly` does, for the
//!   CPU cost of the clipmap update and of tiling per displayed frame.
//!
//! `-- --tau PX` sets the screen-space error bound (default 1 px, the
//! display's). Prints tables, writes target/bench/render.json and
//! target/bench/render.svg.

mod support;

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glam::UVec2;
use image::RgbaImage;
use ridgeline::camera::Camera;
use ridgeline::dataset;
use ridgeline::display::measure::draw_truth;
use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::flight::{default_flight, FlightPath};
use ridgeline::gl::{GlBackend, TruthFrameStats, TruthMesh, TruthPass, TruthRegion};
use ridgeline::node::NodeSource;
use ridgeline::pipeline::FrameStats;
use ridgeline::pyramid::Silent;
use ridgeline::scene::TerrainSummary;
use serde_json::json;
use support::{print_table, write_json, write_svg, BenchArgs, Panel, Series};

const SIZE: UVec2 = UVec2::new(1280, 720);
const FOV_X_DEG: f64 = 60.0;
const DISPLAY_RATE_HZ: f64 = 60.0;
/// A pixel differs when a channel differs by more than this (of 255).
const PIXEL_TOLERANCE: u8 = 16;

/// One view drawn both ways.
#[derive(serde::Serialize)]
struct ViewRow {
    t: f64,
    above_ground_m: f64,
    /// Paging in what the view wants before its LOD frame (not part of it).
    settle_ms: f64,
    lod: FrameStats,
    /// LOD tiles drawn per level, finest first.
    lod_tiles_per_level: Vec<usize>,
    /// LOD triangles without skirts.
    lod_surface_triangles: u64,
    truth: TruthFrameStats,
    /// Share of pixels whose colours differ by more than PIXEL_TOLERANCE.
    differing_pixels: f64,
}

/// Mean, median and 95th percentile.
#[derive(Clone, Copy, serde::Serialize)]
struct Spread {
    mean: f64,
    p50: f64,
    p95: f64,
}

impl Spread {
    fn of(values: impl Iterator<Item = f64>) -> Spread {
        let mut sorted: Vec<f64> = values.collect();
        sorted.sort_by(f64::total_cmp);
        let pick = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize];
        Spread {
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
            p50: pick(0.5),
            p95: pick(0.95),
        }
    }
}

fn main() {
    let args = BenchArgs::parse();
    let (view_count, live_frames) = if args.quick { (12, 12) } else { (60, 60) };
    let tau_px = tau_arg();
    let pyramid = dataset::open(None, Path::new("cache"), &Silent).expect("the built-in terrain");
    let layout = *pyramid.layout();
    let path = default_flight(&pyramid);
    let summary = TerrainSummary::from_pyramid(pyramid.info());
    let source: Arc<dyn NodeSource> = Arc::new(pyramid);
    let mut config = DisplayConfig::new(GlBackend::Egl, SIZE);
    config.scene.lod.tau_px = tau_px;
    config.fov_x_deg = FOV_X_DEG;
    let mut display =
        DisplayParts::open(&config, Arc::clone(&source), summary).expect("headless EGL display");
    let info = display.context.info().clone();
    let started = Instant::now();
    // As `ridgeline accuracy`: a window of level 0 around the flight (a
    // layered pyramid's level 0 spans its whole base: 55M posts for the
    // built-in terrain).
    let positions = path.frame_times(view_count).map(|t| {
        let p = path.sample(t).position;
        [p.x, p.y]
    });
    let region = TruthRegion::around_positions(&layout, config.scene.lod.grid_size, positions);
    let mesh = TruthMesh::load(source.as_ref(), region).expect("truth mesh");
    let truth = TruthPass::new(display.context.gl(), &mesh).expect("truth pass");
    let truth_build_ms = started.elapsed().as_secs_f64() * 1e3;
    println!(
        "render: {} on {} ({}); {}x{} posts, truth mesh {}x{} posts in {} chunks, built in {truth_build_ms:.0} ms",
        info.renderer, info.backend.name(), info.version, layout.posts[0], layout.posts[1],
        mesh.region.posts[0], mesh.region.posts[1], mesh.chunks.len()
    );
    let grid = config.scene.lod.grid_size as u64;
    let views =
        draw_views(&mut display, &truth, &path, source.as_ref(), view_count, 2 * grid * grid);
    let live = fly_at_display_rate(&mut display, &path, live_frames);
    report(&args, tau_px, &info, &mesh, truth_build_ms, &views, &live);
}

/// `--tau PX`, else the display's default.
fn tau_arg() -> f64 {
    let args: Vec<String> = std::env::args().collect();
    let given = args.iter().position(|a| a == "--tau").and_then(|k| args.get(k + 1));
    let tau = given.map_or(DisplayConfig::new(GlBackend::Egl, SIZE).scene.lod.tau_px, |text| {
        text.parse().unwrap_or_else(|_| panic!("--tau {text} is not a number of pixels"))
    });
    assert!(tau.is_finite() && tau > 0.0, "--tau {tau} must be above 0");
    tau
}

fn camera_at(path: &FlightPath, t: f64) -> Camera {
    path.sample(t).camera(FOV_X_DEG, [SIZE.x, SIZE.y])
}

fn draw_views(
    display: &mut DisplayParts,
    truth: &TruthPass,
    path: &FlightPath,
    source: &dyn NodeSource,
    count: u32,
    triangles_per_tile_surface: u64,
) -> Vec<ViewRow> {
    // Warm-up: the first draws compile shaders and fault in buffers.
    let first = camera_at(path, path.start_time());
    display.pipeline.settle(&first, 10_000).expect("settle");
    display.frame(&first).expect("warm-up LOD frame");
    draw_truth(display, truth).expect("warm-up truth frame");
    let mut rows = Vec::with_capacity(count as usize);
    for (k, t) in path.frame_times(count).enumerate() {
        let camera = camera_at(path, t);
        let settle = Instant::now();
        display.pipeline.settle(&camera, 10_000).expect("settle");
        let settle_ms = settle.elapsed().as_secs_f64() * 1e3;
        // The truth draws with the uniforms (near plane) of a LOD frame at
        // this pose: one untimed frame makes its tiles and uniforms.
        display.frame(&camera).expect("LOD frame");
        let draw_lod = |display: &mut DisplayParts| {
            let stats = display.frame(&camera).expect("LOD frame");
            (stats, display.context.read_pixels().expect("read LOD"))
        };
        let draw_truth = |display: &mut DisplayParts| {
            let stats = draw_truth(display, truth).expect("truth frame");
            (stats, display.context.read_pixels().expect("read truth"))
        };
        let ((lod, lod_image), (truth_stats, truth_image)) = if k % 2 == 0 {
            let lod = draw_lod(display);
            (lod, draw_truth(display))
        } else {
            let truth = draw_truth(display);
            (draw_lod(display), truth)
        };
        let mut lod_tiles_per_level = vec![0; source.layout().levels as usize];
        for tile in &display.pipeline.draw_list().tiles {
            lod_tiles_per_level[tile.key.level as usize] += 1;
        }
        let ground =
            source.exact_height(camera.position.x, camera.position.y).unwrap_or(0.0) as f64;
        rows.push(ViewRow {
            t,
            above_ground_m: camera.position.z - ground,
            settle_ms,
            lod,
            lod_tiles_per_level,
            lod_surface_triangles: lod.scene.tiles as u64 * triangles_per_tile_surface,
            truth: truth_stats,
            differing_pixels: differing_share(&lod_image, &truth_image),
        });
    }
    rows
}

fn differing_share(a: &RgbaImage, b: &RgbaImage) -> f64 {
    let differs = |p: &image::Rgba<u8>, q: &image::Rgba<u8>| {
        p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > PIXEL_TOLERANCE)
    };
    a.pixels().zip(b.pixels()).filter(|(p, q)| differs(p, q)).count() as f64
        / a.pixels().len() as f64
}

/// Consecutive frames 1/60 s apart from the middle of the approach, LOD
/// only, after one unrecorded frame there (the jump from the last view).
fn fly_at_display_rate(
    display: &mut DisplayParts,
    path: &FlightPath,
    frames: u32,
) -> Vec<FrameStats> {
    let start = path.start_time() + path.duration() / 2.0;
    let camera = |k: u32| camera_at(path, start + k as f64 / DISPLAY_RATE_HZ);
    display.pipeline.settle(&camera(0), 10_000).expect("settle");
    display.frame(&camera(0)).expect("warm-up LOD frame");
    (1..=frames).map(|k| display.frame(&camera(k)).expect("LOD frame")).collect()
}

/// The views summarised; ratios are truth over LOD, per view.
#[derive(serde::Serialize)]
struct Summary {
    lod_frame_ms: Spread,
    lod_gl_ms: Spread,
    truth_frame_ms: Spread,
    truth_over_lod_frame: Spread,
    truth_over_lod_gl: Spread,
    lod_triangles: Spread,
    lod_surface_triangles: Spread,
    truth_triangles: Spread,
    truth_over_lod_triangles: Spread,
    lod_draw_calls: Spread,
    truth_draw_calls: Spread,
    differing_pixels_percent: Spread,
    settle_ms: Spread,
    lod_tiles_per_level_mean: Vec<f64>,
}

impl Summary {
    fn of(views: &[ViewRow]) -> Summary {
        let spread = |f: &dyn Fn(&ViewRow) -> f64| Spread::of(views.iter().map(f));
        let levels = views.first().map_or(0, |v| v.lod_tiles_per_level.len());
        Summary {
            lod_frame_ms: spread(&|v| v.lod.frame_ms),
            lod_gl_ms: spread(&|v| v.lod.gl_ms),
            truth_frame_ms: spread(&|v| v.truth.frame_ms),
            truth_over_lod_frame: spread(&|v| v.truth.frame_ms / v.lod.frame_ms),
            truth_over_lod_gl: spread(&|v| v.truth.frame_ms / v.lod.gl_ms),
            lod_triangles: spread(&|v| v.lod.scene.triangles as f64),
            lod_surface_triangles: spread(&|v| v.lod_surface_triangles as f64),
            truth_triangles: spread(&|v| v.truth.triangles as f64),
            truth_over_lod_triangles: spread(&|v| {
                v.truth.triangles as f64 / v.lod.scene.triangles as f64
            }),
            lod_draw_calls: spread(&|v| v.lod.calls.draw_calls as f64),
            truth_draw_calls: spread(&|v| v.truth.draw_calls as f64),
            differing_pixels_percent: spread(&|v| v.differing_pixels * 100.0),
            settle_ms: spread(&|v| v.settle_ms),
            lod_tiles_per_level_mean: (0..levels)
                .map(|l| {
                    views.iter().map(|v| v.lod_tiles_per_level[l] as f64).sum::<f64>()
                        / views.len() as f64
                })
                .collect(),
        }
    }

    fn print(&self, title: &str) {
        let rows: [(&str, Spread, usize); 12] = [
            ("LOD frame ms (CPU + GPU)", self.lod_frame_ms, 1),
            ("LOD GPU-side ms (upload, draw)", self.lod_gl_ms, 1),
            ("truth frame ms", self.truth_frame_ms, 1),
            ("truth / LOD frame", self.truth_over_lod_frame, 2),
            ("truth / LOD GPU-side", self.truth_over_lod_gl, 2),
            ("LOD triangles (with skirts)", self.lod_triangles, 0),
            ("LOD surface triangles", self.lod_surface_triangles, 0),
            ("truth triangles", self.truth_triangles, 0),
            ("truth / LOD triangles", self.truth_over_lod_triangles, 2),
            ("LOD draw calls", self.lod_draw_calls, 0),
            ("truth draw calls", self.truth_draw_calls, 0),
            ("pixels differing (%)", self.differing_pixels_percent, 2),
        ];
        let cells: Vec<Vec<String>> = rows
            .iter()
            .map(|(name, s, digits)| {
                let values =
                    [s.mean, s.p50, s.p95].map(|v| format!("{v:.digits$}", digits = *digits));
                std::iter::once(name.to_string()).chain(values).collect()
            })
            .collect();
        print_table(title, &["", "mean", "p50", "p95"], &cells);
        let levels: Vec<String> = self
            .lod_tiles_per_level_mean
            .iter()
            .enumerate()
            .map(|(l, n)| format!("L{l} {n:.0}"))
            .collect();
        println!("\n  LOD tiles per level at the views (mean): {}", levels.join(", "));
        println!(
            "  paging before each view (settle, not in the frames): mean {:.1} ms",
            self.settle_ms.mean
        );
    }
}

/// A CPU stage's name and its time in a frame.
type Stage = (&'static str, fn(&FrameStats) -> f64);

/// CPU stages of the LOD frames: at the views and at display rate.
fn print_cpu_table(views: &[ViewRow], live: &[FrameStats]) {
    let stages: [Stage; 5] = [
        ("clipmap update", |s| s.clipmap_ms),
        ("tile selection", |s| s.scene.cpu_ms.select_ms),
        ("tile generation", |s| s.scene.cpu_ms.tiles_ms),
        ("draw list", |s| s.scene.cpu_ms.draw_list_ms),
        ("tiles generated (count)", |s| s.scene.tiles_generated as f64),
    ];
    let rows: Vec<Vec<String>> = stages
        .iter()
        .map(|(name, f)| {
            let at_views = Spread::of(views.iter().map(|v| f(&v.lod)));
            let at_rate = Spread::of(live.iter().map(f));
            let cells =
                [at_views.mean, at_views.p95, at_rate.mean, at_rate.p95].map(|v| format!("{v:.2}"));
            std::iter::once(name.to_string()).chain(cells).collect()
        })
        .collect();
    let title =
        format!("CPU ms per LOD frame: at the views, and {} frames at {DISPLAY_RATE_HZ} Hz from mid-approach", live.len());
    print_table(&title, &["", "views mean", "views p95", "60 Hz mean", "60 Hz p95"], &rows);
}

fn report(
    args: &BenchArgs,
    tau_px: f64,
    info: &ridgeline::gl::GlInfo,
    mesh: &TruthMesh,
    truth_build_ms: f64,
    views: &[ViewRow],
    live: &[FrameStats],
) {
    let summary = Summary::of(views);
    let spacing = if views.len() > 1 { views[1].t - views[0].t } else { 0.0 };
    summary.print(&format!(
        "LOD (tau {tau_px} px) against brute force, {} views {spacing:.2} s apart along the approach, {}x{}",
        views.len(),
        SIZE.x,
        SIZE.y
    ));
    print_cpu_table(views, live);
    println!(
        "\n  ratios (same run, same context, p50 of per-view ratios): truth / LOD frame time {:.2}, GPU-side {:.2}; \
         triangles {:.2}",
        summary.truth_over_lod_frame.p50, summary.truth_over_lod_gl.p50, summary.truth_over_lod_triangles.p50
    );
    let json_path = write_json(
        "render",
        &json!({
            "quick": args.quick,
            "tau_px": tau_px,
            "size": [SIZE.x, SIZE.y],
            "fov_x_deg": FOV_X_DEG,
            "gl_renderer": info.renderer,
            "gl_version": info.version,
            "backend": info.backend.name(),
            "truth": {
                "region_posts": mesh.region.posts,
                "chunks": mesh.chunks.len(),
                "triangles": mesh.triangles(),
                "build_ms": truth_build_ms,
            },
            "summary": summary,
            "views": views,
            "display_rate": { "hz": DISPLAY_RATE_HZ, "frames": live },
        }),
    );
    let svg_path = plot(views, live);
    println!("\nwrote {} and {}", json_path.display(), svg_path.display());
}

fn plot(views: &[ViewRow], live: &[FrameStats]) -> std::path::PathBuf {
    let along = |label: &str, f: &dyn Fn(&ViewRow) -> f64| Series {
        label: label.to_owned(),
        points: views.iter().map(|v| (v.t, f(v))).collect(),
    };
    let live_series = |label: &str, f: fn(&FrameStats) -> f64| Series {
        label: label.to_owned(),
        points: live.iter().enumerate().map(|(k, s)| (k as f64, f(s))).collect(),
    };
    write_svg(
        "render",
        &[
            Panel {
                title: "frame time along the approach".to_owned(),
                x_label: "t (s)".to_owned(),
                y_label: "ms to glFinish".to_owned(),
                log_x: false,
                log_y: false,
                series: vec![
                    along("LOD frame", &|v| v.lod.frame_ms),
                    along("LOD GPU-side", &|v| v.lod.gl_ms),
                    along("truth frame", &|v| v.truth.frame_ms),
                ],
            },
            Panel {
                title: "triangles along the approach".to_owned(),
                x_label: "t (s)".to_owned(),
                y_label: "triangles".to_owned(),
                log_x: false,
                log_y: true,
                series: vec![
                    along("LOD (with skirts)", &|v| v.lod.scene.triangles as f64),
                    along("truth", &|v| v.truth.triangles as f64),
                ],
            },
            Panel {
                title: format!("CPU per frame at {DISPLAY_RATE_HZ} Hz"),
                x_label: "frame".to_owned(),
                y_label: "ms".to_owned(),
                log_x: false,
                log_y: false,
                series: vec![
                    live_series("clipmap update", |s| s.clipmap_ms),
                    live_series("tile selection", |s| s.scene.cpu_ms.select_ms),
                    live_series("tile generation", |s| s.scene.cpu_ms.tiles_ms),
                ],
            },
        ],
    )
}
