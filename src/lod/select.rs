//! Per-frame refinement of the implicit quadtree: the thesis' Algorithm 1 run
//! on the CPU with an explicit stack, culling each tile against the terrain's
//! extent and the view frustum before deciding to split it.
//!
//! Tiles the frustum keeps may still lie below the horizon: those are
//! dropped too (see [`super::horizon`]) and counted apart.
//!
//! Both lists are allocated once, at `max_tiles`; a frame never allocates.
//! When refining further would exceed `max_tiles`, the tile is kept whole:
//! the view gets coarser, never a hole.
//!
//! With a declared travel per frame (`LodConfig::max_travel_m`) the split
//! test of a tile is taken from its valid life ([`super::life`]) while it
//! lasts; culling, the tile budget and the finer-data test are made on every
//! visit, so the selection is the one a full re-evaluation makes.

use super::horizon::Horizon;
use super::life::{LifeStats, ValidLife};
use super::{LevelRings, LodConfig, TileKey};
use crate::camera::{curvature_drop, Frustum};
use crate::earth::{EarthFrame, EllipsoidHorizon, PlaceCache};
use crate::node::{NodeId, NodeLayout};
use glam::DVec3;

/// A tile chosen for this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelectedTile {
    /// The tile to draw.
    pub key: TileKey,
    /// Distance from the camera to the tile's bounding box, metres.
    pub distance: f64,
}

/// What the selector needs to know about the terrain.
pub trait TileBounds {
    /// Level-0 posts east and north (the terrain's extent).
    fn posts(&self) -> [u32; 2];
    /// Post spacing at level 0, metres east and north.
    fn spacing_m(&self) -> [f64; 2];
    /// Lowest and highest height any level-0 sample under `tile` may have.
    fn height_bounds(&self, tile: TileKey, grid_size: u32) -> (f32, f32);
    /// Whether data finer than `tile`'s level lie under it: the node of
    /// level `tile.level - 1` holding its children is stored. Where it is
    /// absent, finer tiles would only resample `tile`'s own data (a 5' base
    /// drawn in 90 m tiles), so the tile is not split.
    fn has_finer_data(&self, tile: TileKey, grid_size: u32) -> bool;
}

/// Refines the quadtree each frame into a list of tiles.
pub struct TileSelector {
    config: LodConfig,
    stack: Vec<TileKey>,
    selected: Vec<SelectedTile>,
    /// Tiles dropped by the frustum in the last frame (for statistics).
    culled: usize,
    /// Tiles inside the frustum dropped below the horizon in the last frame.
    horizon_culled: usize,
    /// Valid lives of the split tests, when a travel per frame is declared.
    life: Option<ValidLife>,
    /// A projected grid's tile samples on the ellipsoid, across frames.
    places: PlaceCache,
}

/// A view to select tiles for: camera position, frustum and rings.
pub struct View<'a> {
    /// Camera position in the local frame, metres.
    pub eye: DVec3,
    /// Frustum in camera-relative coordinates.
    pub frustum: &'a Frustum,
    /// The rings to select from.
    pub rings: &'a LevelRings,
    /// Apply the earth's curvature to bounding boxes.
    pub curvature: bool,
    /// Cull tiles below this horizon (`None`: no horizon culling).
    pub horizon: Option<Horizon>,
    /// Boxes, distances and the horizon on the ellipsoid (the display's
    /// frame when it draws there), instead of the chart's.
    pub earth: Option<EarthView>,
}

/// What the selector measures tiles with on the ellipsoid.
#[derive(Clone, Copy, Debug)]
pub struct EarthView {
    /// The frame's eye and the grid's places.
    pub frame: EarthFrame,
    /// The ellipsoid's horizon under the data's lowest surface (`None`: no
    /// horizon culling).
    pub horizon: Option<EllipsoidHorizon>,
}

/// Why a tile is not drawn, or how far it is.
enum Visibility {
    /// Inside the frustum and above the horizon: distance to the box and to
    /// its farthest corner, and height bounds.
    Visible(f64, f64, (f32, f32)),
    /// Outside the frustum.
    Outside,
    /// Inside the frustum but hidden below the horizon.
    BelowHorizon,
}

impl TileSelector {
    /// A selector for `config`, its lists sized once to `max_tiles`.
    pub fn new(config: LodConfig) -> Self {
        TileSelector {
            config,
            stack: Vec::with_capacity(config.max_tiles + 4),
            selected: Vec::with_capacity(config.max_tiles),
            culled: 0,
            horizon_culled: 0,
            life: config.max_travel_m.map(|m| ValidLife::new(m, config.max_tiles + 4)),
            places: PlaceCache::default(),
        }
    }

