//! The one owner of tau: the requested tiling, the tau the next frames
//! select with (set, or a frame budget's controller's), the ceiling past
//! which raising it changes nothing, and the frame's search for a tau that
//! keeps a triangle budget's band ([`super::band`]), with the coarsening a
//! full buffer forces. The scene asks it which tiling to select with and
//! tells it what each try and each frame drew; nothing else sets tau.

use crate::lod::budget::{BudgetConfig, BudgetError, BudgetTarget, TauController};
use crate::lod::rings::RingInputs;
use crate::lod::select::SelectedTile;
use crate::lod::{LevelRings, LodConfig, LodError, TileKey};
use crate::mesh::code::threshold_code;
use crate::node::NodeId;
use crate::tiles::errors::{MapErrors, MeshErrors};
use crate::tiles::TileCache;

use super::band::{BandSearch, BandState};
use super::{SceneStats, TerrainData, TileEstimate, TriangleBand, View};

/// How far, as a share, the tiles made may miss a triangle budget before
/// the frame selects once more with their real count: under the 5 % a
/// budget promises, over the in-frame band the estimate aims at.
const CORRECTION_BAND: f64 = 0.04;

/// Corrections a frame may make: tiles whose errors grow with the distance
/// (`tiles::by_distance`) are remade at every tau, so a retake's count can
/// again miss what the estimate foretold; a second one closes it.
const MAX_CORRECTIONS: u8 = 2;

/// The band a triangle budget holds within each frame: 2 %, under half the
/// 5 % the budget promises, since the estimate of tiles yet to be remade
/// at another error is itself off by up to 3 % (measured on the default
/// flight); none for a frame-time target, which only the next frame can
/// measure.
const IN_FRAME_BAND: f64 = 0.02;

/// Tau from one frame to the next and within each.
pub(super) struct TauPolicy {
    /// The tiling asked for.
    requested: LodConfig,
    /// Tiles are extracted from error maps (tau coarsens their meshes),
    /// not made as grids (tau moves only the rings).
    maps: bool,
    /// Tau of the next frame, pixels: the requested one unless set.
    tau_px: f64,
    /// A frame budget's controller, which sets `tau_px` each frame.
    controller: Option<TauController>,
    band: BandState,
    /// Rings without Ulrich's rule, and the tau past which rings stop
    /// shrinking, of the last frame.
    loose_rings: LevelRings,
    ceiling: f64,
    /// This frame's tiling, its band search, and whether its tiles are
    /// being made again after a correction.
    lod: LodConfig,
    search: Option<BandSearch>,
    retaking: bool,
    /// Corrections made this frame.
    corrections: u8,
}

impl TauPolicy {
    /// The policy for `requested` tiling (tiles extracted from error maps
    /// when `maps`), its rings sized by `inputs`.
    pub fn new(requested: LodConfig, maps: bool, inputs: RingInputs<'_>) -> Self {
        TauPolicy {
            requested,
            maps,
            tau_px: requested.tau_px,
            controller: None,
            band: BandState::default(),
            loose_rings: LevelRings::new(&requested, inputs),
            ceiling: f64::INFINITY,
            lod: requested,
            search: None,
            retaking: false,
            corrections: 0,
        }
    }

    /// Sets the tau the next frames select with; refused when it is not
    /// finite or below the requested tau.
    pub fn set_tau(&mut self, tau_px: f64) -> Result<(), LodError> {
        if !(tau_px.is_finite() && tau_px >= self.requested.tau_px) {
            return Err(LodError::Tau(tau_px));
        }
        self.tau_px = tau_px;
        Ok(())
    }

    /// Keeps the next frames' triangles inside `band`; `None`: no band.
    pub fn set_band(&mut self, band: Option<TriangleBand>) {
        self.band.band = band;
    }

    /// Holds each frame to `budget` from now on (`None`: tau as set).
    pub fn set_budget(&mut self, budget: Option<BudgetConfig>) -> Result<(), BudgetError> {
        let tau = self.requested.tau_px;
        self.controller = budget.map(|b| TauController::new(tau, b)).transpose()?;
        Ok(())
    }

    /// The frame budget's controller, when there is a budget.
    pub fn controller(&self) -> Option<&TauController> {
        self.controller.as_ref()
    }

    /// The tau past which the last frame's rings stop shrinking, pixels.
    pub fn ceiling(&self) -> f64 {
        self.ceiling
    }

    /// The tiling the frame's next try selects with.
    pub fn lod(&self) -> &LodConfig {
        &self.lod
    }

    /// Whether the frame's tiles are being made again after a correction.
    pub fn retaking(&self) -> bool {
        self.retaking
    }

