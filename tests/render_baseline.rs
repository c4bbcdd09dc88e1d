//! Plain Chunked LOD, the baseline of `benches/lod.rs`: drawn from a vertex
//! buffer per tile it gives the display's picture pixel for pixel, uploads a
//! tile once (not again while it stays), and the display's own renderer,
//! whose uploads the baseline frames skipped, draws correctly afterwards.

mod render_common;

use render_common::{config, open, render, VIEWS};
use ridgeline::gl::{ChunkedBaseline, GlBackend, GlesVersion};

#[test]
fn baseline_draws_the_display_picture_and_uploads_each_tile_once() {
    let config = config(GlBackend::Egl, GlesVersion::Es3);
    let mut display = open(&config).expect("headless EGL display");
    let [first, second, _] = VIEWS.map(|v| v.camera());
    let (batched, _) = render(&mut display, &first);
    let mut baseline =
        ChunkedBaseline::new(display.context().gl(), config.scene.lod.grid_size).expect("baseline");
    let (stats, base) = display.frame_baseline(&first, &mut baseline).expect("baseline frame");
    assert_eq!(base.uploads, stats.draw_calls, "every tile is uploaded by itself on first sight");
    assert_eq!(base.buffers, stats.draw_calls);
    assert!(display.read_pixels().expect("read") == batched, "the baseline draws the same picture");
    let (_, again) = display.frame_baseline(&first, &mut baseline).expect("baseline frame");
    assert_eq!(again.uploads, 0, "a still camera uploads nothing");
    // Elsewhere, then back to the batched renderer, which must not draw stale heights.
    display.settle(&second, 1000).expect("settle");
    let (_, moved) = display.frame_baseline(&second, &mut baseline).expect("baseline frame");
    assert!(moved.uploads > 0 && moved.buffers <= moved.uploads + again.buffers);
    let baseline_second = display.read_pixels().expect("read");
    let (batched_second, _) = render(&mut display, &second);
    assert!(
        batched_second == baseline_second,
        "the batched renderer catches up on the skipped uploads"
    );
}

/// While nodes page in a few per frame, tiles are regenerated from better
/// data, often at their old offsets: the baseline must rewrite those
/// buffers, frame for frame drawing what the batched display draws.
#[test]
fn baseline_rewrites_tiles_regenerated_in_place() {
    let mut config = config(GlBackend::Egl, GlesVersion::Es3);
    config.load_budget = 2;
    let mut batched = open(&config).expect("headless EGL display");
    let mut chunked = open(&config).expect("second headless EGL display");
    let mut baseline =
        ChunkedBaseline::new(chunked.context().gl(), config.scene.lod.grid_size).expect("baseline");
    let start = VIEWS[0].camera();
    let mut paging_frames = 0;
    for k in 0..16 {
        let mut camera = start;
        camera.position.x += 150.0 * k as f64;
        batched.context_mut().make_current().expect("current");
        let stats = batched.frame(&camera).expect("batched frame");
        let expected = batched.read_pixels().expect("read");
        chunked.context_mut().make_current().expect("current");
        let (_, base) = chunked.frame_baseline(&camera, &mut baseline).expect("baseline frame");
        paging_frames += usize::from(stats.nodes_loaded > 0 && base.uploads > 0);
        assert!(
            chunked.read_pixels().expect("read") == expected,
            "frame {k}: the baseline draws stale heights"
        );
    }
    assert!(
        paging_frames >= 8,
        "nodes paged in and tiles were rewritten in {paging_frames} of 16 frames"
    );
}
