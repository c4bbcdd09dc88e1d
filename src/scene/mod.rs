//! One frame of the display, GL-free: the rings for the current camera, the
//! tile selection, the tile cache's uploads and the draw list, with the time
//! each stage took. A renderer backend consumes the result.
//!
//! When the GPU buffer cannot take a frame's new tiles, the frame is selected
//! again with rings half as wide (coarser tiles), down to the root level,
//! whose tiles are always resident: the picture gets coarser, never a hole.

mod band;
mod clearance;
mod clipmap_terrain;
mod tau;
mod terrain;
mod view;

pub use band::{TileEstimate, TriangleBand, MAX_RESELECTIONS};

pub use clipmap_terrain::{ClipmapTerrain, TerrainSummary};
pub use terrain::{PreloadedTerrain, TerrainData};
pub use view::{clip_planes, clip_planes_computed, View};

use crate::camera::{Camera, CameraError};
use crate::clusters::{ClusterCache, ClusterConfig, ClusterError};
use crate::earth::GridPlacement;
use crate::lod::budget::{BudgetConfig, BudgetError, TauController};
use crate::lod::census::{frustum_census, Census};
use crate::lod::life::LifeStats;
use crate::lod::rings::RingInputs;
use crate::lod::{LevelRings, LodConfig, LodError, TileSelector};
use crate::node::NodeLayout;
use crate::render::draw_list::{made_delta, TileGeometry};
#[cfg(feature = "test-support")]
use crate::render::ClusterMorph;
use crate::render::{palette, BufferPlan, ClusterOrder, DrawList};
use crate::tiles::errors::{MapErrors, MeshErrors};
use crate::tiles::{TileCache, TileCacheConfig, TileError};
use std::time::Instant;
use tau::TauPolicy;

/// The default longest single upload, 196 608 bytes: four of Polok's 64 x 64
/// tiles of heights, morph targets and normals (12 bytes a vertex; a tile's
/// block now also holds positions and indices, so about five of our regular
/// 32-cell tiles). `cargo bench --bench hwmetrics`
/// finds no gain from batching on llvmpipe that matters (glBufferSubData is a
/// memcpy there: from 1 to 1024 tiles a run, 256 tiles take 0.71 to 0.96 ms,
/// under 0.1 % of the frame), so the cap comes from the paper's Table 1,
/// where runs shorter than four tiles cost up to 35 % more and longer ones
/// gain nothing significant.
/// A cap also keeps the allocator's runs short enough to reuse small gaps
/// (see the transfer-cap table of `cargo bench --bench allocator`).
pub const DEFAULT_TRANSFER_CAP: u32 = 4 * 64 * 64 * 12;

/// The default tile buffer, 84 MiB: room for 2303 regular 32-cell tiles
/// (38 244 bytes each), as many as the 32 MiB held when a tile's block
/// carried only its heights (14 652 bytes). The earth-scale view of
/// `tests/scene_precision.rs` needs 2027 tiles even at its coarsest.
pub const DEFAULT_BUFFER_BYTES: u32 = 84 << 20;

/// Everything fixed for a run of the display.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneConfig {
    /// Tiling parameters: grid size, view distance, morph range, tau, most tiles.
    pub lod: LodConfig,
    /// GPU tile buffer (every tile's block: vertices and indices), bytes.
    pub buffer_bytes: u32,
    /// Longest single upload, bytes; `None` uploads each frame's run in one transfer.
    pub transfer_cap: Option<u32>,
    /// Frames a released tile's bytes stay out of reuse (0: reusable at once).
    pub frames_in_flight: u32,
    /// Whether the earth's curvature lowers distant terrain (in culling and drawing).
    pub curvature: bool,
    /// Cull tiles hidden below the horizon (with the curvature, and only while
    /// the camera is over the data). Holes do not hide what is behind them:
    /// leave it off for data with no-data posts.
    pub horizon_culling: bool,
    /// Terrain this many metres above the aircraft, or higher, is red.
    pub warning_above_m: f32,
    /// Terrain less than this many metres below the aircraft is amber.
    pub caution_below_m: f32,
    /// Draw the tiles as clusters (Judnich & Ling; `crate::clusters`): the
    /// GPU buffer then holds the clusters' blocks, not the tiles'.
    pub clusters: bool,
    /// Which morph range a cluster's members take (tests break it on
    /// purpose; feature `test-support`).
    #[cfg(feature = "test-support")]
    pub cluster_morph: ClusterMorph,
    /// In which order clusters are drawn.
    pub cluster_order: ClusterOrder,
    /// Draw on the WGS 84 ellipsoid where the grid is placed by its
    /// geographic coordinates ([`crate::earth::EarthFrame`]); `None`, or a
    /// projected grid: in the planar chart (`fly --chart`).
    pub earth: Option<GridPlacement>,
}