    /// Starts a frame for `view`: the budget's tau and band, the ceiling
    /// (from the rings without Ulrich's rule, or with error maps the tau at
    /// which every level reaches its coarsest meshes: `errors` are left at
    /// the requested tiling's), and the band's search between the two.
    pub fn begin(
        &mut self,
        view: &View,
        deltas: &[f64],
        maps: &MapErrors,
        errors: &mut MeshErrors,
        levels: u8,
    ) -> Result<(), LodError> {
        if let Some(controller) = &self.controller {
            let (tau, band) = (controller.tau_px(), triangle_band(controller.config()));
            self.set_tau(tau)?;
            self.set_band(band);
        }
        let (requested, inputs) = (self.requested, view.ring_inputs(deltas));
        self.lod = loosened(&requested, self.tau_px, !self.maps);
        self.ceiling = if self.maps {
            self.loose_rings.update(&requested, inputs);
            let rings = &self.loose_rings;
            let split = |level| rings.split_distance(level);
            let (tau, morph) = (requested.tau_px, requested.morph_range);
            errors.update(split, levels, view.k, tau, morph, maps);
            errors.tau_ceiling(maps, view.k, tau)
        } else {
            let loosest = LodConfig { view_distance: 1.0, ..requested };
            let ceiling = LevelRings::tau_ceiling(&mut self.loose_rings, &loosest, inputs);
            ceiling.max(requested.tau_px * requested.view_distance)
        };
        self.search = self.band.search(requested.tau_px, self.ceiling);
        self.retaking = false;
        self.corrections = 0;
        Ok(())
    }

    /// After a selection of `tiles` (estimated, with `coarsened` times the
    /// frame was coarsened so far): whether to select again, at the tau
    /// the band's search moved to.
    pub fn retarget(&mut self, tiles: impl Iterator<Item = TileEstimate>, coarsened: u32) -> bool {
        let Some(search) = self.search.as_mut().filter(|_| coarsened == 0) else {
            return false;
        };
        let estimate = self.band.estimate(tiles);
        let next = search.next(estimate, self.lod.tau_px);
        self.reselect(next)
    }

    /// After the tiles were made, drawing `drawn` triangles: whether to
    /// select once more with that real count (the tiles remade at another
    /// error hold counts the estimate only foretold), making the tiles
    /// again ([`Self::retaking`]). At most [`MAX_CORRECTIONS`] a frame.
    pub fn correct(&mut self, drawn: f64) -> bool {
        let more = self.corrections < MAX_CORRECTIONS;
        let Some(search) = self.search.as_mut().filter(|_| more) else {
            return false;
        };
        if (drawn / search.target() - 1.0).abs() <= CORRECTION_BAND {
            return false;
        }
        let next = search.correct(drawn, self.lod.tau_px);
        self.corrections += 1;
        self.retaking = self.reselect(next);
        self.retaking
    }

    /// After the buffer was full: whether the frame can select coarser,
    /// with half the rings (Ulrich's rule through tau, Kühnert's through
    /// distance).
    pub fn coarsen(&mut self) -> bool {
        let lod = &mut self.lod;
        if !(lod.view_distance > 1.0 || lod.tau_px < 1e6) {
            return false;
        }
        self.retaking = false;
        lod.view_distance = (lod.view_distance / 2.0).max(1.0);
        lod.tau_px *= 2.0;
        true
    }

    /// Ends a frame that drew `stats` (learning the estimate's bias when
    /// it was not coarsened) from `tiles` (level, triangles, the error
    /// made at).
    pub fn end(&mut self, stats: &SceneStats, tiles: impl Iterator<Item = (u8, u64, f64)>) {
        if stats.coarsened == 0 {
            self.band.observe(stats.triangles);
        }
        self.band.learn(tiles);
    }

    /// Feeds the frame budget's controller what a frame drew (`stats`)
    /// and how long it took in all (`frame_ms`), for the next frame's tau.
    pub fn observe(&mut self, stats: &SceneStats, frame_ms: f64) {
        let ceiling = self.ceiling;
        if let Some(controller) = &mut self.controller {
            controller.set_ceiling(ceiling);
            if stats.reselected > 0 && stats.coarsened == 0 {
                controller.adopt(stats.tau_px);
            }
            controller.observe(match controller.config().target {
                BudgetTarget::Triangles(_) => stats.triangles as f64,
                BudgetTarget::FrameMs(_) => frame_ms,
            });
        }
    }

    /// Takes `next`, a tau to select again with, if any.
    fn reselect(&mut self, next: Option<f64>) -> bool {
        if let Some(tau_px) = next {
            self.lod = loosened(&self.requested, tau_px, !self.maps);
        }
        next.is_some()
    }
}

/// The band a frame budget of `config` holds within each frame.
fn triangle_band(config: &BudgetConfig) -> Option<TriangleBand> {
    match config.target {
        BudgetTarget::Triangles(n) => {
            Some(TriangleBand { target: n as f64, tolerance: IN_FRAME_BAND })
        }
        BudgetTarget::FrameMs(_) => None,
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

/// The band's estimate of each `selected` tile: resident ones by their
/// own triangles, scaled by the source's map where it is resident (then as
/// made at the wanted error), else by the errors' ratio in the band.
/// Skirts follow a tile's edge vertices: the square root of what its
/// surface does.
pub(super) fn estimates<'a>(
    selected: &'a [SelectedTile],
    cache: &'a TileCache,
    errors: &'a MeshErrors,
    terrain: &'a dyn TerrainData,
    grid_size: u32,
) -> impl Iterator<Item = TileEstimate> + 'a {
    selected.iter().map(move |t| {
        let leaf = !terrain.has_finer_data(t.key, grid_size);
        let sub = errors.for_tile(t.key.level, t.distance, leaf).sub_level;
        let wanted = errors.allowed_m(t.key.level, sub);
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
    })
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
