//! Cameras at the edges of what a pilot can do to the display: straight up
//! and down, inverted, below the terrain, at 100 km, with a near-zero field of
//! view, and with numbers that are not numbers. Every frame must either be
//! refused with a clear error or produce a valid draw list (tiles inside the
//! data, finite uniforms, nothing allocated past the buffer).

use ridgeline::camera::CameraError;
use ridgeline::pipeline::{FrameError, FramePipeline, PipelineError};
use ridgeline::render::{NullBackend, RenderError};
use ridgeline::scene::{SceneConfig, SceneError};
use testkit::scene::{fly, null_backend, pipeline, VIEWPORT};
use testkit::{camera, over_tile};

/// Runs one frame of the whole pipeline, clipmap included.
fn check_frame(
    (pipeline, backend): &mut (FramePipeline, NullBackend),
    cam: &ridgeline::camera::Camera,
) -> usize {
    let stats = fly(pipeline, backend, cam).unwrap_or_else(|e| panic!("{cam:?}: {e}"));
    let report = stats.scene;
    let list = pipeline.draw_list();
    let frame = list.uniforms.expect("frame uniforms");
    assert!(frame.view_projection.is_finite(), "{cam:?}: projection not finite");
    for tile in &list.tiles {
        let values = [
            tile.first_post[0],
            tile.first_post[1],
            tile.post_step,
            tile.morph[0],
            tile.morph[1],
            tile.skirt_depth,
        ];
        assert!(
            values.iter().all(|v| v.is_finite()),
            "{cam:?}: tile {:?} has {values:?}",
            tile.key
        );
    }
    assert!(report.allocator_used_bytes <= pipeline.scene().config().buffer_bytes as u64);
    report.tiles
}

#[test]
fn extreme_attitudes_and_positions_draw_or_refuse_cleanly() {
    let mut scene = display_pipeline();
    let centre = (35_000.0, 45_000.0);
    let cases = [
        (
            "looking straight down",
            camera(VIEWPORT, over_tile(centre.0, centre.1, 5_000.0), 0.0, -90.0),
        ),
        (
            "looking straight up",
            camera(VIEWPORT, over_tile(centre.0, centre.1, 5_000.0), 0.0, 90.0),
        ),
        ("inverted", {
            let mut c = camera(VIEWPORT, over_tile(centre.0, centre.1, 4_000.0), 30.0, -5.0);
            c.roll_deg = 180.0;
            c
        }),
        ("below the terrain", camera(VIEWPORT, over_tile(centre.0, centre.1, 500.0), 10.0, 5.0)),
        ("at 100 km", camera(VIEWPORT, over_tile(centre.0, centre.1, 100_000.0), 0.0, -60.0)),
        ("near-zero field of view", {
            let mut c = camera(VIEWPORT, over_tile(centre.0, centre.1, 3_500.0), 0.0, -5.0);
            c.fov_x_deg = 1e-3;
            c
        }),
        (
            "far outside the data",
            camera(VIEWPORT, over_tile(-500_000.0, 2_000_000.0, 3_000.0), 135.0, -3.0),
        ),
    ];
    for (name, cam) in cases {
        let tiles = check_frame(&mut scene, &cam);
        println!("{name}: {tiles} tiles");
    }
    // Looking down from 5 km over the middle of the data must see terrain.
    assert!(check_frame(&mut scene, &cases[0].1) > 0);
    // Looking straight up sees none of it.
    assert_eq!(check_frame(&mut scene, &cases[1].1), 0);
}

#[test]
fn numbers_that_are_not_numbers_are_refused() {
    let mut scene = display_pipeline();
    for (field, value) in [
        ("x", f64::NAN),
        ("altitude", f64::INFINITY),
        ("heading", f64::NEG_INFINITY),
        ("pitch", f64::NAN),
    ] {
        let mut cam = camera(VIEWPORT, over_tile(30_000.0, 30_000.0, 3_000.0), 0.0, 0.0);
        match field {
            "x" => cam.position.x = value,
            "altitude" => cam.position.z = value,
            "heading" => cam.heading_deg = value,
            _ => cam.pitch_deg = value,
        }
        match frame(&mut scene, &cam) {
            Err(SceneError::Camera(CameraError::NotFinite { field: named, .. })) => {
                assert_eq!(named, field)
            }
            other => panic!("{field} = {value}: expected a refusal, got {other:?}"),
        }
    }
    let mut cam = camera(VIEWPORT, over_tile(30_000.0, 30_000.0, 3_000.0), 0.0, 0.0);
    cam.fov_x_deg = 0.0;
    assert!(matches!(
        frame(&mut scene, &cam),
        Err(SceneError::Camera(CameraError::FieldOfView(_)))
    ));
    cam.fov_x_deg = 60.0;
    cam.viewport = [0, 100];
    assert!(matches!(
        frame(&mut scene, &cam),
        Err(SceneError::Camera(CameraError::EmptyViewport(0, 100)))
    ));
}

/// The pipeline over the built-in terrain and its null backend.
fn display_pipeline() -> (FramePipeline, NullBackend) {
    let pipeline = pipeline(SceneConfig::default());
    let backend = null_backend(&pipeline);
    (pipeline, backend)
}

/// A frame that must be refused by the scene (the camera), not elsewhere.
fn frame(
    (pipeline, backend): &mut (FramePipeline, NullBackend),
    cam: &ridgeline::camera::Camera,
) -> Result<(), SceneError> {
    match fly(pipeline, backend, cam) {
        Ok(_) => Ok(()),
        Err(FrameError::Pipeline(PipelineError::Scene(error))) => Err(error),
        Err(FrameError::Pipeline(other)) => panic!("{cam:?}: refused by paging: {other}"),
        Err(FrameError::Backend(error)) => panic!("{cam:?}: backend: {}", error as RenderError),
    }
}
