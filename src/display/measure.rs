//! [`measure_flight`]: the accuracy tool's loop over a display's parts. For
//! each view it settles the clipmap (the error of the LOD, not of paging, is
//! measured), draws the LOD frame (once to make its tiles, then timed), then
//! three passes over that frame's output with its uniforms: the LOD tiles as
//! positions, the full-resolution truth in colour (timed) and as positions;
//! and measures the per-pixel error. It keeps the heat map of the worst view.
//!
//! Where the full-resolution mesh is too large to draw (a cruise out to the
//! horizon), the truth's positions come from each pixel's ray followed on
//! the CPU against the exact heights instead ([`Truth::Rays`]), and its
//! triangles are counted in the frustum, not drawn.

use glam::DVec2;
use image::RgbaImage;

use super::{DisplayError, DisplayParts};
use crate::accuracy::{
    heat_map, measure_earth, measure_view, percentile, trace_earth, trace_truth, CoverageProbe,
    DisplayFrame, EarthErrors, EarthGround, EarthImage, EarthView, ErrorSummary, ExactHeight,
    LodSurface, PositionImage, RayGround, SkirtProbe, TrueCamera, ViewErrors, ViewGeometry,
};
use crate::camera::Camera;
use crate::earth::GridPlacement;
use crate::gl::{GlError, OffscreenTarget, TruthFrameStats, TruthPass};
use crate::pipeline::FrameStats;
use crate::render::{DrawList, FrameUniforms, RenderBackend};
use std::time::Instant;

/// Clipmap updates allowed per view to page in everything it wants.
const SETTLE_UPDATES: u32 = 10_000;
/// Frames a frame budget's controller gets at each view to hold tau still.
const BUDGET_FRAMES: u32 = 40;

/// One view's numbers.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ViewRow {
    /// Time along the flight path, seconds.
    pub t: f64,
    /// The bound the view achieved, pixels ([`crate::scene::SceneStats::bound_px`]):
    /// above the requested tau when a frame budget loosened it or tiles
    /// were drawn from coarser data than their level's.
    pub tau_px: f64,
    /// Percentiles of this view's per-pixel error, pixels.
    #[serde(flatten)]
    pub errors: ErrorSummary,
    /// Share of all pixels where one image shows terrain over ground the
    /// other has no surface for (see [`crate::accuracy`]'s coverage notes).
    pub coverage_mismatch: f64,
    /// Pixels with terrain in one image only over ground both surfaces
    /// cover: silhouettes moved by the surface's error, measured there.
    pub silhouette: usize,
    /// Of the mismatch: terrain in the LOD image only, over ground without data.
    pub lod_only: usize,
    /// Of the mismatch: terrain in the truth image only, over ground no drawn
    /// tile covers with data.
    pub truth_only: usize,
    /// Of the mismatch: terrain pixels whose truth ground point a drawn tile
    /// covers without data.
    pub no_data: usize,
    /// Terrain pixels whose ground point no LOD tile covers.
    pub holes: usize,
    /// Terrain pixels showing a skirt, and the largest error off skirts.
    pub skirt_pixels: usize,
    /// Largest error, pixels, over terrain pixels that show no skirt.
    pub max_surface_px: f64,
    /// The worst skirt pixel followed to the tile edge it hangs from.
    pub worst_skirt: Option<SkirtProbe>,
    /// A pixel where the truth shows terrain and the LOD none, followed to
    /// the LOD tile and triangle over its ground point.
    pub truth_only_probe: Option<CoverageProbe>,
    /// 99th percentile of |GPU-drawn height - CPU mirror| over LOD terrain
    /// pixels, metres: the measurement's own check.
    pub mirror_p99_m: f64,
    /// Surface triangles (skirts left out, as the truth has none).
    pub triangles_lod: u64,
    /// Surface triangles of the truth mesh drawn for the view.
    pub triangles_truth: u64,
    /// Draw calls of the LOD frame.
    pub draw_calls_lod: usize,
    /// Draw calls of the truth pass.
    pub draw_calls_truth: usize,
    /// LOD tiles per level, finest first.
    pub tiles_per_level: Vec<usize>,
    /// Tiles the frustum kept that the horizon hid (not selected, made or drawn).
    pub horizon_culled: usize,
    /// The LOD frame (paging, tiling, upload, draw, to glFinish) drawn at the
    /// view's pose after a first frame there made its tiles, and the truth's
    /// draw right after it.
    pub lod_frame_ms: f64,
    /// Milliseconds of the truth's draw, to glFinish.
    pub truth_frame_ms: f64,
    /// The view's error against the geodetic truth, when measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub earth: Option<EarthRow>,
}