impl Default for SceneConfig {
    fn default() -> Self {
        SceneConfig {
            lod: LodConfig::default(),
            buffer_bytes: DEFAULT_BUFFER_BYTES,
            transfer_cap: Some(DEFAULT_TRANSFER_CAP),
            frames_in_flight: 0,
            curvature: true,
            horizon_culling: true,
            warning_above_m: palette::DEFAULT_WARNING_ABOVE_M,
            caution_below_m: palette::DEFAULT_CAUTION_BELOW_M,
            clusters: false,
            #[cfg(feature = "test-support")]
            cluster_morph: ClusterMorph::PerMember,
            cluster_order: ClusterOrder::ByBase,
            earth: None,
        }
    }
}

/// Why a frame, or the scene itself, cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The camera is not valid.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// The tiling configuration does not suit the terrain.
    #[error("tiling: {0}")]
    Lod(#[from] LodError),
    /// The tile cache could not be built or could not take the frame's tiles, even
    /// coarsened down to the root level.
    #[error("tiles: {0}")]
    Tiles(#[from] TileError),
    /// The cluster cache could not be built or could not take the frame's
    /// clusters, even coarsened down to the root level.
    #[error("clusters: {0}")]
    Clusters(#[from] ClusterError),
}

/// CPU time of each stage of a frame, milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StageTimes {
    /// Computing the rings and selecting tiles, every try of the frame together.
    pub select_ms: f64,
    /// Updating the tile cache: releasing, allocating and making tiles.
    pub tiles_ms: f64,
    /// Building the draw list.
    pub draw_list_ms: f64,
}

/// What a frame drew and what it cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SceneStats {
    /// Tiles in the draw list.
    pub tiles: usize,
    /// Tiles dropped by the frustum in the frame's final selection.
    pub culled: usize,
    /// Tiles inside the frustum dropped below the horizon in the frame's
    /// final selection: neither selected, nor made, nor drawn.
    pub horizon_culled: usize,
    /// Triangles of the tiles in the draw list, skirts included (each tile once).
    pub triangles: u64,
    /// Bytes of the staging copy uploaded.
    pub bytes_uploaded: u64,
    /// Transfers: one per run piece (dirty range).
    pub transfers: usize,
    /// Tiles whose block was made this frame.
    pub tiles_generated: usize,
    /// Bytes held by resident tiles.
    pub allocator_used_bytes: u64,
    /// End of the highest block not free: the buffer size this state needs, bytes.
    pub allocator_workspace_bytes: u32,
    /// Times the selection was coarsened because the buffer was full.
    pub coarsened: u32,
    /// The tau the frame's tiles were selected with, pixels: the bound it
    /// achieved (above the requested one when a budget or a full buffer
    /// loosened it).
    pub tau_px: f64,
    /// The error bound the drawn tiles achieve, pixels: `tau_px`, or more
    /// where tiles fell back to coarser resident data than their level
    /// (nodes still paging in, or left out by the memory budget).
    pub bound_px: f64,
    /// Tiles drawn from a coarser node than their level's (best available).
    pub fallback_tiles: usize,
    /// The valid life's split tests in the final selection (all zero without one).
    pub split_tests: LifeStats,
    /// Selections redone to keep a triangle budget's band ([`TriangleBand`]).
    pub reselected: u32,
    /// Clusters drawn (0 when tiles are drawn one by one).
    pub clusters: usize,
    /// Clusters whose block was made this frame.
    pub clusters_made: usize,
    /// Bytes of cluster blocks uploaded (the GPU's uploads when clustered).
    pub cluster_bytes_uploaded: u64,
    /// Windows of the cluster vertex buffer the frame's clusters lie in:
    /// their distinct attribute bases.
    pub cluster_windows: usize,
    /// The fewest windows the frame's cluster vertices could fill.
    pub cluster_windows_least: usize,
    /// CPU time of each stage.
    pub cpu_ms: StageTimes,
}

