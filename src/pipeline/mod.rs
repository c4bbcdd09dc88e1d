//! The frame pipeline, GL-free: it owns the chunked clipmap and the scene,
//! sizes the clipmap from the scene's own rings, and makes one frame per
//! call on any [`RenderBackend`]: page nodes in, select and make tiles,
//! upload what changed, draw. The GL renderer, the null backend and the
//! accuracy tool's passes all consume what it produces: the draw list and
//! the staging copy the GPU buffer mirrors.
//!
//! Nothing is carried from one frame to the next but named state: the
//! clipmap's atlas, the tile cache, the last frame's draw list (whose
//! uniforms passes drawn beside the frame reuse), the selector's valid lives
//! and, with a frame budget, the tau controller fed each frame's triangles
//! or milliseconds ([`crate::lod::budget`]).

mod sizing;

pub use sizing::{
    buffer_copies, clipmap_view, least_budget, plan_memory, MemoryPlan, MAX_LOADER_QUEUE,
    MIN_BUDGET_BYTES, MIN_BUFFER_BYTES,
};

use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;

use crate::camera::Camera;
use crate::clipmap::{
    Clipmap, ClipmapConfig, ClipmapError, ClipmapStats, LoaderMode, NodeAtlas, ViewId,
};
use crate::lod::budget::{BudgetConfig, BudgetError, TauController};
use crate::node::NodeSource;
use crate::render::{BufferPlan, CallStats, DrawList, FrameOutput, RenderBackend, SymbolBackend};
use crate::scene::{
    ClipmapTerrain, Scene, SceneConfig, SceneError, SceneStats, TerrainSummary, View,
};
use crate::symbology::SymbolMesh;

/// Everything fixed for one pipeline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PipelineConfig {
    /// Tiling, buffer and palette settings.
    pub scene: SceneConfig,
    /// Horizontal field of view the clipmap's load radius is sized for, degrees.
    pub fov_x_deg: f64,
    /// Viewport the load radius is sized for, pixels (its width sets K).
    pub viewport: [u32; 2],
    /// Loads copied into the node atlas per frame.
    pub load_budget: u32,
    /// Load nodes on a thread (flying) or inline up to the budget (tests that
    /// want every frame complete and repeatable).
    pub loader: LoaderMode,
    /// Ridgeline's own heap and GPU buffer together, bytes: sizes the node
    /// atlas, the staging copy and the GPU buffer at start ([`plan_memory`]);
    /// `None` sizes them for the view and takes `scene.buffer_bytes`.
    pub memory_budget_bytes: Option<u64>,
    /// A frame budget: triangles or milliseconds a frame, held by raising
    /// tau above `scene.lod.tau_px` (never below it). `None`: tau as set.
    pub budget: Option<BudgetConfig>,
}

impl PipelineConfig {
    /// The defaults for a viewport of `viewport` pixels.
    pub fn new(viewport: [u32; 2]) -> Self {
        PipelineConfig {
            scene: SceneConfig::default(),
            fov_x_deg: 60.0,
            viewport,
            load_budget: 32,
            loader: LoaderMode::Thread { queue: 256 },
            memory_budget_bytes: None,
            budget: None,
        }
    }
}

/// Why the pipeline could not make a frame.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Paging failed (the loader thread could not start, a view is invalid).
    #[error(transparent)]
    Clipmap(#[from] ClipmapError),
    /// The camera or the tiling was invalid, or the buffer could not hold the root.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The memory budget is below what the display keeps aside.
    #[error(
        "memory budget {budget} bytes is too small: nodes of up to {node_bytes} bytes need at \
         least {least} bytes (the atlas holds at least eight, the loader's buffers a few)"
    )]
    MemoryBudget {
        /// The budget asked for, bytes.
        budget: u64,
        /// The least budget with a plan for these nodes, bytes.
        least: u64,
        /// Bytes a node buffer is counted at.
        node_bytes: u64,
    },
    /// The frame budget's target or settings are invalid.
    #[error("frame budget: {0}")]
    Budget(#[from] BudgetError),
}

