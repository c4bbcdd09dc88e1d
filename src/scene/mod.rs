//! One frame of the display, GL-free: the rings for the current camera, the
//! tile selection, the tile cache's uploads and the draw list, with the time
//! each stage took. A renderer backend consumes the result.
//!
//! When the GPU buffer cannot take a frame's new tiles, the frame is selected
//! again with rings half as wide (coarser tiles), down to the root level,
//! whose tiles are always resident: the picture gets coarser, never a hole.

mod band;
mod clipmap_terrain;
mod terrain;

pub use band::{TileEstimate, TriangleBand, MAX_RESELECTIONS};

pub use clipmap_terrain::{ClipmapTerrain, TerrainSummary};
pub use terrain::{PreloadedTerrain, TerrainData};

use crate::camera::{Camera, CameraError, Frustum, EARTH_RADIUS_M};
use crate::clusters::{ClusterCache, ClusterConfig, ClusterError};
use crate::earth::{EarthFrame, EllipsoidHorizon, GridPlacement};
use crate::lod::census::{frustum_census, Census, CensusView};
use crate::lod::horizon::Horizon;
use crate::lod::life::LifeStats;
use crate::lod::rings::RingInputs;
use crate::lod::select::{EarthView, View};
use crate::lod::{LevelRings, LodConfig, LodError, TileKey, TileSelector};
use crate::mesh::code::threshold_code;
use crate::node::{NodeId, NodeLayout};
use crate::render::draw_list::{made_delta, TileGeometry};
use crate::render::draw_list::{DepthSlices, PostFrame};
use crate::render::{palette, BufferPlan, ClusterMorph, ClusterOrder, DrawList, FrameUniforms};
use crate::tiles::errors::{MapErrors, MeshErrors};
use crate::tiles::{TileCache, TileCacheConfig, TileError};
use std::time::Instant;

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
    /// Which morph range a cluster's members take (tests break it on purpose).
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
    height_range_m: f64,
    /// Tau of the next frame, pixels: the configured one unless a budget set it.
    tau_px: f64,
    /// Rings without Ulrich's rule, and the tau past which rings stop
    /// shrinking (a budget's ceiling), of the last frame.
    loose_rings: LevelRings,
    tau_ceiling: f64,
    band: band::BandState,
    /// With clusters on: their blocks, which the GPU buffer then mirrors.
    clusters: Option<ClusterCache>,
    /// What the terrain's error maps can do per level.
    map_errors: MapErrors,
    /// The errors this frame's tiles are extracted at.
    mesh_errors: MeshErrors,
}

