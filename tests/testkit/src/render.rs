//! What the rendering regression tests share: the built-in terrain (built once
//! into the target's temporary directory, so child processes and later runs
//! reuse it), displays over it that draw complete, repeatable frames, the
//! fixed views, and the image comparison ([`compare`]).

use crate::{builtin_pyramid, compare, coverage};

use glam::{DVec2, UVec2};
use image::RgbaImage;
use ridgeline::camera::Camera;
use ridgeline::clipmap::LoaderMode;
use ridgeline::display::{DisplayConfig, DisplayError, DisplayParts};
use ridgeline::gl::{GlBackend, GlesVersion};
use ridgeline::lod::TileKey;
use ridgeline::pipeline::FrameStats;
use ridgeline::pyramid::Pyramid;
use ridgeline::render::{DrawList, RenderBackend};
use ridgeline::scene::TerrainSummary;
use std::collections::BTreeSet;
use std::sync::Arc;

/// Small enough that llvmpipe draws a frame in milliseconds, large enough to
/// see every level of detail (Ulrich's bound is in pixels of this viewport).
pub const SIZE: UVec2 = UVec2::new(256, 144);

/// Clear colour with the sky off: any pixel left this colour is not terrain.
pub const SENTINEL: [f32; 4] = [1.0, 0.0, 1.0, 1.0];
pub const SENTINEL_RGBA: [u8; 4] = [255, 0, 255, 255];

/// How closely two renders of one view must agree, across backends
/// (EGL, OSMesa, a window) and context versions (ES 2.0, ES 3), and against
/// the golden images (see [`compare`] for the metric). Measured on Mesa
/// 22.3.6 (llvmpipe): EGL, OSMesa and ES 2.0, with 128- or 256-bit vectors,
/// give identical pixels; a window under Xvfb differs in 30 of 36864 pixels,
/// 2 of them by more than 16 (far ridges at the skyline, where the depth
/// buffer decides); softpipe, a different rasteriser, differs in 0.005% of
/// pixels by at most 10 (mean 0.002). Moving the camera 5 m, changing tau
/// from 1 to 2 px or turning 0.2 degrees gives a mean of 0.22 to 1.8, so the
/// mean bound of 0.1 sits 50 times above driver noise and 2 times below the
/// smallest change that matters; the share bound (7 pixels) takes the
/// window's stray pixels with a margin of 3.
pub const TOLERANCE: compare::Tolerance =
    compare::Tolerance { channel_threshold: 16, max_share_over: 0.0002, max_mean: 0.1 };

/// Terrain height under `(x, y)` metres from the built-in SRTM tile's
/// south-west post ([`crate::builtin_origin`]); the views stay inside the data.
pub fn ground(x: f64, y: f64) -> f64 {
    let origin = crate::builtin_origin();
    builtin_pyramid()
        .exact_height(origin.x + x, origin.y + y)
        .unwrap_or_else(|| panic!("({x}, {y}) is outside the terrain")) as f64
}

/// A display whose frames are complete and repeatable: nodes load inline with
/// a budget no view exhausts, and every view is settled before it is drawn.
pub fn config(backend: GlBackend, version: GlesVersion) -> DisplayConfig {
    DisplayConfig {
        version,
        loader: LoaderMode::Inline,
        load_budget: 1000,
        ..DisplayConfig::new(backend, SIZE)
    }
}

/// A display over the built-in terrain, tiles cut from its node meshes for
/// the config's tau (what `ridgeline fly` draws).
pub fn open(config: &DisplayConfig) -> Result<DisplayParts, DisplayError> {
    let terrain = crate::builtin_terrain();
    let summary = crate::summary_of(&terrain);
    DisplayParts::open(config, terrain, summary)
}

/// A display over the built-in terrain, tiles drawn as regular grids
/// (`ridgeline fly --regular-grid`).
pub fn open_grid(config: &DisplayConfig) -> Result<DisplayParts, DisplayError> {
    open_over(config, builtin_pyramid())
}

/// A display over `pyramid`, tiles drawn as regular grids of its posts.
pub fn open_over(
    config: &DisplayConfig,
    pyramid: Arc<Pyramid>,
) -> Result<DisplayParts, DisplayError> {
    let summary = TerrainSummary::from_pyramid(pyramid.info());
    DisplayParts::open(config, pyramid, summary)
}