/// Why a frame failed: in the pipeline or in the backend drawing it.
#[derive(Debug, thiserror::Error)]
pub enum FrameError<E: std::error::Error + 'static> {
    /// The GL-free part.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// The backend's upload or draw.
    #[error(transparent)]
    Backend(E),
}

/// What one frame did and cost. Its serde output is `stats.json`'s
/// per-frame keys (with `SceneStats`' flattened in), written by nothing
/// else, so a field's doc comment is its key's documentation.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Selection, tiles and uploads.
    #[serde(flatten)]
    pub scene: SceneStats,
    /// Every call the backend issued, by kind (`calls.draw_calls`: tiles
    /// once per depth slice they reach, and the sky).
    pub calls: CallStats,
    /// Nodes in the atlas after paging.
    pub resident_nodes: u32,
    /// Loads copied into the atlas this frame.
    pub nodes_loaded: u32,
    /// Missing nodes the atlas's byte budget had no room for this frame.
    pub nodes_over_budget: u32,
    /// Bytes the atlas's resident nodes take after paging.
    pub atlas_bytes: u64,
    /// Paging, milliseconds.
    pub clipmap_ms: f64,
    /// Upload, draw and the wait for the backend to finish, milliseconds.
    pub gl_ms: f64,
    /// The whole frame, milliseconds.
    pub frame_ms: f64,
    /// The tau asked for, pixels; `scene.tau_px` is the one achieved.
    pub tau_requested_px: f64,
}

impl FrameStats {
    /// Whether the frame's bound was loosened: selected with a tau above
    /// the requested, or drawn in part from coarser data than selected.
    pub fn tau_loosened(&self) -> bool {
        self.scene.bound_px > self.tau_requested_px
    }
}

/// The clipmap and the scene over one node source.
pub struct FramePipeline {
    clipmap: Clipmap,
    scene: Scene,
    view: ViewId,
    summary: TerrainSummary,
    memory: Option<MemoryPlan>,
}

impl FramePipeline {
    /// Builds the clipmap over `source` (whose per-level error and height
    /// range `summary` gives), sized for the scene's rings, and the scene.
    pub fn new(
        config: &PipelineConfig,
        source: Arc<dyn NodeSource>,
        summary: TerrainSummary,
    ) -> Result<FramePipeline, PipelineError> {
        let layout = *source.layout();
        let view_config = clipmap_view(config, &summary, &layout)?;
        let wanted = sizing::atlas_slots(&view_config, layout.levels);
        let mut scene_config = config.scene;
        let mut loader = config.loader;
        let memory = match config.memory_budget_bytes {
            Some(budget) => {
                let changes = 2 * config.load_budget as usize + 16;
                let table = NodeAtlas::table_bytes(wanted, changes);
                Some(plan(config, budget, source.node_bytes(), table)?)
            }
            None => None,
        };
        if let Some(plan) = memory {
            scene_config.buffer_bytes = plan.buffer_bytes;
            if let LoaderMode::Thread { queue } = &mut loader {
                *queue = plan.loader_queue as usize;
            }
        }
        let clipmap_config = ClipmapConfig {
            atlas_slots: wanted,
            atlas_bytes: memory.map(|plan| plan.atlas_bytes),
            budget: config.load_budget,
            loader,
        };
        let mut clipmap = Clipmap::new(source, clipmap_config)?;
        clipmap.set_earth(config.scene.earth);
        let view = clipmap.add_view(view_config, DVec3::ZERO)?;
        let terrain = ClipmapTerrain { clipmap: &clipmap, summary: &summary };
        let mut scene = Scene::new(scene_config, &terrain)?;
        scene.set_budget(config.budget)?;
        Ok(FramePipeline { clipmap, scene, view, summary, memory })
    }

