//! Cluster batches against one draw per tile (Judnich & Ling, Table 1 and
//! Table II, on our data): the default flight at 1280x720 on headless EGL,
//! at one tau (1 px, `-- --tau PX` to change), over the node meshes `fly`
//! draws (`-- --regular-grid` for regular grids of each level's posts),
//! drawn as
//! - CLOD-16, -32, -64: one draw call per tile of 16, 32 or 64 cells;
//! - SCSLOD-16, -32: clusters of up to 16 such tiles, one draw call each
//!   (and SCSLOD-64 for completeness: 16 tiles of 64 cells exceed 16-bit
//!   indices, so its clusters are cut to quadrants).
//!
//! Per view, every technique in turn (interleaved, the order reversed every
//! other view): the view is settled and drawn once (uploads), then drawn
//! again from the same camera three times (two with `--quick`), nothing to upload,
//! and the median kept: draw calls ("batches"), triangles, attribute
//! pointer changes and vertex array binds (a cluster's attribute window
//! changing), the CPU time the renderer spends issuing the frame's
//! GL calls (clear, sky, terrain; no glFinish), the frame time to
//! glFinish, and triangles per second over the frame time. Ratios are
//! taken against CLOD-32 of the same run.
//!
//! The same again with a 2x2 render target (the tiles still chosen for
//! 1280x720, the viewport clipped to the target): rasterisation then costs
//! next to nothing, and what is left is Mesa's per-call and per-vertex work.
//!
//! `-- --quick` draws 3 views instead of 24. Prints tables, writes
//! target/bench/batches.json and target/bench/batches.svg.

mod support;

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glam::UVec2;
use ridgeline::camera::Camera;
use ridgeline::clipmap::LoaderMode;
use ridgeline::dataset;
use ridgeline::display::DisplayConfig;
use ridgeline::flight::default_flight;
use ridgeline::gl::{ContextRequest, GlBackend, GlContext, GlRenderer};
use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::node::NodeSource;
use ridgeline::pipeline::FramePipeline;
use ridgeline::pyramid::{Pyramid, Silent};
use ridgeline::render::{
    CallStats, ClusterOrder, DrawList, FrameOutput, FrameUniforms, RenderBackend,
};
use ridgeline::scene::TerrainSummary;
use serde_json::json;
use support::{print_table, write_json, write_svg, BenchArgs, Panel, Series};

const SIZE: UVec2 = UVec2::new(1280, 720);
const FOV_X_DEG: f64 = 60.0;
/// Each technique's buffer: CLOD-16's 2000 tiles at tau 1 take 20 MB.
const BUFFER_BYTES: u32 = 48 << 20;

/// The built-in terrain, with its node meshes unless regular grids are drawn.
struct Terrain {
    pyramid: Arc<Pyramid>,
    meshed: Option<Arc<MeshedSource>>,
}

impl Terrain {
    /// The node source a pipeline pages from, and its summary (the meshes'
    /// deltas when meshes are drawn).
    fn source(&self) -> (Arc<dyn NodeSource>, TerrainSummary) {
        let summary = TerrainSummary::from_pyramid(self.pyramid.info());
        match &self.meshed {
            Some(meshed) => {
                let summary = TerrainSummary::of_maps(self.pyramid.info(), meshed.info());
                (meshed.clone(), summary)
            }
            None => (self.pyramid.clone(), summary),
        }
    }
}

/// The GL renderer, timing how long issuing each frame's calls takes.
struct Timed {
    renderer: GlRenderer,
    issue_ms: f64,
}

impl RenderBackend for Timed {
    type Error = ridgeline::gl::GlError;

    fn upload_frame(&mut self, frame: &FrameOutput<'_>) -> Result<(), Self::Error> {
        self.renderer.upload_frame(frame)
    }

    fn draw_frame(&mut self, list: &DrawList, uniforms: &FrameUniforms) -> Result<(), Self::Error> {
        self.renderer.draw_frame(list, uniforms)
    }

