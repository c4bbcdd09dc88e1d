//! `examples/embed.rs`, the integrator's entry point, run headless: its own
//! EGL context and framebuffer, frames drawn by Ridgeline into it, the GL
//! state Ridgeline documents leaving behind checked after every frame, and a
//! picture with terrain in it.

#[path = "../examples/embed.rs"]
#[allow(dead_code)] // its `main` is the example's, not the test's
mod embed;

#[test]
fn the_embedding_example_draws_into_the_applications_framebuffer() {
    let scratch = testkit::target_tmp();
    let picture = embed::run(&scratch.join("embed"), &scratch.join("render-terrain"), 4)
        .unwrap_or_else(|e| panic!("the example failed: {e}"));
    let image = image::open(&picture).expect("the example's picture").to_rgba8();
    let lower = image.rows().skip(image.height() as usize * 2 / 3).flatten();
    let sky = ridgeline::render::palette::SKY_HORIZON.map(|c| (c * 255.0).round() as u8);
    let terrain = lower.filter(|p| p.0[..3] != sky).count();
    assert!(terrain > 1000, "the lower third shows terrain ({terrain} pixels)");
}
