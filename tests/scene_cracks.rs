//! No cracks, checked on the CPU: along a low flight with many LOD changes,
//! wherever two selected tiles share an edge, the heights the shader will draw
//! there (vertex data plus the per-vertex morph of src/lod/morph.rs) agree.

mod scene_common;

use ridgeline::lod::morph::{morph_factor, morphed_height};
use ridgeline::render::DrawList;
use ridgeline::scene::{Scene, SceneConfig};
use ridgeline::tiles::grid::{edge_posts, vertex_count};
use ridgeline::tiles::TileVertex;
use scene_common::{camera, terrain};
use std::collections::HashMap;

/// Drawn height at every edge post and edge-segment midpoint of every tile,
/// keyed by level-0 post coordinates (doubled, so midpoints are integers).
fn edge_heights(list: &DrawList, staging: &[u8], altitude: f64, grid: u32) -> HashMap<(i64, i64), Vec<f64>> {
    let mut heights: HashMap<(i64, i64), Vec<f64>> = HashMap::new();
    let count = vertex_count(grid);
    for tile in &list.tiles {
        let start = tile.byte_offset as usize;
        let bytes = &staging[start..start + count * std::mem::size_of::<TileVertex>()];
        let vertices: Vec<TileVertex> = bytes.chunks_exact(std::mem::size_of::<TileVertex>()).map(bytemuck::pod_read_unaligned).collect();
        let drawn = |i: u32, j: u32| {
            let v = vertices[(i + j * (grid + 1)) as usize];
            let x = tile.origin[0] as f64 + i as f64 * tile.spacing[0] as f64;
            let y = tile.origin[1] as f64 + j as f64 * tile.spacing[1] as f64;
            let distance = (x * x + y * y + (v.height as f64 - altitude).powi(2)).sqrt();
            morphed_height(v.height, v.target, morph_factor(distance, tile.morph[0] as f64, tile.morph[1] as f64))
        };
        let stride = 1i64 << tile.key.level;
        let base = (tile.key.x as i64 * grid as i64 * stride, tile.key.y as i64 * grid as i64 * stride);
        let at = |i: u32, j: u32| (2 * (base.0 + i as i64 * stride), 2 * (base.1 + j as i64 * stride));
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

#[test]
fn shared_edges_agree_along_a_low_flight() {
    let terrain = terrain();
    let config = SceneConfig::default();
    let mut scene = Scene::new(config, terrain).unwrap();
    let grid = config.lod.grid_size;
    let mut levels_seen = std::collections::BTreeSet::new();
    let mut shared_points = 0;
    for k in 0..30 {
        let t = k as f64 / 29.0;
        let cam = camera(8_000.0 + 50_000.0 * t, 10_000.0 + 60_000.0 * t, 3_600.0 - 1_000.0 * t, 40.0, -8.0);
        scene.frame(&cam, terrain).unwrap();
        let list = scene.draw_list();
        levels_seen.extend(list.tiles.iter().map(|t| t.key.level));
        let (staging, _) = scene.uploads();
        for ((x, y), values) in edge_heights(list, staging, cam.position.z, grid) {
            if values.len() < 2 {
                continue;
            }
            shared_points += 1;
            let (lo, hi) = values.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
            assert!(hi - lo < 0.01, "frame {k}: tiles disagree by {} m at post ({}, {})", hi - lo, x as f64 / 2.0, y as f64 / 2.0);
        }
    }
    assert!(levels_seen.len() >= 3, "the flight crosses several levels: {levels_seen:?}");
    assert!(shared_points > 1000, "enough shared edge points were compared: {shared_points}");
}