    /// The renderer's whole frame, uploads and draws, timed.
    fn render(&mut self, frame: &FrameOutput<'_>) -> Result<(), Self::Error> {
        let start = Instant::now();
        let result = self.renderer.render(frame);
        self.issue_ms = start.elapsed().as_secs_f64() * 1e3;
        result
    }

    fn finish(&mut self) {
        self.renderer.finish();
    }

    fn take_calls(&mut self) -> CallStats {
        self.renderer.take_calls()
    }
}

/// A technique: tiles of `grid` cells, drawn one by one or as clusters.
#[derive(Clone, Copy)]
struct Technique {
    grid: u32,
    clusters: bool,
    order: ClusterOrder,
}

impl Technique {
    fn name(&self) -> String {
        let order = match (self.clusters, self.order) {
            (true, ClusterOrder::NearestFirst) => " nearest first",
            _ => "",
        };
        format!("{}-{}{order}", if self.clusters { "SCSLOD" } else { "CLOD" }, self.grid)
    }
}

/// Means over the views of one technique.
#[derive(Clone, Copy, Default, serde::Serialize)]
struct Row {
    batches: f64,
    triangles: f64,
    pointer_changes: f64,
    vertex_array_binds: f64,
    uniform_writes: f64,
    issue_ms: f64,
    frame_ms: f64,
    triangles_per_s: f64,
    tiles: f64,
    clusters: f64,
    /// Bytes uploaded by the view's first frame, mean.
    first_frame_upload_bytes: f64,
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// One technique's context, pipeline and renderer, and its sums.
struct Runner {
    context: GlContext,
    pipeline: FramePipeline,
    backend: Timed,
    sum: Row,
}

impl Runner {
    fn open(
        terrain: &Terrain,
        technique: Technique,
        target: UVec2,
        tau: f64,
    ) -> Result<Runner, Box<dyn std::error::Error>> {
        let mut config = DisplayConfig::new(GlBackend::Egl, SIZE);
        config.loader = LoaderMode::Inline;
        config.load_budget = 1000;
        config.scene.buffer_bytes = BUFFER_BYTES;
        config.scene.lod.grid_size = technique.grid;
        config.scene.lod.tau_px = tau;
        config.scene.clusters = technique.clusters;
        config.scene.cluster_order = technique.order;
        let request = ContextRequest::new(GlBackend::Egl, config.version, target);
        let context = GlContext::new(&request)?;
        let (source, summary) = terrain.source();
        let pipeline = FramePipeline::new(&config.pipeline(), source, summary)?;
        let renderer = GlRenderer::new(context.gl(), &pipeline.buffer_plan())?;
        let backend = Timed { renderer, issue_ms: 0.0 };
        Ok(Runner { context, pipeline, backend, sum: Row::default() })
    }

    /// Settles `camera`, draws it once (uploads), then `repeats` times.
    fn view(&mut self, camera: &Camera, repeats: usize) -> Result<(), Box<dyn std::error::Error>> {
        let (pipeline, backend, sum) = (&mut self.pipeline, &mut self.backend, &mut self.sum);
        pipeline.settle(camera, 1000)?;
        self.context.make_current()?;
        self.context.bind_target();
        let first = pipeline.frame(camera, backend)?;
        sum.first_frame_upload_bytes += first.calls.bytes_uploaded as f64;
        let mut frames = Vec::new();
        for _ in 0..repeats {
            let stats = pipeline.frame(camera, backend)?;
            frames.push((stats, backend.issue_ms));
        }
        let frame_ms = median(frames.iter().map(|f| f.0.frame_ms).collect());
        let issue_ms = median(frames.iter().map(|f| f.1).collect());
        let stats = frames[0].0;
        assert_eq!(stats.calls.bytes_uploaded, 0, "a repeated frame uploads nothing");
        // The terrain's calls: the sky is one draw and one pointer.
        let triangles = (stats.calls.triangles - 1) as f64;
        sum.batches += (stats.calls.draw_calls - 1) as f64;
        sum.triangles += triangles;
        sum.pointer_changes += (stats.calls.attribute_pointer_changes - 1) as f64;
        sum.vertex_array_binds += stats.calls.vertex_array_binds as f64;
        sum.uniform_writes += stats.calls.uniform_writes as f64;
        sum.issue_ms += issue_ms;
        sum.frame_ms += frame_ms;
        sum.triangles_per_s += triangles / (frame_ms / 1e3);
        sum.tiles += stats.scene.tiles as f64;
        sum.clusters += stats.scene.clusters as f64;
        Ok(())
    }

