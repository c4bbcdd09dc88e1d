//! Plain Chunked LOD, the baseline of `benches/lod.rs`: a render backend of
//! its own, fed by a pipeline of its own in the display's context. Drawn
//! from a vertex buffer per tile it gives the display's picture pixel for
//! pixel and uploads a tile once (not again while it stays).

use ridgeline::camera::Camera;
use ridgeline::display::DisplayParts;
use ridgeline::gl::{ChunkedBaseline, GlBackend, GlesVersion};
use ridgeline::pipeline::{FramePipeline, FrameStats};
use testkit::render::{config, open, render, VIEWS};

/// A second pipeline over the built-in terrain (its node meshes, as the
/// display's), for the baseline backend.
fn baseline_pipeline(config: &ridgeline::display::DisplayConfig) -> FramePipeline {
    let terrain = testkit::builtin_terrain();
    let summary = testkit::summary_of(&terrain);
    FramePipeline::new(&config.pipeline(), terrain, summary).expect("baseline pipeline")
}

/// Draws `camera` through `pipeline` on `baseline` into `display`'s target.
fn baseline_frame(
    display: &DisplayParts,
    pipeline: &mut FramePipeline,
    baseline: &mut ChunkedBaseline,
    camera: &Camera,
) -> FrameStats {
    display.context.make_current().expect("current");
    display.context.bind_target();
    pipeline.settle(camera, 1000).expect("settle");
    pipeline.frame(camera, baseline).expect("baseline frame")
}

#[test]
fn baseline_draws_the_display_picture_and_uploads_each_tile_once() {
    let config = config(GlBackend::Egl, GlesVersion::Es3);
    let mut display = open(&config).expect("headless EGL display");
    let mut pipeline = baseline_pipeline(&config);
    let [first, second, _] = VIEWS.map(|v| v.camera());
    let (batched, batched_stats) = render(&mut display, &first);
    let mut baseline =
        ChunkedBaseline::new(display.context.gl(), config.scene.lod.grid_size).expect("baseline");
    let stats = baseline_frame(&display, &mut pipeline, &mut baseline, &first);
    let base = baseline.last_frame();
    let tiles = stats.scene.tiles;
    assert_eq!(base.uploads, tiles, "every tile is uploaded by itself on first sight");
    assert_eq!(base.buffers, tiles);
    assert_eq!(stats.calls.upload_calls as usize, tiles, "and counted as one upload each");
    assert_eq!(stats.calls.draw_calls, batched_stats.calls.draw_calls, "the same draws");
    let picture = display.context.read_pixels().expect("read");
    assert!(picture == batched, "the baseline draws the same picture");
    baseline_frame(&display, &mut pipeline, &mut baseline, &first);
    assert_eq!(baseline.last_frame().uploads, 0, "a still camera uploads nothing");
    let again = baseline.last_frame();
    baseline_frame(&display, &mut pipeline, &mut baseline, &second);
    let moved = baseline.last_frame();
    assert!(moved.uploads > 0 && moved.buffers <= moved.uploads + again.buffers);
    let baseline_second = display.context.read_pixels().expect("read");
    let (batched_second, _) = render(&mut display, &second);
    assert!(batched_second == baseline_second, "both draw the second view alike");
}

/// While nodes page in a few per frame, tiles are regenerated from better
/// data, often at their old offsets: the baseline must rewrite those
/// buffers, frame for frame drawing what the batched display draws.
#[test]
fn baseline_rewrites_tiles_regenerated_in_place() {
    let mut config = config(GlBackend::Egl, GlesVersion::Es3);
    config.load_budget = 2;
    let mut batched = open(&config).expect("headless EGL display");
    let mut pipeline = baseline_pipeline(&config);
    let mut baseline =
        ChunkedBaseline::new(batched.context.gl(), config.scene.lod.grid_size).expect("baseline");
    let start = VIEWS[0].camera();
    let mut paging_frames = 0;
    for k in 0..16 {
        let mut camera = start;
        camera.position.x += 150.0 * k as f64;
        let stats = batched.frame(&camera).expect("batched frame");
        let expected = batched.context.read_pixels().expect("read");
        batched.context.bind_target();
        pipeline.frame(&camera, &mut baseline).expect("baseline frame");
        let base = baseline.last_frame();
        paging_frames += usize::from(stats.nodes_loaded > 0 && base.uploads > 0);
        assert!(
            batched.context.read_pixels().expect("read") == expected,
            "frame {k}: the baseline draws stale heights"
        );
    }
    assert!(
        paging_frames >= 8,
        "nodes paged in and tiles were rewritten in {paging_frames} of 16 frames"
    );
}