/// A named fixed view over the built-in terrain (local metres, degrees).
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub name: &'static str,
    pub x: f64,
    pub y: f64,
    pub altitude: f64,
    pub heading: f64,
    pub pitch: f64,
}

impl View {
    pub fn camera(&self) -> Camera {
        let position = crate::over_tile(self.x, self.y, self.altitude);
        crate::camera(SIZE.into(), position, self.heading, self.pitch)
    }
}

/// The golden views: a medium one, a low one among ridges higher than the
/// aircraft (amber and red terrain-awareness bands), a high one looking
/// steeply down, all over the built-in SRTM tile (positions relative to its
/// south-west post) and looking across it. Beyond the tile the ETOPO5 base
/// carries the terrain to the horizon: no view shows an edge of the data.
pub const VIEWS: [View; 3] = [
    View {
        name: "medium",
        x: 30_000.0,
        y: 40_000.0,
        altitude: 3_500.0,
        heading: 45.0,
        pitch: -8.0,
    },
    View { name: "low", x: 20_000.0, y: 60_000.0, altitude: 2_600.0, heading: 120.0, pitch: -15.0 },
    View { name: "high", x: 35_000.0, y: 45_000.0, altitude: 9_000.0, heading: 0.0, pitch: -30.0 },
];

/// Pages in everything `camera` wants, draws it and reads it back (a test
/// may hold two displays on one thread: the frame makes its context current).
pub fn render(display: &mut DisplayParts, camera: &Camera) -> (RgbaImage, FrameStats) {
    display.pipeline.settle(camera, 1000).expect("settle");
    let stats = display.frame(camera).expect("frame");
    (display.context.read_pixels().expect("read back"), stats)
}

/// Draws the last frame's draw list again, changed by `alter`, and reads it
/// back: the same uploads, so only what `alter` changed differs. Tests use it
/// to break the picture on purpose and show their checks notice.
pub fn redraw(display: &mut DisplayParts, alter: impl FnOnce(&mut DrawList)) -> RgbaImage {
    let mut list = display.pipeline.draw_list().clone();
    alter(&mut list);
    display.context.make_current().expect("make the display's context current");
    display.context.bind_target();
    let uniforms = list.uniforms.expect("the last frame's list has uniforms");
    display.renderer.draw_frame(&list, &uniforms).expect("redraw");
    display.renderer.finish();
    display.context.read_pixels().expect("read back")
}

/// The data rectangle (the whole base: terrain reaches every corner of it)
/// less `margin_m` on every side, and the lowest height, for
/// [`coverage::terrain_guaranteed`].
pub fn terrain_bounds(margin_m: f64) -> coverage::TerrainBounds {
    let pyramid = builtin_pyramid();
    let layout = *ridgeline::node::NodeSource::layout(&*pyramid);
    let [sx, sy] = layout.spacing_m;
    let extent = DVec2::new((layout.posts[0] - 1) as f64 * sx, (layout.posts[1] - 1) as f64 * sy);
    // A triangle of the coarsest level may reach this far beyond a point on it.
    let coarsest_post = (1u64 << (layout.levels - 1)) as f64 * sx.max(sy);
    coverage::TerrainBounds {
        min: DVec2::splat(margin_m),
        max: extent - margin_m,
        lowest_m: pyramid.info().stats.height_min as f64,
        reach_slack_m: coarsest_post * std::f64::consts::SQRT_2,
    }
}

/// The tiles of the display's last frame.
pub fn drawn_tiles(display: &DisplayParts) -> BTreeSet<TileKey> {
    display.pipeline.draw_list().tiles.iter().map(|tile| tile.key).collect()
}

/// Whether going from `before` to `after` split or merged a tile (tiles that
/// merely entered or left the view do not count).
pub fn lod_changed(before: &BTreeSet<TileKey>, after: &BTreeSet<TileKey>) -> bool {
    let related = |key: &TileKey, other: &BTreeSet<TileKey>| {
        other.contains(&key.parent())
            || (key.level > 0 && key.children().iter().any(|child| other.contains(child)))
    };
    after.difference(before).any(|key| related(key, before))
        || before.difference(after).any(|key| related(key, after))
}