    fn mean(&self, views: usize) -> Row {
        let (sum, n) = (self.sum, views as f64);
        Row {
            batches: sum.batches / n,
            triangles: sum.triangles / n,
            pointer_changes: sum.pointer_changes / n,
            vertex_array_binds: sum.vertex_array_binds / n,
            uniform_writes: sum.uniform_writes / n,
            issue_ms: sum.issue_ms / n,
            frame_ms: sum.frame_ms / n,
            triangles_per_s: sum.triangles_per_s / n,
            tiles: sum.tiles / n,
            clusters: sum.clusters / n,
            first_frame_upload_bytes: sum.first_frame_upload_bytes / n,
        }
    }
}

/// Every technique over the same views, interleaved view by view (the
/// order reversed every other view), so load on the machine hits all alike.
fn run_all(
    terrain: &Terrain,
    techniques: &[Technique],
    target: UVec2,
    tau: f64,
    views: usize,
    repeats: usize,
) -> Result<Vec<Row>, Box<dyn std::error::Error>> {
    let mut runners = techniques
        .iter()
        .map(|&t| Runner::open(terrain, t, target, tau))
        .collect::<Result<Vec<_>, _>>()?;
    let path = default_flight(&terrain.pyramid);
    for (k, t) in path.frame_times(views as u32).enumerate() {
        let camera = path.sample(t).camera(FOV_X_DEG, [SIZE.x, SIZE.y]);
        let count = runners.len();
        for j in 0..count {
            let at = if k % 2 == 0 { j } else { count - 1 - j };
            runners[at].view(&camera, repeats)?;
        }
    }
    Ok(runners.iter().map(|r| r.mean(views)).collect())
}

fn table(title: &str, techniques: &[Technique], rows: &[Row]) {
    let reference = techniques
        .iter()
        .position(|t| t.grid == 32 && !t.clusters)
        .map(|k| rows[k])
        .expect("CLOD-32 is measured");
    let cells: Vec<Vec<String>> = techniques
        .iter()
        .zip(rows)
        .map(|(t, r)| {
            vec![
                t.name(),
                format!("{:.0}", r.batches),
                format!("{:.0}", r.tiles),
                format!("{:.0}", r.triangles),
                format!("{:.0}", r.pointer_changes),
                format!("{:.2}", r.pointer_changes / r.batches),
                format!("{:.1}", r.vertex_array_binds),
                format!("{:.2}", r.issue_ms),
                format!("{:.1}", r.frame_ms),
                format!("{:.1}", r.triangles_per_s / 1e6),
                format!("{:.2}", reference.batches / r.batches),
                format!("{:.2}", reference.issue_ms / r.issue_ms),
                format!("{:.2}", reference.frame_ms / r.frame_ms),
                format!("{:.1}", r.first_frame_upload_bytes / 1e6),
            ]
        })
        .collect();
    print_table(
        title,
        &[
            "technique",
            "batches",
            "tiles",
            "triangles",
            "ptr changes",
            "ptr/batch",
            "VAO binds",
            "issue ms",
            "frame ms",
            "Mtri/s",
            "x fewer batches",
            "x issue",
            "x frame",
            "1st-frame MB up",
        ],
        &cells,
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = BenchArgs::parse();
    let tau: f64 = std::env::args()
        .skip_while(|a| a != "--tau")
        .nth(1)
        .map(|v| v.parse().expect("--tau PX"))
        .unwrap_or(1.0);
    let (views, repeats) = if args.quick { (3, 2) } else { (24, 3) };
    let pyramid = Arc::new(dataset::open(None, Path::new("cache"), &Silent)?);
    let regular_grid = std::env::args().any(|a| a == "--regular-grid");
    let meshed = match regular_grid {
        true => None,
        false => Some(Arc::new(MeshedSource::open_or_build(
            pyramid.clone(),
            MeshOptions::default(),
            &Silent,
        )?)),
    };
    let terrain = Terrain { pyramid, meshed };
    let tiles = if regular_grid { "regular grids" } else { "node meshes" };
    let by_base = ClusterOrder::ByBase;
    let mut techniques: Vec<Technique> =
        [(16, false), (32, false), (64, false), (16, true), (32, true), (64, true)]
            .into_iter()
            .map(|(grid, clusters)| Technique { grid, clusters, order: by_base })
            .collect();
    techniques.push(Technique { grid: 32, clusters: true, order: ClusterOrder::NearestFirst });
    let mut report = serde_json::Map::new();
    let mut panels = Vec::new();
    for (label, target) in [("1280x720", SIZE), ("2x2", UVec2::new(2, 2))] {
        let rows = run_all(&terrain, &techniques, target, tau, views, repeats)?;
        table(
            &format!(
                "{tiles}, tau {tau} px, tiles chosen for 1280x720, drawn into {label}: means over {views} views of the default flight, ratios against CLOD-32"
            ),
            &techniques,
            &rows,
        );
        let entries: Vec<serde_json::Value> = techniques
            .iter()
            .zip(&rows)
            .map(|(t, r)| json!({ "technique": t.name(), "grid": t.grid, "clusters": t.clusters, "row": r }))
            .collect();
        report.insert(label.to_owned(), json!(entries));
        let series = |clusters: bool, f: &dyn Fn(&Row) -> f64| Series {
            label: format!("{} ({label})", if clusters { "clusters" } else { "per tile" }),
            points: techniques
                .iter()
                .zip(&rows)
                .filter(|(t, _)| t.clusters == clusters && t.order == by_base)
                .map(|(t, r)| (t.grid as f64, f(r)))
                .collect(),
        };
        panels.push(Panel {
            title: format!("frame ms, {label}"),
            x_label: "cells per tile".to_owned(),
            y_label: "ms to glFinish".to_owned(),
            log_x: true,
            log_y: false,
            series: vec![series(false, &|r| r.frame_ms), series(true, &|r| r.frame_ms)],
        });
        panels.push(Panel {
            title: format!("CPU ms issuing GL calls, {label}"),
            x_label: "cells per tile".to_owned(),
            y_label: "ms".to_owned(),
            log_x: true,
            log_y: false,
            series: vec![series(false, &|r| r.issue_ms), series(true, &|r| r.issue_ms)],
        });
    }
    print_table(
        "Judnich & Ling at 1920x1080, tau 1 px, GTX 285 (Table 1 fps; Table II)",
        &[
            "technique",
            "fps (Table 1)",
            "batches",
            "triangles",
            "Mtri/s (Table II)",
            "Mtri/s from fps",
        ],
        &[
            vec!["CLOD-16".into(), "30".into(), "".into(), "".into(), "".into(), "".into()],
            vec![
                "CLOD-32".into(),
                "126".into(),
                "421".into(),
                "1.0M".into(),
                "165".into(),
                "126".into(),
            ],
            vec![
                "CLOD-64".into(),
                "253".into(),
                "146".into(),
                "1.3M".into(),
                "460".into(),
                "329".into(),
            ],
            vec!["SCSLOD-16".into(), "174".into(), "".into(), "".into(), "".into(), "".into()],
            vec![
                "SCSLOD-32".into(),
                "338".into(),
                "69".into(),
                "1.0M".into(),
                "438".into(),
                "338".into(),
            ],
        ],
    );
    report.insert("tau_px".to_owned(), json!(tau));
    report.insert("tiles".to_owned(), json!(tiles));
    report.insert("views".to_owned(), json!(views));
    let json_path = write_json("batches", &serde_json::Value::Object(report));
    let svg_path = write_svg("batches", &panels);
    println!("\nwrote {} and {}", json_path.display(), svg_path.display());
    Ok(())
}