    /// What the valid life did in the last selection; `None` without one
    /// (every tile tested every frame).
    pub fn life_stats(&self) -> Option<LifeStats> {
        self.life.as_ref().map(ValidLife::stats)
    }

    /// The tiling parameters it selects with.
    pub fn config(&self) -> &LodConfig {
        &self.config
    }

    /// Tiles dropped by the frustum in the last selection.
    pub fn culled(&self) -> usize {
        self.culled
    }

    /// Tiles the frustum kept but the horizon hid, in the last selection.
    pub fn horizon_culled(&self) -> usize {
        self.horizon_culled
    }

    /// The last selection.
    pub fn selected(&self) -> &[SelectedTile] {
        &self.selected
    }

    /// Selects the tiles for `view` over `terrain`; the result is valid until
    /// the next call.
    pub fn select(&mut self, view: &View<'_>, terrain: &dyn TileBounds) -> &[SelectedTile] {
        self.selected.clear();
        self.stack.clear();
        self.culled = 0;
        self.horizon_culled = 0;
        let root = (view.rings.levels() - 1) as u8;
        self.places.next_frame(view.earth.and_then(|e| e.frame.projected_lattice()));
        if let Some(life) = &mut self.life {
            // On the ellipsoid the eye's travel is the earth's (ECEF), and
            // the boxes turn with the camera's axes.
            let (eye, axes) = match &view.earth {
                Some(earth) => (earth.frame.eye(), Some(earth.frame.axes())),
                None => (view.eye, None),
            };
            life.begin(eye, axes, view.rings.levels(), |l| view.rings.split_distance(l));
        }
        let [nx, ny] = tiles_at(terrain.posts(), self.config.grid_size, root);
        for y in (0..ny).rev() {
            for x in (0..nx).rev() {
                self.stack.push(TileKey::new(root, x, y));
            }
        }
        while let Some(key) = self.stack.pop() {
            let (distance, far, bounds) = match self.visibility(key, view, terrain) {
                Visibility::Visible(distance, far, bounds) => (distance, far, bounds),
                Visibility::Outside => {
                    self.culled += 1;
                    continue;
                }
                Visibility::BelowHorizon => {
                    self.horizon_culled += 1;
                    continue;
                }
            };
            // Children replace this tile on the stack; keep room for the worst case.
            let room = self.selected.len() + self.stack.len() + 4 <= self.config.max_tiles;
            let split = key.level > 0 && self.split_test(key, (distance, far), bounds, view);
            if split && room && terrain.has_finer_data(key, self.config.grid_size) {
                let [nx, ny] = tiles_at(terrain.posts(), self.config.grid_size, key.level - 1);
                for child in key.children().into_iter().rev() {
                    if child.x < nx && child.y < ny {
                        self.stack.push(child);
                    }
                }
            } else {
                self.selected.push(SelectedTile { key, distance });
            }
        }
        &self.selected
    }

    /// Whether a tile of level above 0, `distance` from the eye (and `far`
    /// from its box's farthest corner), is inside its ring: kept from its
    /// valid life while that lasts.
    fn split_test(
        &mut self,
        key: TileKey,
        (distance, far): (f64, f64),
        bounds: (f32, f32),
        view: &View<'_>,
    ) -> bool {
        let ring = view.rings.split_distance(key.level);
        match &mut self.life {
            None => distance < ring,
            Some(life) => {
                let split = life.splits(key, bounds, ring, || (distance, far));
                // The distance is at hand anyway: check the kept outcome.
                debug_assert_eq!(split, distance < ring, "a stale split test kept for {key:?}");
                split
            }
        }
    }