/// One view's error against the geodetic truth (see [`crate::accuracy`]).
#[derive(Clone, Debug, serde::Serialize)]
pub struct EarthRow {
    /// Percentiles over the traced pixels, pixels.
    #[serde(flatten)]
    pub errors: ErrorSummary,
    /// Share of the traced pixels where one image shows terrain over
    /// ground the other has no surface for.
    pub coverage_mismatch: f64,
    /// Traced pixels with terrain in one image only, measured.
    pub silhouette: usize,
    /// Traced terrain pixels whose true place no drawn tile covers.
    pub holes: usize,
    /// Milliseconds the rays took (every traced pixel).
    pub truth_ms: f64,
}

/// The geodetic truth a run measures against: the best data on the
/// ellipsoid, and which pixels to trace.
pub struct EarthTruth<'a> {
    /// Where the grid's posts are on the earth.
    pub placement: GridPlacement,
    /// The best data on the ellipsoid, loaded for the views.
    pub ground: &'a EarthGround,
    /// Every `stride`-th pixel across and down is traced (1: all).
    pub stride: u32,
    /// Rays are followed this far, metres (the views' horizon and more).
    pub reach_m: f64,
}

/// The error against the geodetic truth over every view.
#[derive(Clone, Debug, serde::Serialize)]
pub struct EarthSummary {
    /// Percentiles over every traced pixel of every view, pixels.
    #[serde(flatten)]
    pub errors: ErrorSummary,
    /// Share of all traced pixels with a coverage mismatch.
    pub coverage_mismatch: f64,
    /// Traced terrain pixels whose true place no drawn tile covers.
    pub holes: usize,
    /// Every `stride`-th pixel across and down was traced.
    pub stride: u32,
    /// Mean milliseconds the rays took per view.
    pub truth_ms: f64,
}

/// The view with the largest p99.9 error (then the largest maximum).
pub struct WorstView {
    /// Position of the view among the measured views, from 0.
    pub index: usize,
    /// Per-pixel error of the view coloured against tau.
    pub heat_map: RgbaImage,
    /// The LOD display's own picture of that view.
    pub picture: RgbaImage,
}

/// Everything measured over the views.
pub struct AccuracyRun {
    /// The tau requested, pixels.
    pub tau_px: f64,
    /// Where the full-resolution image came from ([`Truth::route`]).
    pub truth: &'static str,
    /// The largest bound any view achieved, pixels (a frame budget, or
    /// tiles drawn from coarser data than their level's, may raise it above
    /// `tau_px`): the bound the measured error is held to.
    pub tau_achieved_max_px: f64,
    /// Views whose bound was above the requested tau.
    pub tau_loosened_views: usize,
    /// Over every terrain pixel of every view.
    pub summary: ErrorSummary,
    /// Share of all pixels of all views where one image shows terrain over
    /// ground the other has no surface for.
    pub coverage_mismatch: f64,
    /// Terrain pixels of all views whose ground point no LOD tile covers.
    pub holes: usize,
    /// Terrain pixels of all views that show a skirt.
    pub skirt_pixels: usize,
    /// The largest error over pixels that show no skirt.
    pub max_surface_px: f64,
    /// One row per view, in the order measured.
    pub views: Vec<ViewRow>,
    /// The view with the largest p99.9 error; `None` when there were no views.
    pub worst: Option<WorstView>,
    /// The error against the geodetic truth, when it was measured.
    pub earth: Option<EarthSummary>,
}

/// Where the full-resolution image of a view comes from.
#[derive(Clone, Copy)]
pub enum Truth<'a> {
    /// The full-resolution mesh, drawn on the GPU in the display's context.
    Mesh(&'a TruthPass),
    /// Each pixel's ray followed on the CPU against the exact heights
    /// ([`trace_truth`]); triangles counted in the frustum, not drawn.
    Rays(RayGround<'a>),
}

impl Truth<'_> {
    /// The route's name in `accuracy.json`: `gpu_mesh` or `cpu_rays`.
    pub fn route(&self) -> &'static str {
        match self {
            Truth::Mesh(_) => "gpu_mesh",
            Truth::Rays(_) => "cpu_rays",
        }
    }
}

