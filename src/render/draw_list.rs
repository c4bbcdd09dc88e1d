//! One frame's draw data: the per-frame uniforms and, per tile, only what the
//! shader cannot share: the tile's transform, its morph range and skirt depth,
//! and where its vertex data starts (Polok: transforms in uniforms).
//!
//! Every position is relative to the camera and computed in f64 before it is
//! narrowed to f32, so nothing jitters far from the origin.

use crate::camera::Camera;
use crate::lod::{LevelRanges, TileKey};
use crate::tiles::TileDraw;
use glam::{DVec2, Mat4, Vec3};

/// Uniforms shared by every tile of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameUniforms {
    /// Projection times the rotation-only view.
    pub view_projection: Mat4,
    /// Camera altitude above mean sea level, metres (terrain awareness and
    /// the vertical offset of every vertex).
    pub camera_altitude: f64,
    /// Unit vector toward the sun in the local frame.
    pub sun_direction: Vec3,
    /// Whether to lower vertices by the earth's curvature.
    pub curvature: bool,
    /// Terrain-awareness bands, metres relative to the aircraft: terrain above
    /// `warning_above_m` is red, above `-caution_below_m` amber.
    pub warning_above_m: f32,
    pub caution_below_m: f32,
    pub viewport: [u32; 2],
    /// Distance at which fog has fully hidden the terrain, metres.
    pub fog_distance_m: f32,
}

/// Per-tile uniforms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileUniforms {
    pub key: TileKey,
    /// South-west corner of the tile relative to the camera, metres.
    pub origin: [f32; 2],
    /// Metres between the tile's posts, east and north.
    pub spacing: [f32; 2],
    /// Morph start and end distances (equal and huge for no morph).
    pub morph: [f32; 2],
    /// How far skirt vertices hang below the edge, metres.
    pub skirt_depth: f32,
    pub byte_offset: u32,
}

/// Everything drawn in one frame; buffers are kept and reused.
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    pub frame: Option<FrameUniforms>,
    pub tiles: Vec<TileUniforms>,
    /// Indices per tile in the shared index buffer.
    pub indices_per_tile: u32,
}

/// How tiles map to metres and how deep their skirts hang.
#[derive(Clone, Copy, Debug)]
pub struct TileGeometry<'a> {
    pub grid_size: u32,
    /// Level-0 post spacing, metres.
    pub spacing_m: [f64; 2],
    /// Largest geometric error per level, metres.
    pub delta_per_level: &'a [f64],
}

impl DrawList {
    pub fn with_capacity(tiles: usize) -> Self {
        DrawList { frame: None, tiles: Vec::with_capacity(tiles), indices_per_tile: 0 }
    }

    /// Rebuilds the list for `camera` from the tile cache's draws.
    pub fn build(&mut self, camera: &Camera, frame: FrameUniforms, draws: &[TileDraw], ranges: &LevelRanges, geometry: TileGeometry<'_>) {
        self.frame = Some(frame);
        self.tiles.clear();
        let eye = DVec2::new(camera.position.x, camera.position.y);
        for draw in draws {
            self.tiles.push(tile_uniforms(draw, eye, ranges, &geometry));
        }
        self.sort_front_to_back(geometry.grid_size);
    }

    /// Orders the tiles (of `grid_size` cells) nearest first: terrain hidden
    /// behind a near ridge then fails the depth test before it is shaded
    /// (early z) instead of being shaded and overdrawn. On llvmpipe this
    /// took the default flight from about 125 to 70 ms a frame. In place, so
    /// no allocation.
    pub fn sort_front_to_back(&mut self, grid_size: u32) {
        let cells = grid_size as f32;
        let distance = |tile: &TileUniforms| centre_distance_squared(tile, cells);
        self.tiles.sort_unstable_by(|a, b| distance(a).total_cmp(&distance(b)));
    }
}

/// Squared ground distance from the camera to a tile's centre.
fn centre_distance_squared(tile: &TileUniforms, cells: f32) -> f32 {
    let centre = |k: usize| tile.origin[k] + 0.5 * tile.spacing[k] * cells;
    centre(0) * centre(0) + centre(1) * centre(1)
}

fn tile_uniforms(draw: &TileDraw, eye: DVec2, ranges: &LevelRanges, geometry: &TileGeometry<'_>) -> TileUniforms {
    let key = draw.key;
    let scale = (1u64 << key.level) as f64;
    let spacing = DVec2::new(geometry.spacing_m[0], geometry.spacing_m[1]) * scale;
    let span = geometry.grid_size as f64;
    let corner = DVec2::new(key.x as f64 * span, key.y as f64 * span) * spacing;
    let origin = corner - eye;
    let (start, end) = ranges.morph(key.level);
    let morph = if start.is_finite() { [start as f32, end as f32] } else { [f32::MAX, f32::MAX] };
    TileUniforms {
        key,
        origin: [origin.x as f32, origin.y as f32],
        spacing: [spacing.x as f32, spacing.y as f32],
        morph,
        skirt_depth: skirt_depth(draw, geometry.delta_per_level),
        byte_offset: draw.byte_offset,
    }
}

/// Skirts must reach below any surface a neighbour may show along the edge:
/// a neighbour is at most one level apart, and fallback data may be coarser
/// still, so the depth covers twice the error of the coarser of those levels,
/// plus a metre for rounding.
pub fn skirt_depth(draw: &TileDraw, delta_per_level: &[f64]) -> f32 {
    let level = (draw.key.level as usize + 1).max(draw.source_level as usize);
    let delta = delta_per_level.get(level).or(delta_per_level.last()).copied().unwrap_or(0.0);
    (2.0 * delta + 1.0) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(x: u32, origin: [f32; 2]) -> TileUniforms {
        let key = TileKey::new(0, x, 0);
        TileUniforms { key, origin, spacing: [10.0, 10.0], morph: [0.0, 1.0], skirt_depth: 1.0, byte_offset: 0 }
    }

    #[test]
    fn tiles_are_drawn_nearest_first() {
        // Tiles of 4 cells (40 m): centres at 1020, -20 (the camera's tile), 220 and 5020 m east.
        let mut list = DrawList { tiles: vec![tile(0, [1000.0, -20.0]), tile(1, [-40.0, -20.0]), tile(2, [200.0, -20.0]), tile(3, [5000.0, -20.0])], ..DrawList::default() };
        list.sort_front_to_back(4);
        let order: Vec<u32> = list.tiles.iter().map(|t| t.key.x).collect();
        assert_eq!(order, [1, 2, 0, 3]);
    }
}