    /// Pages, tiles, uploads and draws one frame for `camera` on `backend`,
    /// then waits for it ([`RenderBackend::finish`]) so `frame_ms` is the
    /// whole frame. A pipeline's uploads go to the backend they were made
    /// for: give every frame of one pipeline the same backend.
    pub fn frame<B: RenderBackend>(
        &mut self,
        camera: &Camera,
        backend: &mut B,
    ) -> Result<FrameStats, FrameError<B::Error>> {
        self.frame_then(camera, backend, |_| Ok(()))
    }

    /// [`FramePipeline::frame`] with `symbols` (laid out for `camera`,
    /// [`crate::symbology::reference_symbols`]) drawn over the terrain
    /// before the frame is finished.
    pub fn frame_with_symbols<B: SymbolBackend>(
        &mut self,
        camera: &Camera,
        symbols: &SymbolMesh,
        backend: &mut B,
    ) -> Result<FrameStats, FrameError<B::Error>> {
        self.frame_then(camera, backend, |backend| backend.draw_symbols(symbols))
    }

    /// A frame without terrain, for stale or invalid data: nothing is paged
    /// or tiled, the backend clears and draws `flag` (the failure flag,
    /// [`crate::symbology::flag::failure_flag`]) and finishes.
    pub fn withdrawn_frame<B: SymbolBackend>(
        &mut self,
        flag: &SymbolMesh,
        backend: &mut B,
    ) -> Result<FrameStats, FrameError<B::Error>> {
        let start = Instant::now();
        backend.render_withdrawn(flag).map_err(FrameError::Backend)?;
        backend.finish();
        let calls = backend.take_calls();
        let ms = ms(start, Instant::now());
        Ok(FrameStats {
            calls,
            resident_nodes: self.clipmap.atlas().resident_count(),
            atlas_bytes: self.clipmap.atlas().resident_bytes(),
            gl_ms: ms,
            frame_ms: ms,
            tau_requested_px: self.scene.config().lod.tau_px,
            ..FrameStats::default()
        })
    }

    /// A frame, with `overlay` drawn on the backend after the terrain and
    /// before the wait.
    fn frame_then<B: RenderBackend>(
        &mut self,
        camera: &Camera,
        backend: &mut B,
        overlay: impl FnOnce(&mut B) -> Result<(), B::Error>,
    ) -> Result<FrameStats, FrameError<B::Error>> {
        let start = Instant::now();
        // The view first: it refuses a camera that is not valid before its
        // position reaches the clipmap, and every stage after reads it.
        let view = View::new(camera, &self.terrain(), self.scene.config())
            .map_err(|e| PipelineError::from(SceneError::from(e)))?;
        let update = self.page_at(&view)?;
        let paged = Instant::now();
        let terrain = ClipmapTerrain { clipmap: &self.clipmap, summary: &self.summary };
        let scene = self.scene.frame_in(&view, &terrain).map_err(PipelineError::from)?;
        let tiled = Instant::now();
        let (staging, dirty) = self.scene.gpu_uploads();
        let indices = self.scene.index_uploads();
        let output = FrameOutput { list: self.scene.draw_list(), staging, dirty, indices };
        backend.render(&output).map_err(FrameError::Backend)?;
        overlay(backend).map_err(FrameError::Backend)?;
        backend.finish();
        let done = Instant::now();
        let calls = backend.take_calls();
        let stats = FrameStats {
            scene,
            calls,
            resident_nodes: self.clipmap.atlas().resident_count(),
            nodes_loaded: update.applied,
            nodes_over_budget: update.over_budget,
            atlas_bytes: self.clipmap.atlas().resident_bytes(),
            clipmap_ms: ms(start, paged),
            gl_ms: ms(tiled, done),
            frame_ms: ms(start, done),
            tau_requested_px: self.scene.config().lod.tau_px,
        };
        self.scene.observe_budget(&stats.scene, stats.frame_ms);
        Ok(stats)
    }

