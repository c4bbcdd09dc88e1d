//! `examples/embed.rs`, the integrator's entry point, run headless as
//! `embed` and as `embed --clusters`: its own EGL context and framebuffer,
//! frames drawn by Ridgeline into it, the GL state Ridgeline documents
//! leaving behind checked after every frame, and a picture with terrain in
//! it. With clusters every frame draws cluster batches, in fewer draw
//! calls than it has tiles.

#[path = "../examples/embed.rs"]
#[allow(dead_code)] // its `main` is the example's, not the test's
mod embed;

use testkit::gl::take_turn;

const FRAMES: u32 = 4;

/// Runs the example with the arguments `args`, checks its picture shows
/// terrain, and returns its frames' stats.
fn run_example(name: &str, args: &[&str]) -> Vec<ridgeline::pipeline::FrameStats> {
    let _turn = take_turn();
    let clusters = embed::clusters_flag(args.iter().map(|a| a.to_string())).expect("arguments");
    let scratch = testkit::target_tmp();
    let flight = embed::run(&scratch.join(name), &scratch.join("render-terrain"), FRAMES, clusters)
        .unwrap_or_else(|e| panic!("the example {args:?} failed: {e}"));
    let image = image::open(&flight.picture).expect("the example's picture").to_rgba8();
    let lower = image.rows().skip(image.height() as usize * 2 / 3).flatten();
    let sky = ridgeline::render::palette::SKY_HORIZON.map(|c| (c * 255.0).round() as u8);
    let terrain = lower.filter(|p| p.0[..3] != sky).count();
    assert!(terrain > 1000, "{args:?}: the lower third shows terrain ({terrain} pixels)");
    assert_eq!(flight.frames.len(), FRAMES as usize);
    flight.frames
}

#[test]
fn the_embedding_example_draws_into_the_applications_framebuffer() {
    for stats in run_example("embed", &[]) {
        assert_eq!(stats.scene.clusters, 0, "tiles are drawn one by one");
        // The sky is one draw; every tile one more per depth slice it reaches.
        assert!(stats.calls.draw_calls > stats.scene.tiles as u64, "{stats:?}");
    }
}

#[test]
fn the_embedding_example_draws_cluster_batches_with_clusters() {
    for stats in run_example("embed-clusters", &["--clusters"]) {
        let (tiles, clusters) = (stats.scene.tiles, stats.scene.clusters);
        assert!(clusters > 0, "every frame draws clusters ({tiles} tiles)");
        assert!(
            stats.calls.draw_calls - 1 < tiles as u64,
            "{clusters} clusters of {tiles} tiles take fewer draws: {}",
            stats.calls.draw_calls
        );
    }
}

#[test]
fn the_embedding_example_takes_only_the_clusters_flag() {
    let flag = |args: &[&str]| embed::clusters_flag(args.iter().map(|a| a.to_string())).ok();
    assert_eq!(flag(&[]), Some(false));
    assert_eq!(flag(&["--clusters"]), Some(true));
    assert_eq!(flag(&["--cluster"]), None);
    assert_eq!(flag(&["--clusters", "extra"]), None);
}
