//! [`frustum_census`]: how many full-resolution cells a view holds, counted
//! and not drawn, for the triangle ratio of the LOD against full
//! resolution where the full-resolution mesh is too large to draw (a 10 km
//! cruise: 10^8 triangles and more).
//!
//! It walks the quadtree as the selector does, with the same frustum and
//! horizon tests, but always down to level 0: a tile entirely inside the
//! frustum counts all its level-0 cells at once, a tile outside or hidden
//! counts none, a tile across a plane is split. A level-0 tile across a
//! plane counts all its cells, so the count is an upper bound by at most a
//! tile along the frustum's edges.

use super::horizon::Horizon;
use super::select::{tile_box, tiles_at, TileBounds};
use super::TileKey;
use crate::camera::{curvature_drop, Frustum};
use glam::{DVec2, DVec3, Vec3};

/// What [`frustum_census`] counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Census {
    /// Level-0 cells (two full-resolution triangles each) in the frustum
    /// and above the horizon.
    pub cells: u64,
    /// Level-0 cells in the frustum but below the horizon.
    pub hidden_cells: u64,
}

/// The view [`frustum_census`] counts for.
pub struct CensusView<'a> {
    /// Camera position in the local frame, metres.
    pub eye: DVec3,
    /// Frustum in camera-relative coordinates.
    pub frustum: &'a Frustum,
    /// Apply the earth's curvature to bounding boxes.
    pub curvature: bool,
    /// The horizon tiles are hidden below (`None`: none are).
    pub horizon: Option<Horizon>,
    /// Cells per tile side.
    pub grid_size: u32,
    /// The root level.
    pub root: u8,
}

/// Counts the level-0 cells of `terrain` that `view` holds.
pub fn frustum_census(view: &CensusView<'_>, terrain: &dyn TileBounds) -> Census {
    let mut census = Census::default();
    let [nx, ny] = tiles_at(terrain.posts(), view.grid_size, view.root);
    let mut stack: Vec<TileKey> = Vec::new();
    for y in 0..ny {
        for x in 0..nx {
            stack.push(TileKey::new(view.root, x, y));
        }
    }
    let cells_of = |level: u8| {
        let side = (view.grid_size as u64) << level;
        side * side
    };
    while let Some(key) = stack.pop() {
        let (min, mut max) = tile_box(key, view.grid_size, terrain, view.eye);
        let mut lo = min;
        if view.curvature {
            let far = DVec2::new(min.x.abs().max(max.x.abs()), min.y.abs().max(max.y.abs()));
            lo.z -= curvature_drop(far.length());
        }
        max.z = max.z.max(lo.z);
        let (lo32, hi32) = (lo.as_vec3(), max.as_vec3());
        if !view.frustum.intersects_box(lo32, hi32) {
            continue;
        }
        let nearest = DVec2::ZERO.clamp(min.truncate(), max.truncate()).length();
        if view.horizon.is_some_and(|h| h.hides(nearest, max.z + view.eye.z)) {
            census.hidden_cells += cells_of(key.level);
            continue;
        }
        if key.level == 0 || inside(view.frustum, lo32, hi32) {
            census.cells += cells_of(key.level);
            continue;
        }
        let [cx, cy] = tiles_at(terrain.posts(), view.grid_size, key.level - 1);
        stack.extend(key.children().into_iter().filter(|c| c.x < cx && c.y < cy));
    }
    census
}

/// Whether the box `[min, max]` lies entirely inside the frustum.
fn inside(frustum: &Frustum, min: Vec3, max: Vec3) -> bool {
    frustum.planes.iter().all(|plane| {
        let normal = plane.truncate();
        let corner = Vec3::select(normal.cmpge(Vec3::ZERO), min, max);
        normal.dot(corner) + plane.w >= 0.0
    })
}