    /// The frame budget's controller, when there is a budget (the scene's
    /// tau policy owns it).
    pub fn budget(&self) -> Option<&TauController> {
        self.scene.budget()
    }

    /// Paging: the clipmap's view moves to `view`'s eye and updates.
    fn page_at(&mut self, view: &View) -> Result<ClipmapStats, PipelineError> {
        self.clipmap.set_view_position(self.view, view.camera.position)?;
        Ok(self.clipmap.update()?)
    }

    fn page(&mut self, camera: &Camera) -> Result<ClipmapStats, PipelineError> {
        // Refused here, before a position that is not a number reaches the clipmap.
        camera.validate().map_err(SceneError::from)?;
        self.clipmap.set_view_position(self.view, camera.position)?;
        Ok(self.clipmap.update()?)
    }

    /// Pages in every node the view wants around `camera` before a frame
    /// (start-up, and tests that need complete, repeatable frames). Gives up
    /// after `max_updates` clipmap updates; returns how many ran.
    pub fn settle(&mut self, camera: &Camera, max_updates: u32) -> Result<u32, PipelineError> {
        for update in 1..=max_updates {
            let stats = self.page(camera)?;
            if stats.missing == 0 && stats.in_flight == 0 {
                return Ok(update);
            }
            if stats.applied == 0 {
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
        }
        Ok(max_updates)
    }

    /// The last frame's draw list; its uniforms are the ones passes drawn
    /// beside that frame (truth, positions) must use.
    pub fn draw_list(&self) -> &DrawList {
        self.scene.draw_list()
    }

    /// The tile cache's staging copy: what the draw list's tiles' offsets
    /// refer to (the GPU buffer mirrors it when clusters are off).
    pub fn staging(&self) -> &[u8] {
        self.scene.uploads().0
    }

    /// The scene (its configuration, rings and tile cache).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The clipmap (its atlas and views).
    pub fn clipmap(&self) -> &Clipmap {
        &self.clipmap
    }

    /// The GPU buffers this pipeline's frames fill (after any memory
    /// budget shrank them): every backend is built from it
    /// (`GlRenderer::new`, [`crate::render::NullBackend::new`]).
    pub fn buffer_plan(&self) -> BufferPlan {
        self.scene.buffer_plan()
    }

    /// How the memory budget was shared, if one was given.
    pub fn memory_plan(&self) -> Option<MemoryPlan> {
        self.memory
    }

    /// The data's per-level error and height range.
    pub fn summary(&self) -> &TerrainSummary {
        &self.summary
    }

    /// The terrain as the scene sees it now: the clipmap's resident nodes.
    pub fn terrain(&self) -> ClipmapTerrain<'_> {
        ClipmapTerrain { clipmap: &self.clipmap, summary: &self.summary }
    }
}

/// The memory plan for `budget` bytes, or why there is none: the atlas's
/// tables (`table_bytes`, which grow with its slots) come off the top.
fn plan(
    config: &PipelineConfig,
    budget: u64,
    node_bytes: u64,
    table_bytes: u64,
) -> Result<MemoryPlan, PipelineError> {
    let queue = match config.loader {
        LoaderMode::Thread { queue } => queue.min(u32::MAX as usize) as u32,
        LoaderMode::Inline => 0,
    };
    let copies = buffer_copies(config.scene.clusters);
    let buffer = config.scene.buffer_bytes;
    let plan = budget
        .checked_sub(table_bytes)
        .and_then(|left| plan_memory(left, node_bytes, queue, copies, buffer));
    plan.map(|plan| MemoryPlan { budget_bytes: budget, ..plan }).ok_or_else(|| {
        let least = least_budget(node_bytes, queue, copies, buffer) + table_bytes;
        PipelineError::MemoryBudget { budget, least, node_bytes }
    })
}

fn ms(from: Instant, to: Instant) -> f64 {
    (to - from).as_secs_f64() * 1e3
}