/// The per-frame state of the display.
pub struct Scene {
    config: SceneConfig,
    selector: TileSelector,
    cache: TileCache,
    rings: LevelRings,
    draw_list: DrawList,
    deltas: Vec<f64>,
    /// The regular grid's deltas (what tiles made as grids err by).
    grid_deltas: Vec<f64>,
    /// Tau: the one owner of it, the band's search and a budget's controller.
    tau: TauPolicy,
    /// With clusters on: their blocks, which the GPU buffer then mirrors.
    clusters: Option<ClusterCache>,
    /// What the terrain's error maps can do per level.
    map_errors: MapErrors,
    /// The errors this frame's tiles are extracted at.
    mesh_errors: MeshErrors,
    /// The last frame's view.
    view: Option<View>,
}

/// The near plane sits this share of the way to the nearest drawn tile's
/// bounding box (the rest is margin for the curvature drop and rounding).
const NEAR_SHARE: f64 = 0.8;

impl Scene {
    /// Builds the scene for `terrain`: checks the tiling and makes the root level's tiles.
    pub fn new(config: SceneConfig, terrain: &dyn TerrainData) -> Result<Self, SceneError> {
        let layout = *terrain.layout();
        config.lod.validate(layout.node_size)?;
        let cache_config = TileCacheConfig {
            grid_size: config.lod.grid_size,
            capacity_bytes: config.buffer_bytes,
            max_tiles: config.lod.max_tiles as u32 + root_tiles(terrain, config.lod.grid_size),
            transfer_cap: config.transfer_cap,
            frames_in_flight: config.frames_in_flight,
        };
        let deltas = terrain.delta_per_level();
        #[cfg_attr(not(feature = "test-support"), allow(unused_mut))]
        let mut draw_list = DrawList::with_capacity(cache_config.max_tiles as usize);
        #[cfg(feature = "test-support")]
        {
            draw_list.cluster_morph = config.cluster_morph;
        }
        let plan = BufferPlan::new(config.buffer_bytes, config.clusters);
        let clusters = if let Some(index_capacity_bytes) = plan.cluster_index_bytes {
            Some(ClusterCache::new(ClusterConfig {
                capacity_bytes: plan.buffer_bytes,
                index_capacity_bytes,
                max_clusters: cache_config.max_tiles,
                transfer_cap: config.transfer_cap,
                frames_in_flight: config.frames_in_flight,
                order: config.cluster_order,
            })?)
        } else {
            None
        };
        let inputs = RingInputs {
            tile_size_m: 1.0,
            delta_per_level: &deltas,
            height_range_m: 0.0,
            perspective_scale: 1.0,
        };
        let map_errors = terrain.map_errors();
        Ok(Scene {
            tau: TauPolicy::new(config.lod, !map_errors.is_empty(), inputs),
            clusters,
            config,
            selector: TileSelector::new(config.lod),
            cache: TileCache::new(cache_config, terrain)?,
            rings: LevelRings::new(&config.lod, inputs),
            draw_list,
            deltas,
            grid_deltas: terrain.grid_delta_per_level(),
            map_errors,
            mesh_errors: MeshErrors::default(),
            view: None,
        })
    }

    /// Sets the tau the next frames select with (a frame budget's), pixels;
    /// Kühnert's view distance shrinks by the same factor, down to 1 tile.
    /// Refused when it is not finite or below the configured tau.
    pub fn set_tau(&mut self, tau_px: f64) -> Result<(), SceneError> {
        Ok(self.tau.set_tau(tau_px)?)
    }

    /// Keeps the next frames' triangles inside `band` (a triangle budget's)
    /// by selecting again within the frame; `None`: no band.
    pub fn set_triangle_band(&mut self, band: Option<TriangleBand>) {
        self.tau.set_band(band);
    }

    /// Holds every next frame to `budget` (triangles or milliseconds): its
    /// controller sets each frame's tau and band, and learns from what the
    /// frames report to [`Scene::observe_budget`]. `None`: tau as set.
    pub fn set_budget(&mut self, budget: Option<BudgetConfig>) -> Result<(), BudgetError> {
        self.tau.set_budget(budget)
    }

    /// The frame budget's controller, when there is a budget.
    pub fn budget(&self) -> Option<&TauController> {
        self.tau.controller()
    }

    /// Feeds the frame budget's controller a frame's `stats` and its whole
    /// time, `frame_ms` (backend included), for the next frame's tau.
    pub fn observe_budget(&mut self, stats: &SceneStats, frame_ms: f64) {
        self.tau.observe(stats, frame_ms);
    }

