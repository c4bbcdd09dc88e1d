//! The null backend counts what a scripted flight would cost a GPU: uploads
//! happen only when tiles change, a still camera uploads nothing, every tile
//! is one draw call, and a buffer too small for the view coarsens the tiles
//! instead of failing or leaving holes.

mod scene_common;

use ridgeline::render::{NullBackend, RenderBackend};
use ridgeline::scene::{Scene, SceneConfig};
use scene_common::{camera, terrain};

fn run_frame(
    scene: &mut Scene,
    backend: &mut NullBackend,
    cam: &ridgeline::camera::Camera,
) -> ridgeline::scene::FrameReport {
    let report = scene.frame(cam, terrain()).unwrap();
    let (staging, ranges) = scene.uploads();
    backend.upload(staging, ranges).unwrap();
    backend.draw(scene.draw_list()).unwrap();
    report
}

#[test]
fn scripted_flight_counts_and_a_still_camera_uploads_nothing() {
    let config = SceneConfig { transfer_cap: None, ..SceneConfig::default() };
    let mut scene = Scene::new(config, terrain()).unwrap();
    let mut backend = NullBackend::new(config.buffer_bytes);
    let mut uploaded = 0;
    for k in 0..20 {
        let cam = camera(10_000.0 + 1_500.0 * k as f64, 20_000.0, 3_500.0, 60.0, -6.0);
        let report = run_frame(&mut scene, &mut backend, &cam);
        let counts = backend.take();
        assert_eq!(counts.draw_calls as usize, report.tiles, "one draw call per tile");
        assert_eq!(counts.bytes_uploaded, report.bytes_uploaded);
        assert!(counts.upload_calls as usize <= 1, "one transfer per frame without a cap");
        assert_eq!(counts.triangles, report.triangles);
        uploaded += counts.bytes_uploaded;
    }
    assert!(uploaded > 0, "moving uploads new tiles");
    let still = camera(40_000.0, 20_000.0, 3_500.0, 60.0, -6.0);
    run_frame(&mut scene, &mut backend, &still);
    backend.take();
    for _ in 0..5 {
        let report = run_frame(&mut scene, &mut backend, &still);
        let counts = backend.take();
        assert_eq!(
            (counts.bytes_uploaded, counts.upload_calls, report.generated),
            (0, 0, 0),
            "a still camera uploads nothing"
        );
        assert!(counts.draw_calls > 0);
    }
}

#[test]
fn the_default_transfer_cap_bounds_every_upload() {
    let config = SceneConfig::default();
    let cap = config.transfer_cap.expect("the default caps transfers");
    let mut scene = Scene::new(config, terrain()).unwrap();
    let mut pieces = 0;
    for k in 0..10 {
        let cam = camera(10_000.0 + 3_000.0 * k as f64, 25_000.0, 3_200.0, 70.0, -6.0);
        scene.frame(&cam, terrain()).unwrap();
        let (_, ranges) = scene.uploads();
        pieces += ranges.len();
        let tile = ridgeline::tiles::vertex::tile_bytes(config.lod.grid_size);
        assert!(
            ranges.iter().all(|r| r.end - r.start <= cap.max(tile)),
            "a transfer exceeds the cap: {ranges:?}"
        );
    }
    assert!(pieces > 10, "a moving camera's uploads are cut into several transfers");
}

#[test]
fn a_small_buffer_coarsens_instead_of_failing() {
    let roomy = SceneConfig::default();
    let tight = SceneConfig { buffer_bytes: 1 << 20, ..roomy };
    let cam = camera(30_000.0, 30_000.0, 2_600.0, 10.0, -10.0);
    let mut full = Scene::new(roomy, terrain()).unwrap();
    let wanted = full.frame(&cam, terrain()).unwrap();
    let mut scene = Scene::new(tight, terrain()).unwrap();
    let report = scene.frame(&cam, terrain()).unwrap();
    assert!(report.coarsened > 0, "1 MB cannot hold {} tiles", wanted.tiles);
    assert!(report.tiles > 0 && report.tiles < wanted.tiles);
    assert!(report.allocator_used_bytes <= 1 << 20);
}

/// The near plane follows the nearest tile drawn, not the highest peak of
/// the data: below the highest summit but high above the valley, a 0.5 m
/// near plane would leave a 24-bit depth buffer blind to hundreds of metres
/// at the horizon. Low over the ground it comes back in front of it.
#[test]
fn the_near_plane_follows_the_nearest_tile() {
    let terrain = terrain();
    let mut scene = Scene::new(SceneConfig::default(), terrain).expect("scene");
    let near = |scene: &Scene, cam: &ridgeline::camera::Camera| {
        let m = scene.frame_uniforms(cam, terrain).view_projection.to_cols_array();
        // Perspective: near = m[14] / (m[10] - 1) for glam's right-handed GL projection.
        let (c, d) = (m[10] as f64, m[14] as f64);
        d / (c - 1.0)
    };
    // The lowest ground on a 5 km lattice, away from the data's edges.
    let pyramid = scene_common::pyramid();
    let lattice =
        (2..14).flat_map(|i| (2..18).map(move |j| (i as f64 * 5000.0, j as f64 * 5000.0)));
    let height = |&(x, y): &(f64, f64)| pyramid.exact_height(x, y).expect("inside the data") as f64;
    let (x, y) = lattice.min_by(|a, b| height(a).total_cmp(&height(b))).expect("points");
    let ground = height(&(x, y));
    let summit = pyramid.info().stats.height_max as f64;
    let high = camera(x, y, ground + 1000.0, 0.0, -5.0);
    assert!(high.position.z < summit, "the view is below the highest summit ({summit} m)");
    scene.frame(&high, terrain).expect("frame");
    let high_near = near(&scene, &high);
    let low = camera(x, y, ground + 20.0, 0.0, -5.0);
    scene.frame(&low, terrain).expect("frame");
    let low_near = near(&scene, &low);
    println!(
        "near plane {high_near:.1} m at {:.0} m above the ground, {low_near:.2} m at 20 m",
        high.position.z - ground
    );
    assert!(high_near > 100.0, "near plane {high_near} m");
    assert!(
        (0.5..16.0).contains(&low_near),
        "near plane {low_near} m must stay in front of the ground 20 m below"
    );
}
