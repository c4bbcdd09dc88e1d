//! Two displays on one thread, as the budget bench runs its pacer beside a
//! flight: each frame makes its own context current, an accuracy run makes
//! its targets in its own context, and dropping one display deletes its
//! objects in its own context, never in the other's (GL object names are
//! per context, so the other's objects share them).

use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::flight::default_flight;
use ridgeline::gl::{GlBackend, GlesVersion};
use ridgeline::scene::TerrainSummary;
use testkit::builtin_pyramid;
use testkit::gl::take_turn;

const SIZE: [u32; 2] = [256, 144];

fn open() -> DisplayParts {
    let pyramid = builtin_pyramid();
    let summary = TerrainSummary::from_pyramid(pyramid.info());
    let config = DisplayConfig {
        version: GlesVersion::Es3,
        fov_x_deg: 60.0,
        ..DisplayConfig::new(GlBackend::Egl, SIZE.into())
    };
    DisplayParts::open(&config, pyramid, summary).expect("EGL display")
}

#[test]
fn dropping_one_display_leaves_the_other_drawing_as_before() {
    let _turn = take_turn();
    let path = default_flight(&builtin_pyramid());
    let camera = path.sample(path.start_time()).camera(60.0, SIZE);
    let mut kept = open();
    kept.pipeline.settle(&camera, 10_000).expect("settle");
    kept.frame(&camera).expect("frame");
    let before = kept.context.read_pixels().expect("read back");
    let mut dropped = open();
    dropped.pipeline.settle(&camera, 10_000).expect("settle");
    dropped.frame(&camera).expect("frame");
    // The kept display's context is current when the other is dropped.
    kept.frame(&camera).expect("frame");
    drop(dropped);
    kept.frame(&camera).expect("frame after the other display was dropped");
    let after = kept.context.read_pixels().expect("read back");
    let differing = before.pixels().zip(after.pixels()).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} pixels changed after the other display was dropped");
}
