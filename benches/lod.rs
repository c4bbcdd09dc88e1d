//! Run time against measured error (issues 5 and 22): the built-in approach
//! over the built-in terrain, headless EGL.
//!
//! - `--quick`: the display sizes (issue 22): node meshes at 480x272,
//!   800x480, 1280x720 and 1920x1080, tau 1 and 4, each against the RTIN
//!   floor of its own viewport, with the measured p99.9 and max;
//! - the full run adds, at 1280x720, a sweep of the error bound tau (0.5 to
//!   8 px) and of the tile parameters (grid size, morph range, Kühnert's
//!   view distance). Every point of the sweep records, in one run:
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
//! - for the tau sweep, at the same views, two GL-free baselines over one
//!   square of level-0 posts around the flight (`support::rtin_floor`): the
//!   RTIN floor (a view-dependent RTIN refinement of those posts at the same
//!   tau and K, triangles meeting the culling frustum) and the
//!   full-resolution triangles in that frustum, each against the LOD's
//!   triangles over the same square.
//!
//! Ratios against the brute-force mesh are per view, so machine noise hits
//! both sides alike. Prints the tables, writes target/bench/lod.json and
//! target/bench/lod.svg (frame time against measured p99 error; triangles
//! against tau beside the floors).

mod support;

use std::cell::OnceCell;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

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
use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::node::NodeSource;
use ridgeline::pipeline::FrameStats;
use ridgeline::pyramid::{Pyramid, Silent};
use ridgeline::render::{RenderBackend, TileUniforms};
use ridgeline::scene::{clip_planes, TerrainSummary};
use serde_json::json;
use support::rtin_floor::{FloorCount, FloorGrid, FloorView};
use support::{print_table, write_json, write_svg, BenchArgs, Panel, Series};

/// The sweep's viewport.
const SIZE: [u32; 2] = [1280, 720];
/// The display sizes of the quick run (issue 22): embedded cockpit
/// displays to a full-HD one.
const SIZES: [[u32; 2]; 4] = [[480, 272], [800, 480], [1280, 720], [1920, 1080]];
const FOV_X_DEG: f64 = 60.0;
/// Frames of the flight part are this often: a low-power board's rate.
const FLIGHT_RATE_HZ: f64 = 10.0;
/// Posts a side of the RTIN floor's square of level-0 posts: the truth's
/// window (31 chunks of 128 cells) and a little more, `2^12 + 1`.
const FLOOR_SIDE: u32 = 4097;

/// One point of the sweep.
#[derive(Clone, Copy, serde::Serialize)]
struct Point {
    name: &'static str,
    #[serde(flatten)]
    lod: LodConfigRow,
    /// What the tiles are drawn from.
    tiles: Tiles,
    /// Also draw the flight by plain Chunked LOD.
    baseline: bool,
    /// Also count the RTIN floor and full resolution in the frustum.
    floors: bool,
    /// The viewport, pixels.
    viewport: [u32; 2],
    /// Also fly consecutive frames (the sweep; the sizes table only
    /// measures its views).
    flight: bool,
}

/// What the tiles are drawn from: the node meshes (`fly`'s default) or the
/// regular grids of each level's posts (`fly --regular-grid`, the
/// subsampled baseline before issue 11).
#[derive(Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
enum Tiles {
    NodeMeshes,
    RegularGrid,
}

/// The built-in terrain, with and without its node meshes (those of each
/// tau, built on first use).
struct Terrain {
    pyramid: Arc<Pyramid>,
    meshed: std::cell::RefCell<Vec<(u64, Arc<MeshedSource>)>>,
}

impl Terrain {
    fn meshed(&self) -> Arc<MeshedSource> {
        let mut all = self.meshed.borrow_mut();
        if let Some((_, source)) = all.first() {
            return Arc::clone(source);
        }
        let options = MeshOptions::default();
        let source = MeshedSource::open_or_build(Arc::clone(&self.pyramid), options, &Silent)
            .expect("the built-in terrain's error maps");
        all.push((0, Arc::new(source)));
        Arc::clone(&all.last().expect("just pushed").1)
    }
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
        let (tiles, viewport) = (Tiles::NodeMeshes, SIZE);
        Point { name, lod: row, tiles, baseline, floors: baseline, viewport, flight: true }
    }

    fn regular(self) -> Point {
        Point { tiles: Tiles::RegularGrid, name: "regular grid", baseline: false, ..self }
    }

    fn apply(&self, lod: &mut LodConfig) {
        lod.tau_px = self.lod.tau_px;
        lod.grid_size = self.lod.grid_size;
        lod.morph_range = self.lod.morph_range;
        lod.view_distance = self.lod.view_distance;
    }
}

