//! The display put together: a GL context and its target, the GL renderer,
//! and the frame pipeline driving it, one call per frame. `fly` drives a
//! [`Display`]; the accuracy tool ([`measure`]) and the regression tests use
//! the same [`DisplayParts`] and add their own passes over the pipeline's
//! output.

pub mod measure;

use std::sync::Arc;
use std::time::Duration;

use glam::UVec2;
use image::RgbaImage;

use crate::clipmap::LoaderMode;
use crate::gl::{
    ContextRequest, GlBackend, GlContext, GlError, GlInfo, GlRenderer, GlesVersion, WindowEvents,
};
use crate::node::NodeSource;
use crate::pipeline::{FrameError, FramePipeline, FrameStats, PipelineConfig, PipelineError};
use crate::scene::{SceneConfig, TerrainSummary};
use crate::symbology::SymbolMesh;

/// Everything fixed for one display.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplayConfig {
    /// Which platform opens the context.
    pub backend: GlBackend,
    /// OpenGL ES version requested.
    pub version: GlesVersion,
    /// Target size, pixels.
    pub size: UVec2,
    /// Tiling, buffer and palette settings.
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
    /// Ridgeline's own heap and GPU buffer together, bytes (see
    /// [`PipelineConfig::memory_budget_bytes`]).
    pub memory_budget_bytes: Option<u64>,
    /// A frame budget (triangles or milliseconds) that may raise tau.
    pub budget: Option<crate::lod::budget::BudgetConfig>,
    /// Use vertex array objects where the driver has them (see
    /// [`ContextRequest::vertex_arrays`]).
    pub vertex_arrays: bool,
}

impl DisplayConfig {
    /// The defaults for `backend` at `size`.
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
            memory_budget_bytes: None,
            budget: None,
            vertex_arrays: true,
        }
    }

    /// The frame pipeline's part of the configuration.
    pub fn pipeline(&self) -> PipelineConfig {
        PipelineConfig {
            scene: self.scene,
            fov_x_deg: self.fov_x_deg,
            viewport: self.size.into(),
            load_budget: self.load_budget,
            loader: self.loader,
            memory_budget_bytes: self.memory_budget_bytes,
            budget: self.budget,
        }
    }
}

/// Why the display could not open or draw.
#[derive(Debug, thiserror::Error)]
pub enum DisplayError {
    /// The context, a GL object or a GL call failed.
    #[error(transparent)]
    Gl(#[from] GlError),
    /// Paging or tiling failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
}

impl From<FrameError<GlError>> for DisplayError {
    fn from(error: FrameError<GlError>) -> Self {
        match error {
            FrameError::Pipeline(error) => DisplayError::Pipeline(error),
            FrameError::Backend(error) => DisplayError::Gl(error),
        }
    }
}

/// The parts of a display, for callers that draw passes of their own over
/// the pipeline's output. Field order is drop order: GL objects before
/// their context.
pub struct DisplayParts {
    /// The display's passes, fed by `pipeline`.
    pub renderer: GlRenderer,
    /// The context and its render target.
    pub context: GlContext,
    /// Paging, tiling and uploads.
    pub pipeline: FramePipeline,
}

impl Drop for DisplayParts {
    fn drop(&mut self) {
        // The renderer's objects are deleted (fields drop in order) in
        // whichever context is current: another display on this thread may
        // have made its own current, whose objects share the names.
        let _ = self.context.make_current();
    }
}

impl DisplayParts {
    /// Opens the context and builds the renderer and the pipeline over
    /// `source` (whose per-level error and height range `summary` gives).
    pub fn open(
        config: &DisplayConfig,
        source: Arc<dyn NodeSource>,
        summary: TerrainSummary,
    ) -> Result<DisplayParts, DisplayError> {
        let mut request = ContextRequest::new(config.backend, config.version, config.size);
        request.title = "Ridgeline".to_owned();
        request.vertex_arrays = config.vertex_arrays;
        let context = GlContext::new(&request)?;
        let pipeline = FramePipeline::new(&config.pipeline(), source, summary)?;
        let mut renderer = GlRenderer::new(context.gl(), &pipeline.buffer_plan())?;
        renderer.set_sentinel(config.sentinel);
        Ok(DisplayParts { renderer, context, pipeline })
    }

