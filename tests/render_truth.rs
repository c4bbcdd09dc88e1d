//! The brute-force truth pass against the LOD display: where the display
//! draws only level-0 tiles the two images agree to the pixel but for
//! rounding; coarser tiles cover the same pixels with close colours.
use glam::{DVec3, UVec2};
use image::RgbaImage;
use ridgeline::camera::Camera;
use ridgeline::clipmap::LoaderMode;
use ridgeline::display::measure::draw_truth;
use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::gl::GlBackend;
use ridgeline::gl::{TruthMesh, TruthPass, TruthRegion};
use ridgeline::node::NodeSource;
use ridgeline::procedural::{EarthParams, ProceduralEarth};
use ridgeline::scene::TerrainSummary;
use std::sync::Arc;

const SENTINEL: [u8; 4] = [255, 0, 255, 255];

fn coverage(image: &RgbaImage) -> f64 {
    image.pixels().filter(|p| p.0 != SENTINEL).count() as f64 / image.pixels().len() as f64
}

fn mean_difference(a: &RgbaImage, b: &RgbaImage) -> f64 {
    let sum: u64 = a.as_raw().iter().zip(b.as_raw()).map(|(x, y)| x.abs_diff(*y) as u64).sum();
    sum as f64 / a.as_raw().len() as f64
}

fn small_earth() -> (Arc<ProceduralEarth>, TerrainSummary) {
    // 512 cells a side in nodes of the default tile grid.
    let params = EarthParams { node_size: 32, levels: 5, border: 1, spacing_m: 30.0, seed: 7 };
    let earth = Arc::new(ProceduralEarth::new(params).expect("small earth"));
    let summary = TerrainSummary::from_procedural(&earth);
    (earth, summary)
}

/// Draws `camera` with the LOD display at `tau_px`, then the truth;
/// returns both images and the levels of the tiles drawn.
fn lod_and_truth(tau_px: f64, camera: &Camera) -> (RgbaImage, RgbaImage, Vec<u8>) {
    let (earth, summary) = small_earth();
    let mut config = DisplayConfig::new(GlBackend::Egl, UVec2::from(camera.viewport));
    config.loader = LoaderMode::Inline;
    config.load_budget = 4096;
    config.sentinel = Some(SENTINEL.map(|c| c as f32 / 255.0));
    config.scene.lod.tau_px = tau_px;
    let source: Arc<dyn NodeSource> = earth.clone();
    let mut display = DisplayParts::open(&config, source, summary).expect("display");
    display.pipeline.settle(camera, 100).expect("settles");
    display.frame(camera).expect("LOD frame");
    let levels = display.pipeline.draw_list().tiles.iter().map(|t| t.key.level).collect();
    let lod = display.context.read_pixels().expect("read LOD");
    let mesh = TruthMesh::load(earth.as_ref(), TruthRegion::whole(earth.layout())).expect("mesh");
    let truth = TruthPass::new(display.context.gl(), &mesh).expect("truth pass");
    let stats = draw_truth(&mut display, &truth).expect("truth frame");
    assert_eq!((stats.triangles, stats.draw_calls), (2 * 512 * 512, 16));
    (lod, display.context.read_pixels().expect("read truth"), levels)
}

fn camera_over(earth: &ProceduralEarth) -> Camera {
    let posts = (0..64).flat_map(|j| (0..64).map(move |i| (i * 8, j * 8)));
    let highest = posts.map(|(i, j)| earth.sample(i, j)).fold(f32::MIN, f32::max);
    let position = DVec3::new(2000.0, 1500.0, highest as f64 + 300.0);
    Camera { roll_deg: 5.0, ..testkit::camera([192, 108], position, 40.0, -20.0) }
}

/// Where the LOD display draws only level-0 tiles it is the truth, to
/// the pixel but for rounding at triangle edges: same transform, same
/// colours. Coarser tiles cover the same pixels with close colours.
#[test]
fn truth_and_lod_images_agree() {
    let camera = camera_over(&small_earth().0);
    let (lod, truth, levels) = lod_and_truth(1.0, &camera);
    assert!(levels.iter().all(|&l| l == 0), "a rough earth keeps level 0 at tau 1 px");
    let differing = lod.pixels().zip(truth.pixels()).filter(|(a, b)| a != b).count();
    println!(
        "level 0 only: {} tiles, {differing} pixels differ, coverage {:.3}",
        levels.len(),
        coverage(&truth)
    );
    assert!(coverage(&truth) > 0.6, "the truth covers the picture below the horizon");
    assert!(differing * 200 < lod.pixels().len(), "{differing} pixels differ");
    let (coarse, truth, levels) = lod_and_truth(16.0, &camera);
    let difference = mean_difference(&coarse, &truth);
    let (lod_cover, truth_cover) = (coverage(&coarse), coverage(&truth));
    let coarsest = levels.iter().max();
    println!("tau 16: coarsest {coarsest:?}, coverage {lod_cover:.3} / {truth_cover:.3}, difference {difference:.2}");
    assert!(levels.iter().any(|&l| l > 0), "tau 16 px draws coarser tiles");
    assert!((lod_cover - truth_cover).abs() < 0.02, "both cover the same pixels");
    assert!(difference < 6.0, "colours agree");
}