/// Measures `views` (times along a path with their cameras) on `display`,
/// against `truth` drawn in the same context and `exact`, the
/// full-resolution surface over level-0 posts `spacing_m` apart.
pub fn measure_flight(
    display: &mut DisplayParts,
    truth: &TruthPass,
    exact: ExactHeight<'_>,
    spacing_m: [f64; 2],
    views: &[(f64, Camera)],
) -> Result<AccuracyRun, DisplayError> {
    measure_flight_with(display, Truth::Mesh(truth), exact, spacing_m, views)
}

/// [`measure_flight`] against either [`Truth`].
pub fn measure_flight_with(
    display: &mut DisplayParts,
    truth: Truth<'_>,
    exact: ExactHeight<'_>,
    spacing_m: [f64; 2],
    views: &[(f64, Camera)],
) -> Result<AccuracyRun, DisplayError> {
    measure_flight_on_earth(display, truth, None, exact, spacing_m, views)
}

/// [`measure_flight_with`], and against the geodetic truth `earth` too.
pub fn measure_flight_on_earth(
    display: &mut DisplayParts,
    truth: Truth<'_>,
    earth: Option<&EarthTruth<'_>>,
    exact: ExactHeight<'_>,
    spacing_m: [f64; 2],
    views: &[(f64, Camera)],
) -> Result<AccuracyRun, DisplayError> {
    let tau_px = display.pipeline.scene().config().lod.tau_px;
    let size = display.context.size();
    // Another display on this thread may have made its context current:
    // the position target must be made in this one.
    display.context.make_current()?;
    let positions = OffscreenTarget::positions(display.context.gl(), size)?;
    let mut images = [PositionImage::default(), PositionImage::default()];
    let mut errors = ViewErrors::default();
    let mut earth_buffers = (EarthImage::default(), EarthErrors::default());
    let mut tally = Tally::default();
    let mut rows: Vec<ViewRow> = Vec::with_capacity(views.len());
    let mut worst: Option<WorstView> = None;
    if let Some((_, first)) = views.first() {
        // Warm-up, untimed: shaders compile and buffers fault in on first use.
        display.pipeline.settle(first, SETTLE_UPDATES)?;
        display.frame(first)?;
        if let Truth::Mesh(truth) = truth {
            draw_truth(display, truth)?;
        }
    }
    for (t, camera) in views {
        let passes = Passes { truth, positions: &positions, earth };
        let buffers =
            Buffers { images: &mut images, errors: &mut errors, earth: &mut earth_buffers };
        let row = measure_one(display, passes, exact, spacing_m, *t, camera, buffers)?;
        tally.add(&errors, earth.map(|_| &earth_buffers.1));
        let is_worse = |w: &WorstView| {
            let best = &rows[w.index].errors;
            (row.errors.p999_px, row.errors.max_px) > (best.p999_px, best.max_px)
        };
        if worst.as_ref().is_none_or(is_worse) {
            let [lod, truth_positions] = &images;
            let heat_map = heat_map(&errors.errors_px, lod, truth_positions, tau_px);
            display.frame(camera)?;
            let picture = display.context.read_pixels()?;
            worst = Some(WorstView { index: rows.len(), heat_map, picture });
        }
        rows.push(row);
    }
    Ok(tally.run(tau_px, truth.route(), earth, rows, worst))
}

/// The flight's pixels, summed over its views.
#[derive(Default)]
struct Tally {
    errors: Vec<f32>,
    mismatched: usize,
    pixels: usize,
    holes: usize,
    earth_errors: Vec<f32>,
    earth_mismatched: usize,
    earth_pixels: usize,
}

impl Tally {
    /// Adds a view's `errors`, and `earth`'s against the geodetic truth.
    fn add(&mut self, errors: &ViewErrors, earth: Option<&EarthErrors>) {
        self.errors.extend(errors.errors_px.iter().copied().filter(|e| !e.is_nan()));
        if let Some(errors) = earth {
            self.earth_errors.extend(errors.errors_px.iter().copied().filter(|e| !e.is_nan()));
            self.earth_mismatched += errors.lod_only + errors.truth_only;
            self.earth_pixels += errors.errors_px.len();
        }
        self.mismatched += errors.lod_only + errors.truth_only + errors.no_data;
        self.pixels += errors.errors_px.len();
        self.holes += errors.holes;
    }