/// The display sizes at tau 1 and 4, node meshes, against their floors.
fn size_points() -> Vec<Point> {
    let keep = |_: &mut LodConfig| {};
    let mut points = Vec::new();
    for viewport in SIZES {
        for tau in [1.0, 4.0] {
            let point = Point::new("display size", tau, keep, false);
            points.push(Point { viewport, floors: true, flight: false, ..point });
        }
    }
    points
}

fn points() -> Vec<Point> {
    let keep = |_: &mut LodConfig| {};
    let mut points: Vec<Point> = [0.5, 1.0, 2.0, 4.0, 8.0]
        .into_iter()
        .map(|tau| Point::new("tau sweep", tau, keep, true))
        .collect();
    // Before issue 11: the same taus drawn from each level's posts.
    for tau in [1.0, 4.0] {
        let point = Point::new("regular grid", tau, keep, false).regular();
        points.push(Point { floors: true, ..point });
    }
    // Beyond the sweep: how low the frame time goes as triangles vanish (the fill floor).
    for tau in [16.0, 64.0] {
        points.push(Point::new("coarse", tau, keep, false));
    }
    for tau in [1.0, 4.0] {
        let small = |l: &mut LodConfig| {
            l.grid_size = 16;
            l.morph_range = 0.15;
        };
        let point = Point::new("grid 16 morph 0.15", tau, small, false);
        points.push(Point { floors: true, ..point });
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
            draw_calls: mean(&|s| s.calls.draw_calls as f64),
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
    /// The RTIN floor and full resolution in the frustum (tau sweep only).
    floors: Option<FloorRow>,
}

/// One view's triangles against the baselines over the floor's square.
#[derive(Clone, Copy, serde::Serialize)]
struct FloorViewRow {
    t: f64,
    /// The LOD frame's surface triangles, all of them and over the square
    /// (each tile's by the share of its footprint over it).
    triangles_lod: u64,
    triangles_lod_square: f64,
    /// The frame had to coarsen (tiles did not fit the buffer).
    coarsened: u32,
    rtin: FloorCount,
    full_res_in_frustum: u64,
}

/// Means over the views; ratios per view, then averaged.
#[derive(serde::Serialize)]
struct FloorRow {
    triangles_lod: f64,
    triangles_lod_square: f64,
    rtin_floor: f64,
    rtin_all_round: f64,
    full_res_in_frustum: f64,
    lod_over_rtin: f64,
    full_res_over_lod: f64,
    views: Vec<FloorViewRow>,
}

/// The floors' square and what does not depend on tau, computed once.
struct Floors {
    pyramid: Arc<Pyramid>,
    grid: FloorGrid,
    /// Per view: full-resolution triangles in its frustum.
    full_res: Vec<OnceCell<u64>>,
    checked: OnceCell<()>,
    /// Ulrich's K of the views, pixels.
    k: f64,
}

fn main() {
    let args = BenchArgs::parse();
    let (view_count, flight_frames) = if args.quick { (4, 20) } else { (16, 60) };
    let pyramid =
        Arc::new(dataset::open(None, Path::new("cache"), &Silent).expect("the built-in terrain"));
    let terrain = Terrain { pyramid: Arc::clone(&pyramid), meshed: Default::default() };
    let layout = *pyramid.layout();
    let path = default_flight(&pyramid);
    let views_at = |viewport: [u32; 2]| -> Vec<(f64, Camera)> {
        path.frame_times(view_count).map(|t| (t, camera_at(&path, t, viewport))).collect()
    };
    let views = views_at(SIZE);
    let source: Arc<dyn NodeSource> = pyramid.clone();
    // As `ridgeline accuracy`: a window of level 0 around the views (a
    // layered pyramid's level 0 spans its whole base).
    let positions = views.iter().map(|(_, c)| [c.position.x, c.position.y]);
    let region = TruthRegion::around_positions(&layout, LodConfig::default().grid_size, positions);
    let mesh = TruthMesh::load(source.as_ref(), region).expect("truth mesh");
    let floors = Floors::load(&pyramid, region, &views);
    let mut all = size_points();
    if !args.quick {
        all.extend(points());
    }
    let mut results = Vec::new();
    for point in all {
        let views = views_at(point.viewport);
        let result = measure_point(&point, &terrain, &mesh, &floors, &path, &views, flight_frames);
        println!(
            "  {:<16} {}x{} tau {:>3}: p99.9 {:.3} px, {:.0} triangles, {:.1} ms (truth {:.1} ms)",
            point.name,
            point.viewport[0],
            point.viewport[1],
            point.lod.tau_px,
            result.p999_px,
            result.triangles_lod,
            result.lod_frame_ms,
            result.truth_frame_ms
        );
        results.push(result);
    }
    report(&args, &results, view_count, &floors);
}

fn camera_at(path: &FlightPath, t: f64, viewport: [u32; 2]) -> Camera {
    path.sample(t).camera(FOV_X_DEG, viewport)
}

fn display_for(point: &Point, terrain: &Terrain) -> DisplayParts {
    let mut config = DisplayConfig::new(GlBackend::Egl, point.viewport.into());
    point.apply(&mut config.scene.lod);
    config.fov_x_deg = FOV_X_DEG;
    config.loader = LoaderMode::Inline;
    config.load_budget = 64;
    let mut summary = TerrainSummary::from_pyramid(terrain.pyramid.info());
    let source: Arc<dyn NodeSource> = match point.tiles {
        Tiles::NodeMeshes => {
            let meshed = terrain.meshed();
            summary = TerrainSummary::of_maps(terrain.pyramid.info(), meshed.info());
            meshed
        }
        Tiles::RegularGrid => terrain.pyramid.clone(),
    };
    DisplayParts::open(&config, source, summary).expect("headless EGL display")
}

fn measure_point(
    point: &Point,
    terrain: &Terrain,
    mesh: &TruthMesh,
    floors: &Floors,
    path: &FlightPath,
    views: &[(f64, Camera)],
    flight_frames: u32,
) -> PointResult {
    let pyramid = &terrain.pyramid;
    let mut display = display_for(point, terrain);
    let truth = TruthPass::new(display.context.gl(), mesh).expect("truth pass");
    let exact = |x: f64, y: f64| pyramid.exact_height(x, y);
    let run = measure_flight(&mut display, &truth, &exact, pyramid.layout().spacing_m, views)
        .expect("accuracy views");
    let floor_row = point.floors.then(|| floors.measure(&mut display, point, views, &run));
    let (flight, _) = match point.flight {
        true => fly(&mut display, None, path, flight_frames, point.viewport),
        false => Default::default(),
    };
    let sky_only_ms = sky_only(&mut display, &views[0].1);
    drop(truth);
    drop(display);
    let (chunked, chunked_uploads_per_frame) = if point.baseline {
        let mut display = display_for(point, terrain);
        let mut baseline =
            ChunkedBaseline::new(display.context.gl(), point.lod.grid_size).expect("baseline");
        let (frames, transfers) =
            fly(&mut display, Some(&mut baseline), path, flight_frames, point.viewport);
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
    result.floors = floor_row;
    result
}

impl Floors {
    /// The square of [`FLOOR_SIDE`] posts centred on the truth's `region`,
    /// and its error map. Its first post is a multiple of the largest power
    /// of two that still lets it hold the whole window (at most the root
    /// level's post step): the coarse levels' posts, those of a base layer
    /// among them, then fall on corners of the RTIN's squares, as they fall
    /// on the LOD's tiles' corners.
    fn load(pyramid: &Arc<Pyramid>, region: TruthRegion, views: &[(f64, Camera)]) -> Floors {
        let start = Instant::now();
        let slack = FLOOR_SIDE.saturating_sub(region.posts[0].max(region.posts[1])).max(1);
        let root_step = 1u32 << (pyramid.layout().levels - 1);
        let align = (1u32 << slack.ilog2()).min(root_step) as i64;
        let grid = FloorGrid::load(pyramid.as_ref(), region, FLOOR_SIDE, align);
        let (sw, ne) = grid.extent_m();
        println!(
            "RTIN floor square: {side}x{side} level-0 posts from post ({}, {}) (a multiple of {align}; truth window {:?} posts from {:?}), \
             {:.0} x {:.0} km, local x {:.0}..{:.0} m, y {:.0}..{:.0} m; {} posts without data filled; \
             error map in {:.1} s",
            grid.first[0],
            grid.first[1],
            region.posts,
            region.first,
            (ne[0] - sw[0]) / 1e3,
            (ne[1] - sw[1]) / 1e3,
            sw[0],
            ne[0],
            sw[1],
            ne[1],
            grid.filled,
            start.elapsed().as_secs_f64(),
            side = grid.side,
        );
        Floors {
            pyramid: pyramid.clone(),
            grid,
            full_res: vec![OnceCell::new(); views.len()],
            checked: OnceCell::new(),
            k: views.first().map_or(0.0, |(_, c)| c.perspective_scale()),
        }
    }

    /// Prints the table of the tau sweep against the floors; returns what
    /// the JSON says of the square.
    fn report(&self, results: &[PointResult]) -> serde_json::Value {
        let grid = &self.grid;
        let (sw, ne) = grid.extent_m();
        let km = [(ne[0] - sw[0]) / 1e3, (ne[1] - sw[1]) / 1e3];
        let header = [
            "tiles",
            "tau",
            "LOD p99.9 px",
            "LOD tri",
            "LOD tri on square",
            "RTIN floor",
            "LOD/RTIN",
            "RTIN all round",
            "full res in frustum",
            "full res/LOD",
            "every post/LOD",
        ];
        let rows: Vec<Vec<String>> = results
            .iter()
            .filter_map(|r| r.floors.as_ref().map(|f| (r, f)))
            .map(|(r, f)| {
                vec![
                    r.point.name.to_string(),
                    format!("{}", r.point.lod.tau_px),
                    format!("{:.4}", r.p999_px),
                    format!("{:.0}", f.triangles_lod),
                    format!("{:.0}", f.triangles_lod_square),
                    format!("{:.0}", f.rtin_floor),
                    format!("{:.2}", f.lod_over_rtin),
                    format!("{:.0}", f.rtin_all_round),
                    format!("{:.0}", f.full_res_in_frustum),
                    format!("{:.2}", f.full_res_over_lod),
                    format!("{:.2}", r.truth_over_lod_triangles),
                ]
            })
            .collect();
        print_table(
            &format!(
                "Triangles in view against the floors over the {side}x{side}-post square of level 0 \
                 ({:.0} x {:.0} km around the flight): means over the views, ratios per view then averaged",
                km[0],
                km[1],
                side = grid.side,
            ),
            &header,
            &rows,
        );
        println!(
            "  RTIN floor: view-dependent RTIN refinement of the square's posts, split while the error \
             (max vertical distance to the posts) > tau D / K, K = {:.1} px, D from the eye to the split's box;\n  \
             counted: triangles whose box meets the LOD's culling frustum (conservative, curvature drop as the \
             selector's). Full res: 2 per level-0 cell of the square whose box meets that frustum.\n  \
             LOD on square: each drawn tile's triangles by the share of its footprint over the square. \
             every post/LOD: the truth window's triangles over all the LOD's.",
            self.k
        );
        json!({
            "side": grid.side,
            "first_post": grid.first,
            "extent_m": [sw, ne],
            "km": km,
            "posts_filled": grid.filled,
            "full_res_triangles": grid.full_res_triangles(),
            "k_px": self.k,
        })
    }

    /// The baselines at `point`'s tau for each view, beside the LOD frame
    /// `display` draws there (settled, as `measure_flight` measured it).
    fn measure(
        &self,
        display: &mut DisplayParts,
        point: &Point,
        views: &[(f64, Camera)],
        run: &AccuracyRun,
    ) -> FloorRow {
        let grid_size = point.lod.grid_size;
        let curvature = display.pipeline.scene().config().curvature;
        let mut rows = Vec::with_capacity(views.len());
        for (v, (t, camera)) in views.iter().enumerate() {
            display.pipeline.settle(camera, 10_000).expect("settle");
            let stats = display.frame(camera).expect("LOD frame");
            let tiles = &display.pipeline.draw_list().tiles;
            // Surface triangles, skirts left out, tile by tile (node mesh
            // tiles have their own counts).
            let (staging, _) = display.pipeline.scene().uploads();
            let surface = |tile: &TileUniforms| tile.block(staging).surface_triangle_count() as f64;
            let share: f64 = tiles
                .iter()
                .map(|tile| self.grid.tile_share(tile.key, grid_size) * surface(tile))
                .sum();
            let drawn: f64 = tiles.iter().map(surface).sum();
            let view =
                self.grid.view(camera, clip_planes(camera, &display.pipeline.terrain()), curvature);
            self.checked.get_or_init(|| self.check(views, &view));
            let full_res = *self.full_res[v].get_or_init(|| self.grid.full_res_in_frustum(&view));
            let row = FloorViewRow {
                t: *t,
                triangles_lod: drawn as u64,
                triangles_lod_square: share,
                coarsened: stats.scene.coarsened,
                rtin: self.grid.rtin_floor(&view, point.lod.tau_px),
                full_res_in_frustum: full_res,
            };
            if row.triangles_lod != run.views[v].triangles_lod || row.coarsened > 0 {
                println!(
                    "  note: view {v} drew {} LOD triangles here ({} coarsenings), {} when measured",
                    row.triangles_lod, row.coarsened, run.views[v].triangles_lod
                );
            }
            rows.push(row);
        }
        let n = rows.len().max(1) as f64;
        let mean = |f: &dyn Fn(&FloorViewRow) -> f64| rows.iter().map(f).sum::<f64>() / n;
        FloorRow {
            triangles_lod: mean(&|r| r.triangles_lod as f64),
            triangles_lod_square: mean(&|r| r.triangles_lod_square),
            rtin_floor: mean(&|r| r.rtin.in_frustum as f64),
            rtin_all_round: mean(&|r| r.rtin.all_round as f64),
            full_res_in_frustum: mean(&|r| r.full_res_in_frustum as f64),
            lod_over_rtin: mean(&|r| r.triangles_lod_square / r.rtin.in_frustum.max(1) as f64),
            full_res_over_lod: mean(&|r| {
                r.full_res_in_frustum as f64 / r.triangles_lod_square.max(1.0)
            }),
            views: rows,
        }
    }

    /// Once, at the first view: that the square's posts lie where the
    /// cameras' frame puts them (the pyramid's height at the post under each
    /// eye and on a lattice over the square is the square's), and that the
    /// refinement spans what it should at both ends of tau: a handful of
    /// triangles at a huge tau, and at tau 0 (every split whose box meets the
    /// frustum) the half cells of the full-resolution cells in the frustum.
    fn check(&self, cameras: &[(f64, Camera)], view: &FloorView) {
        let grid = &self.grid;
        let last = grid.side - 1;
        let lattice = (0..=16).flat_map(|a| (0..=16).map(move |b| [a * last / 16, b * last / 16]));
        let under =
            cameras.iter().map(|(_, c)| grid.post_under(c).expect("every eye over the square"));
        let posts = self.pyramid.layout().posts;
        let (mut compared, mut worst) = (0, 0.0f64);
        for [i, j] in under.chain(lattice) {
            let data = [grid.first[0] + i as i64, grid.first[1] + j as i64];
            if !(0..posts[0] as i64).contains(&data[0]) || !(0..posts[1] as i64).contains(&data[1])
            {
                continue;
            }
            let [x, y] = grid.post_m(i as f64, j as f64);
            let Some(exact) = self.pyramid.exact_height(x, y).filter(|h| !h.is_nan()) else {
                continue;
            };
            let difference = (exact as f64 - grid.at(i, j) as f64).abs();
            assert!(
                difference < 0.01,
                "post ({i}, {j}) of the square: {} m, the pyramid {exact} m",
                grid.at(i, j)
            );
            (compared, worst) = (compared + 1, worst.max(difference));
        }
        let full = grid.full_res_in_frustum(view);
        let coarse = grid.rtin_floor(view, 1e12).in_frustum;
        let tiny = grid.rtin_floor(view, 1e-6).in_frustum;
        let all = grid.split_all_in_frustum(view);
        println!(
            "RTIN floor check, first view: {compared} posts at the pyramid's heights (largest difference {worst:.4} m); \
             in the frustum tau 1e12: {coarse} triangles, tau 1e-6: {tiny}, every split: {all}, full resolution: {full}"
        );
        assert!(compared > cameras.len(), "too few posts compared: {compared}");
        assert!(coarse <= 64, "a huge tau still leaves {coarse} triangles");
        let ratio = all as f64 / full as f64;
        assert!(full > 0 && (0.95..=1.0).contains(&ratio), "tau 0: {all} triangles against {full}");
        assert!(tiny <= all, "tau 1e-6 ({tiny}) past tau 0 ({all})");
    }
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
    viewport: [u32; 2],
) -> (Vec<FrameStats>, Vec<BaselineFrameStats>) {
    let start = path.start_time() + path.duration() / 2.0;
    let camera = |k: u32| camera_at(path, start + k as f64 / FLIGHT_RATE_HZ, viewport);
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
        floors: None,
    }
}

/// The display-size rows (issue 22): one per size and tau.
fn size_rows(results: &[PointResult]) -> Vec<serde_json::Value> {
    results
        .iter()
        .filter(|r| r.point.name == "display size")
        .filter_map(|r| r.floors.as_ref().map(|f| (r, f)))
        .map(|(r, f)| {
            json!({
                "viewport": r.point.viewport,
                "tau_px": r.point.lod.tau_px,
                "tiles": "meshes",
                "triangles": f.triangles_lod_square.round(),
                "rtin_floor": f.rtin_floor.round(),
                "ratio": f.lod_over_rtin,
                "p999_px": r.p999_px,
                "max_px": r.max_px,
                "triangles_drawn": r.triangles_lod.round(),
            })
        })
        .collect()
}

/// Prints the display-size table.
fn report_sizes(results: &[PointResult]) {
    let header = [
        "viewport",
        "tau",
        "LOD tri on square",
        "RTIN floor",
        "LOD/RTIN",
        "p99.9 px",
        "max px",
        "drawn tri",
    ];
    let rows: Vec<Vec<String>> = size_rows(results)
        .iter()
        .map(|r| {
            let v = &r["viewport"];
            vec![
                format!("{}x{}", v[0], v[1]),
                format!("{}", r["tau_px"]),
                format!("{}", r["triangles"]),
                format!("{}", r["rtin_floor"]),
                format!("{:.2}", r["ratio"].as_f64().unwrap_or(f64::NAN)),
                format!("{:.3}", r["p999_px"].as_f64().unwrap_or(f64::NAN)),
                format!("{:.2}", r["max_px"].as_f64().unwrap_or(f64::NAN)),
                format!("{}", r["triangles_drawn"]),
            ]
        })
        .collect();
    print_table(
        "Display sizes (issue 22): node meshes against the view-dependent RTIN floor of the same viewport, tau and views",
        &header,
        &rows,
    );
}

fn report(args: &BenchArgs, results: &[PointResult], views: u32, floors: &Floors) {
    report_sizes(results);
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
    let square = floors.report(results);
    let json_path = write_json(
        "lod",
        &json!({
            "quick": args.quick,
            "views": views,
            "size": SIZE,
            "brute_force_frame_ms": brute,
            "floor_square": square,
            "sizes": size_rows(results),
            "points": results,
        }),
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
    let svg = write_svg("lod", &[panel, floors_panel(&sweep)]);
    println!("\nwrote {} and {}", json_path.display(), svg.display());
}

/// Triangles against tau over the floors' square: the LOD, the RTIN floor
/// and full resolution in the frustum.
fn floors_panel(sweep: &[&PointResult]) -> Panel {
    let line = |label: &str, f: &dyn Fn(&FloorRow) -> f64| Series {
        label: label.into(),
        points: sweep
            .iter()
            .filter_map(|r| r.floors.as_ref().map(|x| (r.point.lod.tau_px, f(x))))
            .collect(),
    };
    Panel {
        title: "triangles in view over the floors' square".into(),
        x_label: "tau (px)".into(),
        y_label: "triangles (mean over the views)".into(),
        log_x: true,
        log_y: true,
        series: vec![
            line("UDLOD (tiles by share over the square)", &|f| f.triangles_lod_square),
            line("RTIN floor (same tau, in the frustum)", &|f| f.rtin_floor),
            line("full resolution in the frustum", &|f| f.full_res_in_frustum),
        ],
    }
}