/// How far, as a share, the tiles made may miss a triangle budget before
/// the frame selects once more with their real count: under the 5 % a
/// budget promises, over the in-frame band the estimate aims at.
const CORRECTION_BAND: f64 = 0.04;

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
        let (lo, hi) = terrain.height_range();
        let mut draw_list = DrawList::with_capacity(cache_config.max_tiles as usize);
        draw_list.cluster_morph = config.cluster_morph;
        draw_list.cluster_order = config.cluster_order;
        let plan = BufferPlan::new(config.buffer_bytes, config.clusters);
        let clusters = if let Some(index_capacity_bytes) = plan.cluster_index_bytes {
            Some(ClusterCache::new(ClusterConfig {
                capacity_bytes: plan.buffer_bytes,
                index_capacity_bytes,
                max_clusters: cache_config.max_tiles,
                transfer_cap: config.transfer_cap,
                frames_in_flight: config.frames_in_flight,
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
        Ok(Scene {
            loose_rings: LevelRings::new(&config.lod, inputs),
            tau_ceiling: f64::INFINITY,
            band: band::BandState::default(),
            clusters,
            config,
            selector: TileSelector::new(config.lod),
            cache: TileCache::new(cache_config, terrain)?,
            rings: LevelRings::new(&config.lod, inputs),
            draw_list,
            height_range_m: (hi - lo) as f64,
            deltas,
            grid_deltas: terrain.grid_delta_per_level(),
            tau_px: config.lod.tau_px,
            map_errors: terrain.map_errors(),
            mesh_errors: MeshErrors::default(),
        })
    }

    /// Sets the tau the next frames select with (a frame budget's), pixels;
    /// Kühnert's view distance shrinks by the same factor, down to 1 tile.
    /// Refused when it is not finite or below the configured tau.
    pub fn set_tau(&mut self, tau_px: f64) -> Result<(), SceneError> {
        if !(tau_px.is_finite() && tau_px >= self.config.lod.tau_px) {
            return Err(LodError::Tau(tau_px).into());
        }
        self.tau_px = tau_px;
        Ok(())
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

    /// Keeps the next frames' triangles inside `band` (a triangle budget's)
    /// by selecting again within the frame; `None`: no band.
    pub fn set_triangle_band(&mut self, band: Option<TriangleBand>) {
        self.band.band = band;
    }

    /// The tau past which the last frame's rings stop shrinking, pixels,
    /// with the view distance shrinking alongside ([`Scene::set_tau`]): a
    /// budget raising tau further gains nothing.
    pub fn tau_ceiling(&self) -> f64 {
        self.tau_ceiling
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

    /// Prepares one frame for `camera`.
    pub fn frame(
        &mut self,
        camera: &Camera,
        terrain: &dyn TerrainData,
    ) -> Result<SceneStats, SceneError> {
        camera.validate()?;
        let layout = *terrain.layout();
        let grid_size = self.config.lod.grid_size;
        // Culling uses the widest frustum (the conservative near plane);
        // drawing uses one pushed out to the nearest selected tile.
        let (near, far) = clip_planes(camera, terrain);
        let frustum = Frustum::from_view_projection(camera.projection(near, far) * camera.view());
        let mut report = SceneStats::default();
        let horizon = self.horizon(camera, terrain);
        let earth_view = self.earth_view(camera, terrain, horizon.is_some());
        // With error maps tau coarsens the meshes; without, only the rings,
        // so Kühnert's view distance shrinks with it.
        let maps = !self.map_errors.is_empty();
        let mut lod = loosened(&self.config.lod, self.tau_px, !maps);
        let mut nearest_m: f64;
        let inputs = ring_inputs(&layout, grid_size, &self.deltas, self.height_range_m, camera);
        let requested = self.config.lod;
        self.tau_ceiling = if maps {
            let (rings, errors) = (&mut self.loose_rings, &mut self.mesh_errors);
            let k = camera.perspective_scale();
            mesh_ceiling(rings, errors, &self.map_errors, &requested, inputs, layout.levels, k)
        } else {
            let loosest = LodConfig { view_distance: 1.0, ..requested };
            let ceiling = LevelRings::tau_ceiling(&mut self.loose_rings, &loosest, inputs);
            ceiling.max(requested.tau_px * requested.view_distance)
        };
        let mut search = self.band.search(requested.tau_px, self.tau_ceiling);
        let mut retaking = false;
        loop {
            let start = Instant::now();
            let inputs = ring_inputs(&layout, grid_size, &self.deltas, self.height_range_m, camera);
            self.rings.update(&lod, inputs);
            let rings = &self.rings;
            self.mesh_errors.update(
                |level| rings.split_distance(level),
                layout.levels,
                camera.perspective_scale(),
                lod.tau_px,
                lod.morph_range,
                &self.map_errors,
            );
            let view = View {
                eye: camera.position,
                frustum: &frustum,
                rings: &self.rings,
                curvature: self.config.curvature,
                horizon,
                earth: earth_view,
            };
            let selected = self.selector.select(&view, terrain);
            let retarget = match (&mut search, report.coarsened) {
                (Some(search), 0) => {
                    let (cache, errors) = (&self.cache, &self.mesh_errors);
                    let tiles = selected.iter().map(|t| {
                        let leaf = !terrain.has_finer_data(t.key, grid_size);
                        let wanted = errors.for_tile(t.key.level, t.distance, leaf).own.metres();
                        // Scaled by the source's map where it is resident
                        // (then as made at the wanted error), else by the
                        // errors' ratio in the band.
                        // Skirts follow a tile's edge vertices: the square
                        // root of what its surface does.
                        let resident = cache.resident_parts(t.key).map(|(n, skirts, made)| {
                            match map_scale(cache, terrain, t.key, grid_size, made, wanted) {
                                Some(s) => {
                                    let scaled = n as f64 * s + skirts as f64 * s.sqrt();
                                    (scaled.round() as u64, wanted)
                                }
                                None => (n + skirts, made),
                            }
                        });
                        TileEstimate { level: t.key.level, resident, error_m: wanted }
                    });
                    let estimate = self.band.estimate(tiles);
                    search.next(estimate, lod.tau_px)
                }
                _ => None,
            };
            if let Some(tau_px) = retarget {
                lod = loosened(&self.config.lod, tau_px, !maps);
                report.reselected += 1;
                report.cpu_ms.select_ms += ms(start, Instant::now());
                continue;
            }
            nearest_m = selected.iter().map(|t| t.distance).fold(f64::INFINITY, f64::min);
            let selected_at = Instant::now();
            report.cpu_ms.select_ms += ms(start, selected_at);
            let tiles = match retaking {
                true => self.cache.retake(selected, terrain, &self.mesh_errors),
                false => self.cache.update(selected, terrain, &self.mesh_errors),
            };
            let outcome = tiles.map(|_| ()).map_err(SceneError::from);
            report.cpu_ms.tiles_ms += ms(selected_at, Instant::now());
            // The tiles remade at another error hold counts the estimate
            // only foretold: off the budget's promise, select once more
            // with the real count (the tiles made stay for this frame).
            if let (Ok(()), Some(search), false) = (&outcome, &mut search, retaking) {
                let drawn = self.cache.drawn_triangles() as f64;
                let off = (drawn / search.target() - 1.0).abs();
                if off > CORRECTION_BAND {
                    if let Some(tau_px) = search.correct(drawn, lod.tau_px) {
                        lod = loosened(&self.config.lod, tau_px, !maps);
                        report.reselected += 1;
                        retaking = true;
                        continue;
                    }
                }
            }
            let outcome = outcome.and_then(|()| {
                let near_m = (nearest_m * NEAR_SHARE).min(f32::MAX as f64) as f32;
                let uniforms = frame_uniforms(&self.config, camera, terrain, near_m);
                let start = Instant::now();
                let geometry = TileGeometry {
                    grid_size,
                    node_size: layout.node_size,
                    spacing_m: layout.spacing_m,
                    delta_per_level: &self.deltas,
                    grid_delta_per_level: &self.grid_deltas,
                    mesh_errors: &self.mesh_errors,
                };
                self.draw_list.build(uniforms, self.cache.draws(), &self.rings, geometry);
                if let Some(clusters) = &mut self.clusters {
                    let (staging, dirty) = (self.cache.staging(), self.cache.dirty_ranges());
                    clusters.update(&mut self.draw_list, staging, dirty)?;
                }
                report.cpu_ms.draw_list_ms = ms(start, Instant::now());
                Ok(())
            });
            // A cluster that no window has room for is a full buffer too:
            // coarser tiles make smaller clusters.
            let full = matches!(
                outcome,
                Err(SceneError::Tiles(TileError::BufferFull(_)))
                    | Err(SceneError::Clusters(
                        ClusterError::BufferFull(_) | ClusterError::NoWindow { .. }
                    ))
            );
            match outcome {
                Ok(()) => break,
                Err(_) if full && (lod.view_distance > 1.0 || lod.tau_px < 1e6) => {
                    retaking = false;
                    // Coarser: half the rings (Ulrich's rule through tau, Kühnert's through distance).
                    lod.view_distance = (lod.view_distance / 2.0).max(1.0);
                    lod.tau_px *= 2.0;
                    report.coarsened += 1;
                }
                Err(error) => return Err(error),
            }
        }
        let stats = self.cache.stats();
        report.tiles = self.draw_list.tiles.len();
        report.culled = self.selector.culled();
        report.horizon_culled = self.selector.horizon_culled();
        report.tau_px = lod.tau_px;
        (report.fallback_tiles, report.bound_px) = self.fallback_bound(camera, lod.tau_px);
        report.split_tests = self.selector.life_stats().unwrap_or_default();
        report.triangles = self.draw_list.triangles();
        if report.coarsened == 0 {
            self.band.observe(report.triangles);
        }
        let cache = &self.cache;
        self.band.learn(self.draw_list.tiles.iter().map(|t| {
            let made = cache.resident_triangles(t.key).map_or(f64::NAN, |(_, e)| e);
            (t.key.level, t.triangles(), made)
        }));
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
        Ok(report)
    }
}

impl Scene {
    /// Tiles drawn from coarser data than their level's, and the bound the
    /// frame achieves with them: each such tile's error is its source
    /// node's delta seen from the tile's distance, or its parent's seen
    /// from where the morph starts (the grid's deltas for a tile made as a
    /// grid of the source's posts), so the frame's bound is the largest of
    /// those and `tau_px`.
    fn fallback_bound(&self, camera: &Camera, tau_px: f64) -> (usize, f64) {
        let scale = camera.perspective_scale();
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

    /// The horizon tiles are culled below for `camera`: over the data's
    /// lowest height, when the curvature is drawn, horizon culling is on and
    /// the camera is over the data's rectangle (see [`crate::lod::horizon`]).
    fn horizon(&self, camera: &Camera, terrain: &dyn TerrainData) -> Option<Horizon> {
        let layout = terrain.layout();
        let inside = |at: f64, posts: u32, spacing: f64| {
            at >= 0.0 && at <= posts.saturating_sub(1) as f64 * spacing
        };
        let p = camera.position;
        let over_data = inside(p.x, layout.posts[0], layout.spacing_m[0])
            && inside(p.y, layout.posts[1], layout.spacing_m[1]);
        let on = self.config.horizon_culling && self.config.curvature && over_data;
        on.then(|| Horizon::new(p.z, terrain.height_range().0 as f64)).flatten()
    }

    /// What the selector measures tiles with on the ellipsoid, when the
    /// display draws there: the frame's eye and, when `culling` (the
    /// chart's conditions for horizon culling hold), the ellipsoid's
    /// horizon under the data's lowest height.
    fn earth_view(
        &self,
        camera: &Camera,
        terrain: &dyn TerrainData,
        culling: bool,
    ) -> Option<EarthView> {
        let frame = EarthFrame::new(&self.config.earth?, camera.position, [0, 0])?;
        let floor = terrain.height_range().0 as f64;
        let horizon = culling.then(|| EllipsoidHorizon::new(frame.eye(), floor)).flatten();
        Some(EarthView { frame, horizon })
    }

    /// The level-0 cells a frame for `camera` holds in its frustum, above
    /// and below the horizon (counted, not drawn; see [`frustum_census`]).
    pub fn census(&self, camera: &Camera, terrain: &dyn TerrainData) -> Census {
        let (near, far) = clip_planes(camera, terrain);
        let frustum = Frustum::from_view_projection(camera.projection(near, far) * camera.view());
        let view = CensusView {
            eye: camera.position,
            frustum: &frustum,
            curvature: self.config.curvature,
            horizon: self.horizon(camera, terrain),
            grid_size: self.config.lod.grid_size,
            root: terrain.layout().levels - 1,
        };
        frustum_census(&view, terrain)
    }
}

/// The uniforms every pass of a frame for `camera` shares: projection,
/// bands, sun, curvature. The far plane comes from [`clip_planes`]; the
/// near plane is `near_m` (at least [`clip_planes`]' near): [`Scene::frame`]
/// puts it 80 % of the way to the nearest tile it selected, since a 24-bit
/// depth buffer resolves `d^2 / (near 2^24)` metres at distance `d` (560 m
/// at 68 km with a 0.5 m near plane: far ridges then fought over pixels;
/// 1.5 m with the near plane at 180 m).
pub fn frame_uniforms(
    config: &SceneConfig,
    camera: &Camera,
    terrain: &dyn TerrainData,
    near_m: f32,
) -> FrameUniforms {
    let (near, far) = clip_planes(camera, terrain);
    let near = near.max(near_m.min(far / 10.0));
    FrameUniforms {
        view_projection: camera.projection(near, far) * camera.view(),
        camera_altitude: camera.position.z,
        sun_direction: palette::sun_direction(),
        curvature: config.curvature,
        horizon_floor_m: horizon_floor_m(config.earth.as_ref(), terrain.height_range().0),
        warning_above_m: config.warning_above_m,
        caution_below_m: config.caution_below_m,
        viewport: camera.viewport,
        fog_distance_m: far,
        posts: PostFrame::new(camera.position.truncate(), terrain.layout().spacing_m),
        last_post: terrain.layout().posts.map(|p| p as i64 - 1),
        slices: DepthSlices::new(camera, near, far, terrain.height_range()),
        earth: config.earth.and_then(|placement| {
            let anchor = PostFrame::new(camera.position.truncate(), terrain.layout().spacing_m);
            EarthFrame::new(&placement, camera.position, anchor.anchor)
        }),
    }
}

/// The lowest height terrain can have where the display draws none (see
/// [`FrameUniforms::horizon_floor_m`]): sea level, or the data's lowest
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

/// The tiling for a budget's `tau_px`: tau itself, and, when `shrink`
/// (tiles made as grids, whose triangles tau cannot change), Kühnert's
/// view distance shrunk by as much as tau grew (never below 1 tile), so the
/// rings shrink even where his rule, not Ulrich's, sets them. Tiles
/// extracted from error maps coarsen with tau instead: their rings stay.
/// The bound drawn is still `tau_px`: Ulrich's rule is kept at every level.
fn loosened(requested: &LodConfig, tau_px: f64, shrink: bool) -> LodConfig {
    let factor = if shrink { tau_px / requested.tau_px } else { 1.0 };
    let view_distance = (requested.view_distance / factor).max(1.0);
    LodConfig { tau_px, view_distance, ..*requested }
}

/// How a resident tile's triangles scale from the error it was made at to
/// `wanted`, read from its source node's error map: the posts whose split
/// the one error makes and the other does not (`ErrorMap::above`). `None`
/// for a grid or a node no longer resident.
fn map_scale(
    cache: &TileCache,
    terrain: &dyn TerrainData,
    key: TileKey,
    grid_size: u32,
    made: f64,
    wanted: f64,
) -> Option<f64> {
    let from = cache.made_from(key)?;
    if !(from.node_mesh && made > 0.0 && wanted > 0.0) {
        return None;
    }
    let (node, _) = crate::tiles::vertex::tile_node(key, grid_size, terrain.layout().node_size);
    let shift = from.source_level.checked_sub(node.level)?;
    let source = NodeId::new(from.source_level, node.x >> shift, node.y >> shift);
    let map = &terrain.resident(source)?.map;
    let quadrants = tile_quadrants(key, grid_size, terrain.layout().node_size, source);
    let above = |error: f64| map.above_in(quadrants, threshold_code(error));
    // The corners and forced posts every mesh has keep small meshes finite.
    let base = 16.0;
    Some((above(wanted) as f64 + base) / (above(made) as f64 + base))
}

/// The quadrants of node `source` tile `key` covers (a bit each, `x + 2 y`).
fn tile_quadrants(key: TileKey, grid_size: u32, node_size: u32, source: NodeId) -> u8 {
    let span = |level: u8, cells: u32| (cells as u64) << level;
    let (tile, node) = (span(key.level, grid_size), span(source.level, node_size));
    let half = node / 2;
    let lo = [key.x as u64 * tile, key.y as u64 * tile];
    let origin = [source.x as u64 * node, source.y as u64 * node];
    let mut bits = 0;
    for q in 0..4u8 {
        let (qx, qy) = ((q & 1) as u64, (q >> 1) as u64);
        let q0 = [origin[0] + qx * half, origin[1] + qy * half];
        let meets = (0..2).all(|k| lo[k] < q0[k] + half && lo[k] + tile > q0[k]);
        if meets {
            bits |= 1 << q;
        }
    }
    bits.max(1)
}

/// The tau past which tiles extracted from error maps get no coarser
/// (every level at its coarsest meshes), for the rings of `requested`
/// (made in `rings`, the errors in `errors`).
fn mesh_ceiling(
    rings: &mut LevelRings,
    errors: &mut MeshErrors,
    maps: &MapErrors,
    requested: &LodConfig,
    inputs: RingInputs<'_>,
    levels: u8,
    k: f64,
) -> f64 {
    rings.update(requested, inputs);
    let rings = &*rings;
    let split = |level| rings.split_distance(level);
    let (tau, morph) = (requested.tau_px, requested.morph_range);
    errors.update(split, levels, k, tau, morph, maps);
    errors.tau_ceiling(maps, k, tau)
}

fn ms(from: Instant, to: Instant) -> f64 {
    (to - from).as_secs_f64() * 1e3
}

fn root_tiles(terrain: &dyn TerrainData, grid_size: u32) -> u32 {
    let layout = terrain.layout();
    let [nx, ny] = crate::lod::select::tiles_at(layout.posts, grid_size, layout.levels - 1);
    nx * ny
}

/// Near and far planes: near shrinks as the aircraft nears the terrain (never
/// below half a metre), far reaches the farthest corner of the data or the
/// horizon, whichever is nearer.
pub fn clip_planes(camera: &Camera, terrain: &dyn TerrainData) -> (f32, f32) {
    let layout = terrain.layout();
    let (lo, hi) = terrain.height_range();
    let above = (camera.position.z - hi as f64).max(camera.position.z - lo as f64).abs();
    let clearance = (camera.position.z - hi as f64).max(1.0);
    let near = (clearance * 0.25).clamp(0.5, 50.0);
    let extent = glam::DVec2::new(
        layout.posts[0] as f64 * layout.spacing_m[0],
        layout.posts[1] as f64 * layout.spacing_m[1],
    );
    let eye = camera.position.truncate();
    let corners = [
        glam::DVec2::ZERO,
        glam::DVec2::new(extent.x, 0.0),
        glam::DVec2::new(0.0, extent.y),
        extent,
    ];
    let data_far = corners.iter().map(|c| c.distance(eye)).fold(0.0, f64::max) + above;
    let horizon = (2.0 * EARTH_RADIUS_M * above.max(1.0)).sqrt() + 200_000.0;
    (near as f32, data_far.min(horizon).max(near * 10.0) as f32)
}