    /// The run of `rows` at `tau_px` against `truth` (its route) and `earth`.
    fn run(
        mut self,
        tau_px: f64,
        truth: &'static str,
        earth: Option<&EarthTruth<'_>>,
        rows: Vec<ViewRow>,
        worst: Option<WorstView>,
    ) -> AccuracyRun {
        let (mismatched, pixels, holes) = (self.mismatched, self.pixels, self.holes);
        let summary = ErrorSummary::of(&mut self.errors);
        let coverage_mismatch = if pixels == 0 { 0.0 } else { mismatched as f64 / pixels as f64 };
        let (earth_mismatched, earth_pixels) = (self.earth_mismatched, self.earth_pixels);
        let mut earth_all = self.earth_errors;
        let skirt_pixels = rows.iter().map(|r| r.skirt_pixels).sum();
        let max_surface_px = rows.iter().map(|r| r.max_surface_px).fold(0.0, f64::max);
        let tau_achieved_max_px = rows.iter().map(|r| r.tau_px).fold(tau_px, f64::max);
        let tau_loosened_views = rows.iter().filter(|r| r.tau_px > tau_px).count();
        let earth = earth.map(|earth| EarthSummary {
            errors: ErrorSummary::of(&mut earth_all),
            coverage_mismatch: earth_mismatched as f64 / earth_pixels.max(1) as f64,
            holes: rows.iter().filter_map(|r| r.earth.as_ref()).map(|e| e.holes).sum(),
            stride: earth.stride,
            truth_ms: rows.iter().filter_map(|r| r.earth.as_ref()).map(|e| e.truth_ms).sum::<f64>()
                / rows.len().max(1) as f64,
        });
        AccuracyRun {
            tau_px,
            truth,
            tau_achieved_max_px,
            tau_loosened_views,
            summary,
            coverage_mismatch,
            holes,
            skirt_pixels,
            max_surface_px,
            views: rows,
            worst,
            earth,
        }
    }
}

/// The passes drawn beside each LOD frame.
#[derive(Clone, Copy)]
struct Passes<'a> {
    truth: Truth<'a>,
    positions: &'a OffscreenTarget,
    earth: Option<&'a EarthTruth<'a>>,
}

/// What one view's measurement writes into, kept between views.
struct Buffers<'a> {
    images: &'a mut [PositionImage; 2],
    errors: &'a mut ViewErrors,
    earth: &'a mut (EarthImage, EarthErrors),
}

fn measure_one(
    display: &mut DisplayParts,
    passes: Passes<'_>,
    exact: ExactHeight<'_>,
    spacing_m: [f64; 2],
    t: f64,
    camera: &Camera,
    buffers: Buffers<'_>,
) -> Result<ViewRow, DisplayError> {
    let Buffers { images, errors, earth: earth_buffers } = buffers;
    let lod_stats = steady_frame(display, camera)?;
    let [lod, truth_positions] = images;
    let frame = lod_positions(display, passes.positions, lod)?;
    let placement = display.pipeline.scene().config().earth;
    let geometry = ViewGeometry::new(camera, &frame).on_earth(&frame, placement);
    let truth_stats = truth_positions_of(display, passes, &frame, &geometry, truth_positions)?;
    display.context.bind_target();
    let scene = display.pipeline.scene();
    let list = scene.draw_list();
    let grid_size = scene.config().lod.grid_size;
    let (staging, _) = scene.uploads();
    let eye = DVec2::new(camera.position.x, camera.position.y);
    let surface = LodSurface::new(list, staging, grid_size, spacing_m, eye);
    measure_view(&geometry, lod, truth_positions, &surface, staging, exact, errors);
    let earth = passes.earth.map(|earth| {
        let heights = |x: f64, y: f64| surface.earth_height_at(staging, x, y);
        let frame = DisplayFrame::of(earth.placement, camera, &frame);
        measure_view_on_earth(earth, &frame, camera, &heights, lod, earth_buffers)
    });
    let mut view_errors: Vec<f32> =
        errors.errors_px.iter().copied().filter(|e| !e.is_nan()).collect();
    Ok(ViewRow {
        t,
        tau_px: lod_stats.scene.bound_px,
        errors: ErrorSummary::of(&mut view_errors),
        coverage_mismatch: (errors.lod_only + errors.truth_only + errors.no_data) as f64
            / errors.errors_px.len().max(1) as f64,
        silhouette: errors.silhouette,
        lod_only: errors.lod_only,
        truth_only: errors.truth_only,
        no_data: errors.no_data,
        holes: errors.holes,
        skirt_pixels: errors.skirt_pixels,
        max_surface_px: errors.max_surface_px,
        worst_skirt: probe_worst_skirt(&surface, staging, &geometry, lod, errors),
        truth_only_probe: probe_truth_only(&surface, staging, &geometry, truth_positions, errors),
        mirror_p99_m: mirror_p99_m(errors),
        triangles_lod: surface.surface_triangles(),
        triangles_truth: truth_stats.triangles,
        draw_calls_lod: lod_stats.calls.draw_calls as usize,
        draw_calls_truth: truth_stats.draw_calls,
        tiles_per_level: tiles_per_level(list),
        horizon_culled: lod_stats.scene.horizon_culled,
        lod_frame_ms: lod_stats.frame_ms,
        truth_frame_ms: truth_stats.frame_ms,
        earth,
    })
}

