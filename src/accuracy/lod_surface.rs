//! [`LodSurface`]: the surface the LOD display drew, evaluated on the CPU at
//! any ground point, from the frame's draw list and the tile vertices in the
//! allocator's staging copy (byte for byte what the GPU holds). Each vertex
//! is morphed as `shaders/gles/terrain.vert` does ([`crate::lod::morph`]),
//! from the same f32 uniforms, and the cell is split south-west to
//! north-east as the shared grid's indices are ([`cell_surface`]).
//! Skirts are not part of the surface.

use std::collections::HashMap;

use glam::DVec2;

use crate::lod::morph::{morph_factor, morphed_height};
use crate::lod::TileKey;
use crate::node::cell_surface;
use crate::render::{DrawList, TileUniforms};
use crate::tiles::TileVertex;

/// The drawn tiles of one frame, indexed by key.
#[derive(Debug, Default)]
pub struct LodSurface {
    tiles: HashMap<TileKey, TileUniforms>,
    levels: u8,
    grid_size: u32,
    /// Level-0 post spacing, metres east and north.
    spacing_m: [f64; 2],
    eye: DVec2,
    altitude: f64,
}

impl LodSurface {
    /// Indexes `list`'s tiles (drawn from `eye` with tiles of `grid_size`
    /// cells over level-0 posts `spacing_m` apart).
    pub fn new(list: &DrawList, grid_size: u32, spacing_m: [f64; 2], eye: DVec2) -> LodSurface {
        let tiles: HashMap<TileKey, TileUniforms> = list.tiles.iter().map(|t| (t.key, *t)).collect();
        let levels = list.tiles.iter().map(|t| t.key.level + 1).max().unwrap_or(0);
        let altitude = list.frame.map_or(0.0, |f| f.camera_altitude);
        LodSurface { tiles, levels, grid_size, spacing_m, eye, altitude }
    }

    /// Height of the drawn surface at the local point `(x_m, y_m)`, metres
    /// above the datum (before the curvature drop); `None` where no tile was
    /// drawn.
    pub fn height_at(&self, staging: &[u8], x_m: f64, y_m: f64) -> Option<f64> {
        let g = self.grid_size as f64;
        (0..self.levels).find_map(|level| {
            let post = [self.spacing_m[0] * (1u64 << level) as f64, self.spacing_m[1] * (1u64 << level) as f64];
            let (u, v) = (x_m / post[0], y_m / post[1]);
            if u < 0.0 || v < 0.0 {
                return None;
            }
            let key = TileKey::new(level, (u / g).floor() as u32, (v / g).floor() as u32);
            let tile = self.tiles.get(&key)?;
            let local = [u - key.x as f64 * g, v - key.y as f64 * g];
            Some(self.tile_surface(staging, tile, local))
        })
    }

    /// The tile's morphed surface at `local` posts from its south-west corner.
    fn tile_surface(&self, staging: &[u8], tile: &TileUniforms, local: [f64; 2]) -> f64 {
        let last = self.grid_size - 1;
        let (i, j) = ((local[0].floor() as u32).min(last), (local[1].floor() as u32).min(last));
        let (fu, fv) = (local[0] - i as f64, local[1] - j as f64);
        let h = |i: u32, j: u32| self.vertex_height(staging, tile, i, j);
        cell_surface(h(i, j), h(i + 1, j), h(i, j + 1), h(i + 1, j + 1), fu, fv)
    }

    /// Post `(i, j)`'s drawn height: the shader's morph, with its f32 inputs.
    fn vertex_height(&self, staging: &[u8], tile: &TileUniforms, i: u32, j: u32) -> f64 {
        let index = (i + j * (self.grid_size + 1)) as usize;
        let at = tile.byte_offset as usize + index * std::mem::size_of::<TileVertex>();
        let vertex: TileVertex = bytemuck::pod_read_unaligned(&staging[at..at + std::mem::size_of::<TileVertex>()]);
        let x = (tile.origin[0] + i as f32 * tile.spacing[0]) as f64;
        let y = (tile.origin[1] + j as f32 * tile.spacing[1]) as f64;
        let distance = (x * x + y * y + (vertex.height as f64 - self.altitude).powi(2)).sqrt();
        let factor = morph_factor(distance, tile.morph[0] as f64, tile.morph[1] as f64);
        morphed_height(vertex.height, vertex.target, factor)
    }

    /// The camera's ground position the tiles were placed relative to.
    pub fn eye(&self) -> DVec2 {
        self.eye
    }
}