    /// Distance to the tile's box and its height bounds, or why it is not drawn.
    fn visibility(
        &mut self,
        key: TileKey,
        view: &View<'_>,
        terrain: &dyn TileBounds,
    ) -> Visibility {
        let bounds = terrain.height_bounds(key, self.config.grid_size);
        if let Some(earth) = &view.earth {
            let grid_size = self.config.grid_size;
            return earth_visibility(key, grid_size, bounds, view.frustum, earth, &mut self.places);
        }
        let (min, max) = box_of(key, self.config.grid_size, terrain.spacing_m(), bounds, view.eye);
        let distance = box_distance(min, max);
        let (mut lo, hi) = (min, max);
        if view.curvature {
            // The surface drops with horizontal distance; the box must reach the
            // drop at its far corner.
            let far = DVec3::new(min.x.abs().max(max.x.abs()), min.y.abs().max(max.y.abs()), 0.0)
                .length();
            lo.z -= curvature_drop(far);
        }
        if !view.frustum.intersects_box(lo.as_vec3(), hi.as_vec3()) {
            return Visibility::Outside;
        }
        let hidden = view.horizon.is_some_and(|horizon| {
            let nearest = glam::DVec2::ZERO.clamp(min.truncate(), max.truncate()).length();
            horizon.hides(nearest, max.z + view.eye.z)
        });
        if hidden {
            Visibility::BelowHorizon
        } else {
            Visibility::Visible(distance, far_corner(min, max), bounds)
        }
    }
}

/// [`TileBounds::has_finer_data`] for a terrain whose stored nodes `has_node` says.
pub fn children_node_stored(
    tile: TileKey,
    grid_size: u32,
    layout: &NodeLayout,
    has_node: impl Fn(NodeId) -> bool,
) -> bool {
    if tile.level == 0 {
        return false;
    }
    let per_node = (layout.node_size / grid_size).max(1);
    tile.children()
        .iter()
        .any(|child| has_node(NodeId::new(child.level, child.x / per_node, child.y / per_node)))
}

/// Tiles per side at `level` that cover `samples` posts.
pub fn tiles_at(samples: [u32; 2], grid_size: u32, level: u8) -> [u32; 2] {
    let span = (grid_size as u64) << level;
    let count = |n: u32| ((n.saturating_sub(1) as u64).div_ceil(span).max(1)) as u32;
    [count(samples[0]), count(samples[1])]
}

/// The tile's bounding box relative to `eye`, in f64.
pub fn tile_box(
    key: TileKey,
    grid_size: u32,
    terrain: &dyn TileBounds,
    eye: DVec3,
) -> (DVec3, DVec3) {
    box_of(key, grid_size, terrain.spacing_m(), terrain.height_bounds(key, grid_size), eye)
}

/// The box of `key` with height `bounds`, relative to `eye`.
/// [`TileSelector::visibility`] on the ellipsoid: the tile's box in the
/// camera's axes ([`EarthFrame::camera_box`], the earth's curvature in it),
/// hidden when its eight corners are behind the ellipsoid's horizon.
fn earth_visibility(
    key: TileKey,
    grid_size: u32,
    bounds: (f32, f32),
    frustum: &Frustum,
    earth: &EarthView,
    places: &mut PlaceCache,
) -> Visibility {
    let span = ((grid_size as u64) << key.level) as f64;
    let p0 = [key.x as f64 * span, key.y as f64 * span];
    let p1 = [p0[0] + span, p0[1] + span];
    let heights = (bounds.0 as f64, bounds.1 as f64);
    let (min, max) = earth.frame.camera_box_with(p0, p1, heights, places);
    if !frustum.intersects_box(min.as_vec3(), max.as_vec3()) {
        return Visibility::Outside;
    }
    let hidden = earth.horizon.is_some_and(|horizon| {
        (0..8).all(|k| {
            let corner = DVec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            );
            horizon.hides(earth.frame.ecef_of(corner))
        })
    });
    if hidden {
        Visibility::BelowHorizon
    } else {
        Visibility::Visible(box_distance(min, max), far_corner(min, max), bounds)
    }
}

fn box_of(
    key: TileKey,
    grid_size: u32,
    [sx, sy]: [f64; 2],
    (lo_h, hi_h): (f32, f32),
    eye: DVec3,
) -> (DVec3, DVec3) {
    let span = ((grid_size as u64) << key.level) as f64;
    let min = DVec3::new(key.x as f64 * span * sx, key.y as f64 * span * sy, lo_h as f64);
    let max = DVec3::new(min.x + span * sx, min.y + span * sy, hi_h as f64);
    (min - eye, max - eye)
}

/// Distance from the origin to the farthest corner of the box `[min, max]`.
fn far_corner(min: DVec3, max: DVec3) -> f64 {
    min.abs().max(max.abs()).length()
}

/// Distance from the origin to the box `[min, max]`.
pub fn box_distance(min: DVec3, max: DVec3) -> f64 {
    let nearest = DVec3::ZERO.clamp(min, max);
    nearest.length()
}
