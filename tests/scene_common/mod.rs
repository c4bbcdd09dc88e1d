//! The built-in terrain, built once into a cache under the target folder,
//! and cameras over it.
#![allow(dead_code)] // each test file uses part of this

use glam::DVec3;
use ridgeline::camera::Camera;
use ridgeline::lod::morph::{morph_factor, morphed_height};
use ridgeline::pyramid::{Pyramid, Silent};
use ridgeline::render::DrawList;
use ridgeline::scene::PreloadedTerrain;
use ridgeline::tiles::grid::{edge_posts, vertex_count};
use ridgeline::tiles::TileVertex;
use std::collections::HashMap;
use std::sync::OnceLock;

/// A cache under the target folder, shared by the test binaries (they run
/// one after another, and pyramids are written atomically) and removed with
/// `cargo clean`.
pub fn cache_dir() -> &'static std::path::Path {
    static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("scene-cache");
        std::fs::create_dir_all(&dir).expect("test cache");
        dir
    })
}

pub fn pyramid() -> Pyramid {
    ridgeline::dataset::open(None, cache_dir(), &Silent).expect("built-in terrain")
}

pub fn terrain() -> &'static PreloadedTerrain {
    static TERRAIN: OnceLock<PreloadedTerrain> = OnceLock::new();
    TERRAIN.get_or_init(|| PreloadedTerrain::load(&pyramid()).expect("all nodes read"))
}

pub fn camera(x: f64, y: f64, altitude: f64, heading: f64, pitch: f64) -> Camera {
    Camera {
        position: DVec3::new(x, y, altitude),
        heading_deg: heading,
        pitch_deg: pitch,
        roll_deg: 0.0,
        fov_x_deg: 60.0,
        viewport: [320, 180],
    }
}

/// Drawn height at every edge post and edge-segment midpoint of every tile,
/// keyed by level-0 post coordinates (doubled, so midpoints are integers).
pub fn edge_heights(
    list: &DrawList,
    staging: &[u8],
    altitude: f64,
    grid: u32,
) -> HashMap<(i64, i64), Vec<f64>> {
    let mut heights: HashMap<(i64, i64), Vec<f64>> = HashMap::new();
    let count = vertex_count(grid);
    for tile in &list.tiles {
        let start = tile.byte_offset as usize;
        let bytes = &staging[start..start + count * std::mem::size_of::<TileVertex>()];
        let vertices: Vec<TileVertex> = bytes
            .chunks_exact(std::mem::size_of::<TileVertex>())
            .map(bytemuck::pod_read_unaligned)
            .collect();
        let drawn = |i: u32, j: u32| {
            let v = vertices[(i + j * (grid + 1)) as usize];
            let posts = list.frame.expect("a built list has its frame").posts;
            let [x, y] = tile.post_position(&posts, i as f32, j as f32).map(f64::from);
            let distance = (x * x + y * y + (v.height as f64 - altitude).powi(2)).sqrt();
            morphed_height(
                v.height,
                v.target,
                morph_factor(distance, tile.morph[0] as f64, tile.morph[1] as f64),
            )
        };
        let stride = 1i64 << tile.key.level;
        let base =
            (tile.key.x as i64 * grid as i64 * stride, tile.key.y as i64 * grid as i64 * stride);
        let at =
            |i: u32, j: u32| (2 * (base.0 + i as i64 * stride), 2 * (base.1 + j as i64 * stride));
        let posts: Vec<(u32, u32)> = edge_posts(grid).collect();
        for edge in posts.chunks(grid as usize + 1) {
            for pair in edge.windows(2) {
                let ((i0, j0), (i1, j1)) = (pair[0], pair[1]);
                let (a, b) = (drawn(i0, j0), drawn(i1, j1));
                heights.entry(at(i0, j0)).or_default().push(a);
                let (p, q) = (at(i0, j0), at(i1, j1));
                heights.entry(((p.0 + q.0) / 2, (p.1 + q.1) / 2)).or_default().push((a + b) / 2.0);
            }
        }
    }
    heights
}

/// The largest disagreement, metres, between tiles sharing an edge point.
pub fn worst_edge_disagreement(list: &DrawList, staging: &[u8], altitude: f64, grid: u32) -> f64 {
    edge_heights(list, staging, altitude, grid)
        .values()
        .filter(|values| values.len() > 1)
        .map(|values| {
            let (lo, hi) =
                values.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
            hi - lo
        })
        .fold(0.0, f64::max)
}