    /// The configuration the scene was built with.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// The GPU buffers the scene's frames fill, as its caches were sized:
    /// what every backend drawing them must be sized by.
    pub fn buffer_plan(&self) -> BufferPlan {
        BufferPlan::new(self.config.buffer_bytes, self.config.clusters)
    }

    /// The last frame's draw list.
    pub fn draw_list(&self) -> &DrawList {
        &self.draw_list
    }

    /// The tile cache's staging copy (what the draw list's tile offsets
    /// refer to) and the ranges of it made this frame. Without clusters
    /// the GPU buffer mirrors it.
    pub fn uploads(&self) -> (&[u8], &[std::ops::Range<u32>]) {
        (self.cache.staging(), self.cache.dirty_ranges())
    }

    /// The tau past which the last frame's rings stop shrinking, pixels,
    /// with the view distance shrinking alongside ([`Scene::set_tau`]): a
    /// budget raising tau further gains nothing.
    pub fn tau_ceiling(&self) -> f64 {
        self.tau.ceiling()
    }

    /// The staging copy the GPU buffer mirrors and the ranges it must
    /// receive this frame: the cluster cache's with clusters on, else
    /// [`Self::uploads`].
    pub fn gpu_uploads(&self) -> (&[u8], &[std::ops::Range<u32>]) {
        match &self.clusters {
            Some(clusters) => (clusters.staging(), clusters.dirty_ranges()),
            None => self.uploads(),
        }
    }

    /// With clusters on, the cluster index buffer's staging copy and the
    /// ranges of it to upload this frame.
    pub fn index_uploads(&self) -> Option<(&[u8], &[std::ops::Range<u32>])> {
        self.clusters.as_ref().map(|c| (c.index_staging(), c.index_dirty_ranges()))
    }

    /// The cluster cache, with clusters on.
    pub fn clusters(&self) -> Option<&ClusterCache> {
        self.clusters.as_ref()
    }

    /// The rings of the last frame.
    pub fn rings(&self) -> &LevelRings {
        &self.rings
    }

    /// Prepares one frame for `camera`: [`Scene::frame_in`] its [`View`].
    pub fn frame(
        &mut self,
        camera: &Camera,
        terrain: &dyn TerrainData,
    ) -> Result<SceneStats, SceneError> {
        let view = View::new(camera, terrain, &self.config)?;
        self.frame_in(&view, terrain)
    }

    /// Prepares one frame for `view`, stage by stage: the tau policy
    /// starts the frame; selection (again while the band's search moves
    /// tau); tiles (again once with a budget's correction); the draw list.
    /// A buffer too full for the tiles or their clusters coarsens the
    /// selection and goes round again.
    pub fn frame_in(
        &mut self,
        view: &View,
        terrain: &dyn TerrainData,
    ) -> Result<SceneStats, SceneError> {
        self.view = Some(*view);
        let mut report = SceneStats::default();
        let levels = terrain.layout().levels;
        let (deltas, maps) = (&self.deltas, &self.map_errors);
        self.tau.begin(view, deltas, maps, &mut self.mesh_errors, levels)?;
        loop {
            let nearest_m = self.select(view, terrain, &mut report);
            let made = self.make_tiles(terrain, &mut report);
            if made.is_ok() && self.tau.correct(self.cache.drawn_triangles() as f64) {
                report.reselected += 1;
                continue;
            }
            match made.and_then(|()| self.draw(view, terrain, nearest_m, &mut report)) {
                Ok(()) => break,
                Err(error) if buffer_full(&error) && self.tau.coarsen() => report.coarsened += 1,
                Err(error) => return Err(error),
            }
        }
        self.report(view, &mut report);
        let cache = &self.cache;
        self.tau.end(
            &report,
            self.draw_list.tiles.iter().map(|t| {
                let made = cache.resident_triangles(t.key).map_or(f64::NAN, |(_, e)| e);
                (t.key.level, t.triangles(), made)
            }),
        );
        Ok(report)
    }