/// `ridgeline accuracy`'s measurement of `views` over `pyramid` at
/// `tau_px`, at the render tests' size on EGL: one tile of view distance (so
/// Ulrich's bound, not Kühnert's three-tile rings, sets the rings at this
/// small viewport), the truth a window of level 0 around the views.
pub fn measure_accuracy(
    pyramid: Arc<Pyramid>,
    views: &[(f64, Camera)],
    tau_px: f64,
) -> ridgeline::display::measure::AccuracyRun {
    measure_accuracy_of(pyramid, views, tau_px, false)
}

/// [`measure_accuracy`], the tiles drawn from node meshes when `meshed`.
pub fn measure_accuracy_of(
    pyramid: Arc<Pyramid>,
    views: &[(f64, Camera)],
    tau_px: f64,
    meshed: bool,
) -> ridgeline::display::measure::AccuracyRun {
    measure_accuracy_budgeted(pyramid, views, tau_px, meshed, None)
}

/// [`measure_accuracy_of`] holding `triangle_budget` triangles a frame
/// (`--triangle-budget`) by raising tau above `tau_px` where it must.
pub fn measure_accuracy_budgeted(
    pyramid: Arc<Pyramid>,
    views: &[(f64, Camera)],
    tau_px: f64,
    meshed: bool,
    triangle_budget: Option<u64>,
) -> ridgeline::display::measure::AccuracyRun {
    use ridgeline::gl::{TruthMesh, TruthPass, TruthRegion};
    use ridgeline::lod::budget::{BudgetConfig, BudgetTarget};
    let mut config = config(GlBackend::Egl, GlesVersion::Es3);
    config.scene.lod.tau_px = tau_px;
    // Under a budget the display's own view distance: at one tile, the
    // rings sit at the floor that keeps neighbours within a level at this
    // size, and no tau above 1 draws fewer triangles.
    if triangle_budget.is_none() {
        config.scene.lod.view_distance = 1.0;
    }
    config.budget = triangle_budget.map(|n| BudgetConfig::new(BudgetTarget::Triangles(n)));
    let mut display = if meshed {
        let terrain = Arc::new(crate::meshed(pyramid.clone()));
        let summary = crate::summary_of(&terrain);
        DisplayParts::open(&config, terrain, summary).expect("headless EGL display")
    } else {
        open_over(&config, pyramid.clone()).expect("headless EGL display")
    };
    let layout = pyramid.info().layout;
    let positions = views.iter().map(|(_, c)| [c.position.x, c.position.y]);
    let region = TruthRegion::around_positions(&layout, config.scene.lod.grid_size, positions);
    let mesh = TruthMesh::load(pyramid.as_ref(), region).expect("truth mesh");
    let truth = TruthPass::new(display.context.gl(), &mesh).expect("truth pass");
    let exact = |x: f64, y: f64| pyramid.exact_height(x, y);
    ridgeline::display::measure::measure_flight(&mut display, &truth, &exact, layout.spacing_m, views)
        .expect("measured")
}

/// The hatching's two greys (`palette::NO_DATA_HATCH`, 0.22 0.22 0.24, and twice
/// it), within rounding.
pub fn is_hatching([r, g, b, _]: [u8; 4]) -> bool {
    let near = |[er, eg, eb]: [f32; 3]| {
        [(r, er), (g, eg), (b, eb)].iter().all(|&(c, e)| (c as f32 - e * 255.0).abs() <= 2.0)
    };
    near([0.22, 0.22, 0.24]) || near([0.44, 0.44, 0.48])
}

/// The topmost row of a `rows`-row viewport whose pixel-centre ray, in
/// `column`, meets the WGS 84 ellipsoid (solved exactly, in f64, from the
/// true camera): the geometric horizon.
pub fn geometric_horizon_row(
    eye: &ridgeline::accuracy::TrueCamera,
    column: u32,
    rows: u32,
) -> Option<u32> {
    use ridgeline::earth::ellipsoid::{A, B};
    let scale = glam::DVec3::new(1.0 / A, 1.0 / A, 1.0 / B);
    let p = eye.eye * scale;
    (0..rows).find(|&row| {
        let d = eye.ray(DVec2::new(column as f64 + 0.5, row as f64 + 0.5)) * scale;
        // |p + t d| = 1 for some t > 0: p is outside, so a real root ahead.
        let (a, b, c) = (d.length_squared(), 2.0 * p.dot(d), p.length_squared() - 1.0);
        b < 0.0 && b * b - 4.0 * a * c >= 0.0
    })
}