/// The steady frame a display shows at `camera`, timed: paged in, then a
/// first frame that makes and uploads its tiles, and with a frame budget
/// the frames its controller takes to settle at the pose.
fn steady_frame(display: &mut DisplayParts, camera: &Camera) -> Result<FrameStats, DisplayError> {
    display.pipeline.settle(camera, SETTLE_UPDATES)?;
    display.frame(camera)?;
    for _ in 0..BUDGET_FRAMES {
        match display.pipeline.budget() {
            Some(budget) if !budget.steady() => display.frame(camera)?,
            _ => break,
        };
    }
    display.frame(camera)
}

/// The truth's positions of the view drawn in `frame` (by the truth pass
/// drawn in the same context, or traced by rays), into `out`, and what
/// drawing it cost.
fn truth_positions_of(
    display: &mut DisplayParts,
    passes: Passes<'_>,
    frame: &FrameUniforms,
    geometry: &ViewGeometry,
    out: &mut PositionImage,
) -> Result<TruthFrameStats, DisplayError> {
    Ok(match passes.truth {
        Truth::Mesh(truth) => {
            let stats = draw_truth(display, truth)?;
            passes.positions.bind();
            // No tiles: the cleared target under the truth's positions.
            display.renderer.draw_positions(&DrawList::default(), frame)?;
            truth.draw(frame, crate::gl::TerrainOutput::Position)?;
            passes.positions.read_positions(out)?;
            stats
        }
        Truth::Rays(ground) => trace_view(display, geometry, &ground, out),
    })
}

/// The 99th percentile of how far the mirror's surface lies from the
/// drawn one, metres (0 without any).
fn mirror_p99_m(errors: &ViewErrors) -> f64 {
    let mut mirror: Vec<f32> = errors.mirror_m.iter().copied().filter(|e| !e.is_nan()).collect();
    mirror.sort_unstable_by(f32::total_cmp);
    if mirror.is_empty() {
        0.0
    } else {
        percentile(&mirror, 0.99)
    }
}

/// How many of `list`'s tiles each level has.
fn tiles_per_level(list: &DrawList) -> Vec<usize> {
    let mut tiles = vec![0; list.tiles.iter().map(|t| t.key.level as usize + 1).max().unwrap_or(0)];
    for tile in &list.tiles {
        tiles[tile.key.level as usize] += 1;
    }
    tiles
}

