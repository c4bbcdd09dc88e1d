//! Earth-scale coordinates: over the procedural earth (2^24 samples a side,
//! 40 000 km), a view 10^7 m from the origin must be drawn as precisely as
//! one next to it. Tile corners are placed relative to the camera in f64 and
//! only then narrowed to f32 (the shader's uniforms), so the error of a
//! vertex position depends on its distance to the camera, not on where on
//! the earth the camera is.

use glam::DVec3;
use ridgeline::camera::Camera;
use ridgeline::clipmap::{Clipmap, ClipmapConfig, LoaderMode, ViewConfig};
use ridgeline::lod::LodConfig;
use ridgeline::node::NodeSource;
use ridgeline::procedural::{EarthParams, ProceduralEarth};
use ridgeline::scene::{ClipmapTerrain, Scene, SceneConfig, TerrainSummary};
use std::sync::Arc;

/// Largest error, metres, of the f32 tile corners against the exact f64
/// positions for the tiles within `radius` metres of the camera, and how many
/// tiles that was.
fn corner_error(earth: &Arc<ProceduralEarth>, at: (f64, f64), radius: f64) -> (f64, usize) {
    let layout = *earth.layout();
    let summary = TerrainSummary::from_procedural(earth);
    let ground = earth.exact_height(at.0, at.1).unwrap() as f64;
    let eye = DVec3::new(at.0, at.1, ground + 900.0);
    let config = ClipmapConfig {
        atlas_bytes: None,
        atlas_slots: 4096,
        budget: 4096,
        loader: LoaderMode::Inline,
    };
    let mut clipmap = Clipmap::new(earth.clone(), config).unwrap();
    let view = ViewConfig { node_count: 14, view_distance: 5.0, load_distance: 5.5 };
    clipmap.add_view(view, eye).unwrap();
    clipmap.update().unwrap();
    let terrain = ClipmapTerrain { clipmap: &clipmap, summary: &summary };
    let lod = LodConfig { tau_px: 4.0, ..LodConfig::default() };
    let mut scene = Scene::new(SceneConfig { lod, ..SceneConfig::default() }, &terrain).unwrap();
    let camera = Camera {
        position: eye,
        heading_deg: 30.0,
        pitch_deg: -10.0,
        roll_deg: 0.0,
        fov_x_deg: 60.0,
        viewport: [640, 360],
    };
    scene.frame(&camera, &terrain).unwrap();
    let grid = lod.grid_size as f64;
    let (mut worst, mut tiles) = (0.0f64, 0);
    for tile in &scene.draw_list().tiles {
        let post = (1u64 << tile.key.level) as f64;
        for (i, j) in [(0.0, 0.0), (grid, 0.0), (0.0, grid), (grid, grid)] {
            let exact_x = (tile.key.x as f64 * grid + i) * post * layout.spacing_m[0] - eye.x;
            let exact_y = (tile.key.y as f64 * grid + j) * post * layout.spacing_m[1] - eye.y;
            if exact_x.hypot(exact_y) > radius {
                continue;
            }
            // What the vertex shader computes, in f32.
            let posts = scene.draw_list().uniforms.expect("a drawn frame").posts;
            let [x, y] = tile.post_position(&posts, i as f32, j as f32);
            worst = worst.max((x as f64 - exact_x).abs()).max((y as f64 - exact_y).abs());
            tiles += 1;
        }
    }
    (worst, tiles)
}

#[test]
fn a_view_ten_thousand_km_out_is_as_precise_as_one_at_the_origin() {
    let earth = Arc::new(
        ProceduralEarth::new(EarthParams { border: 2, ..EarthParams::earth(64, 11) }).unwrap(),
    );
    let (near, near_corners) = corner_error(&earth, (20_000.0, 20_000.0), 20_000.0);
    let (far, far_corners) = corner_error(&earth, (1e7 + 20_000.0, 1e7 + 20_000.0), 20_000.0);
    println!("corner error within 20 km: {near:.2e} m at the origin ({near_corners} corners), {far:.2e} m at 10^7 m ({far_corners})");
    assert!(near_corners > 20 && far_corners > 20, "both views see tiles");
    assert!(near < 0.01 && far < 0.01, "vertex positions within a centimetre: {near} and {far} m");
    assert!(
        far <= 2.0 * near + 1e-3,
        "10^7 m out is no worse than at the origin: {far} vs {near} m"
    );
}
