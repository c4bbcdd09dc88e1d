//! The display put together: a GL context and renderer, the scene, and the
//! chunked clipmap paging a node source, one call per frame. `fly`, the
//! accuracy tool, the regression tests and the render bench all drive this.

use crate::accuracy::PositionImage;
use crate::camera::Camera;
use crate::clipmap::{
    Clipmap, ClipmapConfig, ClipmapError, LoaderMode, UpdateStats, ViewConfig, ViewId,
};
use crate::gl::{
    BaselineFrameStats, ChunkedBaseline, ContextRequest, GlBackend, GlContext, GlError, GlInfo,
    GlRenderer, GlesVersion, OffscreenTarget, TerrainOutput, TruthFrameStats, TruthPass,
};
use crate::lod::ranges::RingInputs;
use crate::lod::LevelRanges;
use crate::node::NodeSource;
use crate::render::{DrawList, FrameUniforms, RenderBackend};
use crate::scene::{ClipmapTerrain, FrameReport, Scene, SceneConfig, SceneError, TerrainSummary};
use glam::{DVec3, UVec2};
use image::RgbaImage;
use std::sync::Arc;
use std::time::Instant;

/// Everything fixed for one display.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplayConfig {
    pub backend: GlBackend,
    pub version: GlesVersion,
    pub size: UVec2,
    pub scene: SceneConfig,
    /// Field of view used to size the clipmap's load radius (the rings depend on it).
    pub fov_x_deg: f64,
    /// Loads copied into the node atlas per frame.
    pub load_budget: u32,
    /// Load nodes on a thread (flying) or inline up to the budget (tests that
    /// want every frame complete and repeatable).
    pub loader: LoaderMode,
    /// Clear to this colour and skip the sky (hole detection in tests).
    pub sentinel: Option<[f32; 4]>,
}