/// One view against the geodetic truth: the true camera's rays, then the
/// display's positions `lod` (drawn in `frame`, its surface `heights` at a
/// chart point) measured against them.
fn measure_view_on_earth(
    earth: &EarthTruth<'_>,
    frame: &DisplayFrame,
    camera: &Camera,
    heights: &(dyn Fn(f64, f64) -> Option<f64> + Sync),
    lod: &PositionImage,
    (image, errors): &mut (EarthImage, EarthErrors),
) -> EarthRow {
    let start = Instant::now();
    let true_camera = TrueCamera::new(camera, &earth.placement);
    trace_earth(&true_camera, earth.ground, earth.stride, earth.reach_m, image);
    let truth_ms = start.elapsed().as_secs_f64() * 1e3;
    let view = EarthView { frame, camera: &true_camera, ground: earth.ground, surface: heights };
    measure_earth(&view, lod, image, errors);
    let mut values: Vec<f32> = errors.errors_px.iter().copied().filter(|e| !e.is_nan()).collect();
    EarthRow {
        errors: ErrorSummary::of(&mut values),
        coverage_mismatch: (errors.lod_only + errors.truth_only) as f64
            / errors.errors_px.len().max(1) as f64,
        silhouette: errors.silhouette,
        holes: errors.holes,
        truth_ms,
    }
}

/// The positions of the frame the pipeline drew last, into `out`
/// (through the `positions` target); returns its uniforms.
fn lod_positions(
    display: &mut DisplayParts,
    positions: &OffscreenTarget,
    out: &mut PositionImage,
) -> Result<FrameUniforms, DisplayError> {
    let frame = frame_of(display.pipeline.draw_list())?;
    positions.bind();
    display.renderer.draw_positions(display.pipeline.draw_list(), &frame)?;
    positions.read_positions(out)?;
    Ok(frame)
}

/// The view's first pixel where only the truth shows terrain, followed to
/// the drawn surface's coverage there.
fn probe_truth_only(
    surface: &LodSurface,
    staging: &[u8],
    geometry: &ViewGeometry,
    truth_positions: &PositionImage,
    errors: &ViewErrors,
) -> Option<CoverageProbe> {
    let pixel = errors.truth_only_pixel?;
    let (ground, _) = geometry.ground(truth_positions.point(pixel)?.as_dvec3());
    Some(surface.probe_coverage(staging, pixel, ground.into()))
}

/// The view's worst skirt pixel, followed to its tile edge.
fn probe_worst_skirt(
    surface: &LodSurface,
    staging: &[u8],
    geometry: &ViewGeometry,
    lod: &PositionImage,
    errors: &ViewErrors,
) -> Option<SkirtProbe> {
    let (pixel, error) = errors.worst_skirt?;
    let (ground, drawn) = geometry.ground(lod.point(pixel)?.as_dvec3());
    surface.probe_skirt(staging, (pixel, error), ground.into(), drawn)
}

/// The truth of one view by rays: its positions, the rays' time, and the
/// full-resolution triangles in its frustum above the horizon, counted.
fn trace_view(
    display: &DisplayParts,
    geometry: &ViewGeometry,
    ground: &RayGround<'_>,
    out: &mut PositionImage,
) -> TruthFrameStats {
    let start = Instant::now();
    trace_truth(geometry, ground, out);
    let frame_ms = start.elapsed().as_secs_f64() * 1e3;
    // The frame just drawn was of this view's camera: its view is the census's.
    let census = display.pipeline.scene().census(&display.pipeline.terrain());
    TruthFrameStats { triangles: census.map_or(0, |c| 2 * c.cells), draw_calls: 0, frame_ms }
}

/// The uniforms of the frame the pipeline drew last.
fn frame_of(list: &DrawList) -> Result<FrameUniforms, DisplayError> {
    let why = "the accuracy passes need a frame drawn first";
    list.uniforms.ok_or_else(|| GlError::InvalidRequest(why.to_owned()).into())
}

/// Draws the truth into the display's target with the last LOD frame's
/// uniforms: the same clear and sky, then every chunk, waiting for the GPU.
/// Touches neither the clipmap nor the tile cache.
pub fn draw_truth(
    display: &mut DisplayParts,
    truth: &TruthPass,
) -> Result<TruthFrameStats, DisplayError> {
    let frame = frame_of(display.pipeline.draw_list())?;
    let start = Instant::now();
    display.context.make_current()?;
    display.context.bind_target();
    display.renderer.draw_background(&frame)?;
    truth.draw(&frame, crate::gl::TerrainOutput::Colour)?;
    display.renderer.finish();
    // The truth's calls are not the display's: leave them out of its counts.
    display.renderer.take_calls();
    let frame_ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(TruthFrameStats { triangles: truth.triangles(), draw_calls: truth.draw_calls(), frame_ms })
}