    /// Makes the context current, binds its target and draws one frame of
    /// the pipeline for `camera` on the renderer.
    pub fn frame(&mut self, camera: &crate::camera::Camera) -> Result<FrameStats, DisplayError> {
        // Another display on this thread may have made its context current.
        self.context.make_current()?;
        self.context.bind_target();
        Ok(self.pipeline.frame(camera, &mut self.renderer)?)
    }

    /// [`DisplayParts::frame`] with `symbols` drawn over the terrain.
    pub fn frame_with_symbols(
        &mut self,
        camera: &crate::camera::Camera,
        symbols: &SymbolMesh,
    ) -> Result<FrameStats, DisplayError> {
        self.context.make_current()?;
        self.context.bind_target();
        Ok(self.pipeline.frame_with_symbols(camera, symbols, &mut self.renderer)?)
    }

    /// A frame with the terrain withdrawn and `flag` drawn instead.
    pub fn withdrawn_frame(&mut self, flag: &SymbolMesh) -> Result<FrameStats, DisplayError> {
        self.context.make_current()?;
        self.context.bind_target();
        Ok(self.pipeline.withdrawn_frame(flag, &mut self.renderer)?)
    }
}

/// A display: one context, its renderer and pipeline, one call per frame.
pub struct Display {
    parts: DisplayParts,
}

impl Display {
    /// Opens the context and builds the clipmap over `source` (whose
    /// per-level error and height range `summary` gives).
    pub fn new(
        config: &DisplayConfig,
        source: Arc<dyn NodeSource>,
        summary: TerrainSummary,
    ) -> Result<Display, DisplayError> {
        Ok(Display { parts: DisplayParts::open(config, source, summary)? })
    }

    /// The context's version and renderer strings.
    pub fn info(&self) -> &GlInfo {
        self.parts.context.info()
    }

    /// The frame pipeline (its scene, clipmap and memory plan).
    pub fn pipeline(&self) -> &FramePipeline {
        &self.parts.pipeline
    }

    /// Pages, tiles, uploads and draws one frame for `camera`, then waits for
    /// the GPU (glFinish) so `frame_ms` is the whole frame.
    pub fn frame(&mut self, camera: &crate::camera::Camera) -> Result<FrameStats, DisplayError> {
        self.parts.frame(camera)
    }

    /// [`Display::frame`] with the reference symbols `symbols` (laid out
    /// for `camera`) drawn over the terrain.
    pub fn frame_with_symbols(
        &mut self,
        camera: &crate::camera::Camera,
        symbols: &SymbolMesh,
    ) -> Result<FrameStats, DisplayError> {
        self.parts.frame_with_symbols(camera, symbols)
    }

    /// A frame with the terrain withdrawn (stale data) and `flag` drawn.
    pub fn withdrawn_frame(&mut self, flag: &SymbolMesh) -> Result<FrameStats, DisplayError> {
        self.parts.withdrawn_frame(flag)
    }

    /// Pages in every node the view wants around `camera` before the first
    /// frame. Gives up after `max_updates` clipmap updates; returns how many ran.
    pub fn settle(
        &mut self,
        camera: &crate::camera::Camera,
        max_updates: u32,
    ) -> Result<u32, DisplayError> {
        Ok(self.parts.pipeline.settle(camera, max_updates)?)
    }

    /// The last frame as RGBA, row 0 at the top.
    pub fn read_pixels(&self) -> Result<RgbaImage, GlError> {
        self.parts.context.read_pixels()
    }

    /// Shows the frame (swaps a window's buffers).
    pub fn present(&self) -> Result<(), GlError> {
        self.parts.context.present()
    }

    /// Handles a window's pending events, waiting up to `timeout`.
    pub fn pump_events(&mut self, timeout: Option<Duration>) -> WindowEvents {
        self.parts.context.pump_events(timeout)
    }
}