    /// Selection: the rings and extraction errors of the policy's tiling,
    /// then the tiles, until the policy keeps them. Returns the nearest
    /// tile's distance, metres.
    fn select(&mut self, view: &View, terrain: &dyn TerrainData, report: &mut SceneStats) -> f64 {
        let (grid_size, levels) = (self.config.lod.grid_size, terrain.layout().levels);
        // The camera's clearance depends on the eye and the resident nodes,
        // not on tau: once a frame, whatever the retargets.
        let (lo, hi) = terrain.height_range();
        let at = view.camera.position.to_array();
        let clearance = clearance::clearance_m(terrain, at, (lo as f64, hi as f64));
        self.mesh_errors.set_clearance(clearance);
        loop {
            let start = Instant::now();
            let lod = *self.tau.lod();
            self.rings.update(&lod, view.ring_inputs(&self.deltas));
            let rings = &self.rings;
            let split = |level| rings.split_distance(level);
            let (tau, morph) = (lod.tau_px, lod.morph_range);
            self.mesh_errors.update(split, levels, view.k, tau, morph, &self.map_errors);
            let eye = [view.camera.position.x, view.camera.position.y];
            self.mesh_errors.anchor(eye, Some(&view.camera), |level| rings.morph(level));
            let selection = view.selection(&self.rings, self.config.curvature);
            let selected = self.selector.select(&selection, terrain);
            let errors = &self.mesh_errors;
            let tiles = tau::estimates(selected, &self.cache, errors, terrain, grid_size);
            let again = self.tau.retarget(tiles, report.coarsened);
            report.cpu_ms.select_ms += ms(start, Instant::now());
            if !again {
                return selected.iter().map(|t| t.distance).fold(f64::INFINITY, f64::min);
            }
            report.reselected += 1;
        }
    }

    /// Tiles: the cache releases, places and makes the selection's tiles
    /// (remakes them at the corrected errors when the policy is retaking).
    fn make_tiles(
        &mut self,
        terrain: &dyn TerrainData,
        report: &mut SceneStats,
    ) -> Result<(), SceneError> {
        let start = Instant::now();
        let selected = self.selector.selected();
        let made = match self.tau.retaking() {
            true => self.cache.retake(selected, terrain, &self.mesh_errors),
            false => self.cache.update(selected, terrain, &self.mesh_errors),
        };
        report.cpu_ms.tiles_ms += ms(start, Instant::now());
        made.map(|_| ()).map_err(SceneError::from)
    }

    /// The draw list: the view's uniforms, with the near plane pushed out
    /// toward the tile `nearest_m` away, the tiles' uniforms, and with
    /// clusters on, the clusters' draws.
    fn draw(
        &mut self,
        view: &View,
        terrain: &dyn TerrainData,
        nearest_m: f64,
        report: &mut SceneStats,
    ) -> Result<(), SceneError> {
        let near_m = (nearest_m * NEAR_SHARE).min(f32::MAX as f64) as f32;
        let uniforms = view.uniforms(&self.config, terrain, near_m);
        let start = Instant::now();
        let layout = terrain.layout();
        let geometry = TileGeometry {
            grid_size: self.config.lod.grid_size,
            node_size: layout.node_size,
            spacing_m: layout.spacing_m,
            delta_per_level: &self.deltas,
            grid_delta_per_level: &self.grid_deltas,
            mesh_errors: &self.mesh_errors,
        };
        self.draw_list.build(uniforms, self.cache.draws(), &self.rings, geometry);
        if let Some(clusters) = &mut self.clusters {
            let (staging, dirty) = (self.cache.staging(), self.cache.dirty_ranges());
            self.draw_list.cluster(|list, draws| clusters.update(list, staging, dirty, draws))?;
        }
        report.cpu_ms.draw_list_ms = ms(start, Instant::now());
        Ok(())
    }

    /// What the frame drew and cost, besides the stage times and tries
    /// `report` already holds.
    fn report(&self, view: &View, report: &mut SceneStats) {
        let stats = self.cache.stats();
        report.tiles = self.draw_list.tiles.len();
        report.culled = self.selector.culled();
        report.horizon_culled = self.selector.horizon_culled();
        report.tau_px = self.tau.lod().tau_px;
        (report.fallback_tiles, report.bound_px) = self.fallback_bound(view.k, report.tau_px);
        report.split_tests = self.selector.life_stats().unwrap_or_default();
        report.triangles = self.draw_list.triangles();
        report.bytes_uploaded = stats.bytes_uploaded;
        report.transfers = stats.transfers;
        report.tiles_generated = stats.generated;
        report.allocator_used_bytes = stats.allocator_used_bytes;
        report.allocator_workspace_bytes = stats.allocator_workspace_bytes;
        if let Some(clusters) = &self.clusters {
            let stats = clusters.stats();
            report.clusters = stats.clusters;
            report.clusters_made = stats.made;
            report.cluster_bytes_uploaded = stats.bytes_uploaded;
            report.cluster_windows = stats.bases;
            report.cluster_windows_least = stats.least_bases;
        }
    }
}

