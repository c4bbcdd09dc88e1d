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
    }
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