impl DisplayConfig {
    pub fn new(backend: GlBackend, size: UVec2) -> Self {
        DisplayConfig {
            backend,
            version: GlesVersion::Es3,
            size,
            scene: SceneConfig::default(),
            fov_x_deg: 60.0,
            load_budget: 32,
            loader: LoaderMode::Thread { queue: 256 },
            sentinel: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum DisplayError {
    #[error(transparent)]
    Gl(#[from] GlError),
    #[error(transparent)]
    Clipmap(#[from] ClipmapError),
    #[error(transparent)]
    Scene(#[from] SceneError),
}

/// What one frame did and cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    #[serde(flatten)]
    pub scene: FrameReport,
    pub draw_calls: usize,
    pub resident_nodes: u32,
    pub nodes_loaded: u32,
    pub clipmap_ms: f64,
    pub gl_ms: f64,
    /// Whole frame on the CPU and GPU, measured up to glFinish.
    pub frame_ms: f64,
}

pub struct Display {
    // Field order is drop order: GL objects before their context.
    renderer: GlRenderer,
    /// RGBA32F target of the accuracy tool's position renders, made on first use.
    positions: Option<OffscreenTarget>,
    context: GlContext,
    scene: Scene,
    clipmap: Clipmap,
    view: ViewId,
    summary: TerrainSummary,
    /// A baseline frame skipped the renderer's uploads: its height buffer
    /// must be rewritten whole before it draws again.
    renderer_stale: bool,
}

impl Display {
    /// Opens the context and builds the clipmap over `source` (whose per-level
    /// error and height range `summary` gives).
    pub fn new(
        config: &DisplayConfig,
        source: Arc<dyn NodeSource>,
        summary: TerrainSummary,
    ) -> Result<Display, DisplayError> {
        let mut request = ContextRequest::new(config.backend, config.version, config.size);
        request.title = "Ridgeline".to_owned();
        let context = GlContext::new(&request)?;
        let layout = *source.layout();
        let view_config = view_config(config, &summary, &layout);
        let slots = atlas_slots(&view_config, layout.levels);
        let clipmap_config =
            ClipmapConfig { atlas_slots: slots, budget: config.load_budget, loader: config.loader };
        let mut clipmap = Clipmap::new(source, clipmap_config)?;
        let view = clipmap.add_view(view_config, DVec3::ZERO)?;
        let terrain = ClipmapTerrain { clipmap: &clipmap, summary: &summary };
        let scene = Scene::new(config.scene, &terrain)?;
        let mut renderer =
            GlRenderer::new(context.gl(), config.scene.lod.grid_size, config.scene.buffer_bytes)?;
        renderer.set_sentinel(config.sentinel);
        Ok(Display {
            renderer,
            positions: None,
            context,
            scene,
            clipmap,
            view,
            summary,
            renderer_stale: false,
        })
    }

    pub fn info(&self) -> &GlInfo {
        self.context.info()
    }

    pub fn context(&self) -> &GlContext {
        &self.context
    }

    pub fn context_mut(&mut self) -> &mut GlContext {
        &mut self.context
    }

    /// The GL renderer, for tests that redraw the last frame's draw list
    /// altered (a tile dropped, morphing or skirts off) to prove that their
    /// image checks would catch such a fault.
    pub fn renderer_mut(&mut self) -> &mut GlRenderer {
        &mut self.renderer
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn clipmap(&self) -> &Clipmap {
        &self.clipmap
    }

    /// Pages, tiles, uploads and draws one frame for `camera`, then waits for
    /// the GPU (glFinish) so `frame_ms` is the whole frame.
    pub fn frame(&mut self, camera: &Camera) -> Result<FrameStats, DisplayError> {
        self.frame_through(camera, None).map(|(stats, _)| stats)
    }

    /// [`Self::frame`] drawn by plain Chunked LOD instead of the batched
    /// renderer: the same paging, tiles and sky, then `baseline` uploads each
    /// new tile by itself and draws every tile from its own buffer.
    pub fn frame_baseline(
        &mut self,
        camera: &Camera,
        baseline: &mut ChunkedBaseline,
    ) -> Result<(FrameStats, BaselineFrameStats), DisplayError> {
        self.frame_through(camera, Some(baseline))
            .map(|(stats, base)| (stats, base.unwrap_or_default()))
    }

    fn frame_through(
        &mut self,
        camera: &Camera,
        baseline: Option<&mut ChunkedBaseline>,
    ) -> Result<(FrameStats, Option<BaselineFrameStats>), DisplayError> {
        let start = Instant::now();
        // Another display on this thread may have made its context current.
        self.context.make_current()?;
        self.clipmap.set_view_position(self.view, camera.position)?;
        let update: UpdateStats = self.clipmap.update()?;
        let paged = Instant::now();
        let terrain = ClipmapTerrain { clipmap: &self.clipmap, summary: &self.summary };
        let report = self.scene.frame(camera, &terrain)?;
        let tiled = Instant::now();
        self.context.bind_target();
        let (staging, ranges) = self.scene.uploads();
        let list = self.scene.draw_list();
        let base = match baseline {
            None => {
                // After baseline frames the whole buffer, else this frame's ranges.
                if !Self::catch_up(&mut self.renderer, staging, &mut self.renderer_stale)? {
                    self.renderer.upload(staging, ranges)?;
                }
                self.renderer.draw(list)?;
                None
            }
            Some(baseline) => {
                // Clear and sky only, then the baseline's tiles.
                self.renderer.draw(&DrawList { frame: list.frame, ..DrawList::default() })?;
                self.renderer_stale = true;
                Some(baseline.frame(list, staging, ranges)?)
            }
        };
        self.renderer.finish();
        let done = Instant::now();
        let stats = FrameStats {
            scene: report,
            draw_calls: list.tiles.len(),
            resident_nodes: self.clipmap.atlas().resident_count(),
            nodes_loaded: update.applied,
            clipmap_ms: (paged - start).as_secs_f64() * 1e3,
            gl_ms: (done - tiled).as_secs_f64() * 1e3,
            frame_ms: (done - start).as_secs_f64() * 1e3,
        };
        Ok((stats, base))
    }

    /// The frame uniforms the scene draws `camera` with (the same near and
    /// far planes, bands and sun), for passes drawn beside it.
    pub fn frame_uniforms(&self, camera: &Camera) -> FrameUniforms {
        let terrain = ClipmapTerrain { clipmap: &self.clipmap, summary: &self.summary };
        self.scene.frame_uniforms(camera, &terrain)
    }

    /// Draws `camera`'s view of the brute-force ground truth into this
    /// display's target: the same clear and sky as [`Self::frame`], then every
    /// chunk of `truth` (built on [`Self::context`]), waiting for the GPU.
    /// Touches neither the clipmap nor the tile cache, so it may be
    /// interleaved with LOD frames; [`Self::read_pixels`] reads the result.
    pub fn render_truth(
        &mut self,
        camera: &Camera,
        truth: &TruthPass,
    ) -> Result<TruthFrameStats, DisplayError> {
        camera.validate().map_err(SceneError::from)?;
        let start = Instant::now();
        self.context.make_current()?;
        let frame = self.frame_uniforms(camera);
        self.context.bind_target();
        // A list without tiles: the renderer clears and draws the sky only.
        self.renderer.draw(&DrawList { frame: Some(frame), ..DrawList::default() })?;
        truth.draw(&frame, TerrainOutput::Colour)?;
        self.renderer.finish();
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(TruthFrameStats {
            triangles: truth.triangles(),
            draw_calls: truth.draw_calls(),
            frame_ms,
        })
    }

    /// Redraws the last frame's tiles (drawn by [`Self::frame`] for this same
    /// `camera`) as camera-relative positions into `out`: what the display
    /// drew, per pixel, for the accuracy tool. Needs float colour buffers.
    pub fn render_positions(
        &mut self,
        camera: &Camera,
        out: &mut PositionImage,
    ) -> Result<(), DisplayError> {
        let list = self.scene.draw_list();
        if list.frame != Some(self.frame_uniforms(camera)) {
            let why =
                "render_positions needs the last frame to have been drawn for the same camera";
            return Err(GlError::InvalidRequest(why.to_owned()).into());
        }
        self.bind_positions()?;
        Self::catch_up(&mut self.renderer, self.scene.uploads().0, &mut self.renderer_stale)?;
        self.renderer.draw_positions(self.scene.draw_list())?;
        self.read_positions(out)
    }

    /// After baseline frames skipped the renderer's uploads, rewrites its
    /// whole height buffer from `staging` (once); tells whether it did.
    fn catch_up(
        renderer: &mut GlRenderer,
        staging: &[u8],
        stale: &mut bool,
    ) -> Result<bool, GlError> {
        let stale = std::mem::take(stale);
        if stale {
            renderer.upload(staging, &[0..staging.len() as u32])?;
        }
        Ok(stale)
    }

    /// Draws `camera`'s view of the ground truth as camera-relative positions
    /// into `out`, with the same frame uniforms as the LOD frame.
    pub fn render_truth_positions(
        &mut self,
        camera: &Camera,
        truth: &TruthPass,
        out: &mut PositionImage,
    ) -> Result<(), DisplayError> {
        camera.validate().map_err(SceneError::from)?;
        let frame = self.frame_uniforms(camera);
        self.bind_positions()?;
        self.renderer.draw_positions(&DrawList { frame: Some(frame), ..DrawList::default() })?;
        truth.draw(&frame, TerrainOutput::Position)?;
        self.read_positions(out)
    }

    /// Makes the context current and binds the position target, creating it
    /// on first use.
    fn bind_positions(&mut self) -> Result<(), DisplayError> {
        self.context.make_current()?;
        if self.positions.is_none() {
            self.positions =
                Some(OffscreenTarget::positions(self.context.gl(), self.context.size())?);
        }
        if let Some(target) = &self.positions {
            target.bind();
        }
        Ok(())
    }

    fn read_positions(&mut self, out: &mut PositionImage) -> Result<(), DisplayError> {
        let size = self.context.size();
        out.size = size;
        crate::gl::read_positions(self.context.gl(), size, &mut out.texels)?;
        self.context.bind_target();
        Ok(())
    }

    /// Pages in every node the view wants around `camera` before the first
    /// frame (start-up, and tests that need complete, repeatable frames).
    /// Gives up after `max_updates` clipmap updates; returns how many ran.
    pub fn settle(&mut self, camera: &Camera, max_updates: u32) -> Result<u32, DisplayError> {
        self.clipmap.set_view_position(self.view, camera.position)?;
        for update in 1..=max_updates {
            let stats = self.clipmap.update()?;
            if stats.missing == 0 && stats.in_flight == 0 {
                return Ok(update);
            }
            if stats.applied == 0 {
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
        }
        Ok(max_updates)
    }

    /// The last frame as RGBA, row 0 at the top.
    pub fn read_pixels(&self) -> Result<RgbaImage, GlError> {
        self.context.read_pixels()
    }

    /// Shows the frame (swaps a window's buffers).
    pub fn present(&self) -> Result<(), GlError> {
        self.context.present()
    }
}

/// Sizes the clipmap's view so that every tile the rings can select finds
/// its own level's node within the load radius: for each level, the far edge
/// of its ring plus a tile diagonal, in node sizes.
fn view_config(
    config: &DisplayConfig,
    summary: &TerrainSummary,
    layout: &crate::node::NodeLayout,
) -> ViewConfig {
    let camera = Camera {
        position: DVec3::ZERO,
        heading_deg: 0.0,
        pitch_deg: 0.0,
        roll_deg: 0.0,
        fov_x_deg: config.fov_x_deg,
        viewport: [config.size.x, config.size.y],
    };
    let grid = config.scene.lod.grid_size as f64;
    let tile_size_m = grid * layout.spacing_m[0].max(layout.spacing_m[1]);
    let inputs = RingInputs {
        tile_size_m,
        delta_per_level: &summary.delta_per_level,
        height_range_m: (summary.height_range.1 - summary.height_range.0) as f64,
        perspective_scale: camera.perspective_scale(),
    };
    let ranges = LevelRanges::new(&config.scene.lod, inputs);
    let mut load_distance: f64 = 2.0;
    for lod in 0..layout.levels.saturating_sub(1) {
        let node = layout.node_size_m(lod);
        let tile = tile_size_m * (1u64 << lod) as f64;
        let reach = ranges.split_distance(lod + 1) + tile * std::f64::consts::SQRT_2;
        load_distance = load_distance.max(reach / node[0].min(node[1]) + 0.5);
    }
    let load_distance = load_distance.min(40.0);
    let node_count = (2.0 * load_distance).ceil() as u32 + 4;
    ViewConfig { node_count, view_distance: load_distance, load_distance }
}

/// Room for every node a view can want (a disc of the load radius per level)
/// and as many again as a cache of recently used ones.
fn atlas_slots(view: &ViewConfig, levels: u8) -> u32 {
    let disc = std::f64::consts::PI * (view.load_distance + 1.5).powi(2);
    (2.0 * disc * levels as f64).ceil() as u32 + 64
}