/// Whether `error` is a buffer too full for the frame: of tiles, or of
/// clusters (a cluster that no window has room for is a full buffer too:
/// coarser tiles make smaller clusters).
fn buffer_full(error: &SceneError) -> bool {
    matches!(
        error,
        SceneError::Tiles(TileError::BufferFull(_))
            | SceneError::Clusters(ClusterError::BufferFull(_) | ClusterError::NoWindow { .. })
    )
}

impl Scene {
    /// Tiles drawn from coarser data than their level's, and the bound the
    /// frame achieves with them: each such tile's error is its source
    /// node's delta seen from the tile's distance, or its parent's seen
    /// from where the morph starts (the grid's deltas for a tile made as a
    /// grid of the source's posts), so the frame's bound is the largest of
    /// those and `tau_px`. `k` is Ulrich's K.
    fn fallback_bound(&self, k: f64, tau_px: f64) -> (usize, f64) {
        let scale = k;
        let mut fallback = 0;
        let mut bound = tau_px;
        for tile in self.selector.selected() {
            let level = tile.key.level;
            let Some(made) = self.cache.made_from(tile.key) else { continue };
            let source = made.source_level;
            if source <= level {
                continue;
            }
            fallback += 1;
            let delta =
                |level: u8| made_delta(&self.deltas, &self.grid_deltas, made.node_mesh, level);
            // Inside its box the distance is 0: a metre keeps the bound finite.
            let near = tile.distance.max(1.0);
            // An extracted tile knows its own error; a grid its level's.
            let own_error =
                if made.error_m.is_finite() { made.error_m as f64 } else { delta(source) };
            let own = own_error * scale / near;
            // Its vertices morph toward the source's parent from the morph
            // start on, wherever in the tile they are.
            let parent =
                delta(source.saturating_add(1)) * scale / near.max(self.rings.morph(level).0);
            bound = bound.max(own.max(parent));
        }
        (fallback, bound)
    }

    /// The level-0 cells the last frame's view holds in its frustum, above
    /// and below the horizon (counted, not drawn; see [`frustum_census`]);
    /// `None` before a frame.
    pub fn census(&self, terrain: &dyn TerrainData) -> Option<Census> {
        let (grid_size, root) = (self.config.lod.grid_size, terrain.layout().levels - 1);
        let view = self.view.as_ref()?.census(self.config.curvature, grid_size, root);
        Some(frustum_census(&view, terrain))
    }
}

/// The lowest height terrain can have where the display draws none (see
/// [`crate::render::FrameUniforms::horizon_floor_m`]): sea level, or the data's lowest
/// height where a grid `placement` puts around the whole earth goes lower.
/// Only a grid that covers the earth may lower it: past a regional grid's
/// edge the terrain is unknown, and the earth's surface there (land or the
/// sea's surface) is at sea level or above it but for a few depressions.
pub fn horizon_floor_m(placement: Option<&GridPlacement>, lowest_m: f32) -> f32 {
    let covers = placement.is_some_and(GridPlacement::covers_the_earth);
    if covers && lowest_m.is_finite() {
        lowest_m.min(0.0)
    } else {
        0.0
    }
}

/// What the rings of a frame for `camera` depend on: tiles of `grid_size`
/// cells over `layout`, the per-level `deltas` and the data's height span.
/// The scene's rings and the clipmap's load radius both come from this.
pub fn ring_inputs<'a>(
    layout: &NodeLayout,
    grid_size: u32,
    deltas: &'a [f64],
    height_range_m: f64,
    camera: &Camera,
) -> RingInputs<'a> {
    RingInputs {
        tile_size_m: grid_size as f64 * layout.spacing_m[0].max(layout.spacing_m[1]),
        delta_per_level: deltas,
        height_range_m,
        perspective_scale: camera.perspective_scale(),
    }
}

fn ms(from: Instant, to: Instant) -> f64 {
    (to - from).as_secs_f64() * 1e3
}

fn root_tiles(terrain: &dyn TerrainData, grid_size: u32) -> u32 {
    let layout = terrain.layout();
    let [nx, ny] = crate::lod::select::tiles_at(layout.posts, grid_size, layout.levels - 1);
    nx * ny
}
