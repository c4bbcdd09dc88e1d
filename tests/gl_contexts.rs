//! Opens a context on every backend and proves each draws: clear, one
//! triangle from the GLSL ES 1.00 smoke shaders, read back, check pixels.
//!
//! EGL (ES 3 and ES 2) is mandatory. OSMesa skips loudly where libOSMesa is
//! missing unless RIDGELINE_REQUIRE_OSMESA=1. The window test starts Xvfb when
//! DISPLAY is unset and skips loudly without it unless
//! RIDGELINE_REQUIRE_WINDOW=1. Window and auto run in child processes: winit
//! gives a process one event loop, and auto must be seen without a display.

use std::time::Instant;

use clap::ValueEnum;
use glam::{UVec2, Vec4};
use image::{Rgba, RgbaImage};
use ridgeline::gl::{ContextRequest, GlBackend, GlContext, GlesVersion, OpenedBackend, SmokePass};
use testkit::gl::{child_test, run_child, skip_for_missing_osmesa, take_turn, window_display};

const SIZE: UVec2 = UVec2::new(96, 64);
const CLEAR: [u8; 4] = [0, 64, 128, 255];
const TRIANGLE: [u8; 4] = [255, 128, 0, 255];
/// The smoke triangle covers 0.9 * 0.9 / 2 of the target.
const TRIANGLE_SHARE: f64 = 0.405;

fn as_vec4(rgba: [u8; 4]) -> Vec4 {
    Vec4::from_array(rgba.map(|c| c as f32 / 255.0))
}

fn close(pixel: &Rgba<u8>, expected: [u8; 4]) -> bool {
    pixel.0.iter().zip(expected).all(|(&a, b)| a.abs_diff(b) <= 1)
}

/// Draws the smoke pass, reads it back and checks it; a failing read-back is
/// saved as a PNG beside the test's temporary files. Prints what the context
/// is and how long it took since `started`.
fn draw_check_and_report(context: &GlContext, started: Instant) {
    let pass = SmokePass::new(context.gl()).expect("smoke pass builds");
    context.bind_target();
    pass.draw(context.size(), as_vec4(CLEAR), as_vec4(TRIANGLE)).expect("smoke pass draws");
    let image = context.read_pixels().expect("read back");
    context.present().expect("present");
    if let Err(problem) = check_smoke_image(&image) {
        let info = context.info();
        let path = testkit::target_tmp().join(format!(
            "smoke-{}-{:?}.png",
            info.backend.name(),
            info.requested
        ));
        let saved =
            image.save(&path).map_or_else(|e| format!("not saved: {e}"), |()| "saved".to_owned());
        panic!("{problem}; read-back at {} ({saved})", path.display());
    }
    report(context, started);
}

fn check_smoke_image(image: &RgbaImage) -> Result<(), String> {
    let (w, h) = image.dimensions();
    // Row 0 is the top: the right angle is at the bottom left.
    let bottom_left = image.get_pixel(w / 10, h * 9 / 10);
    let top_right = image.get_pixel(w * 9 / 10, h / 10);
    if !close(bottom_left, TRIANGLE) {
        return Err(format!("bottom left {bottom_left:?} is not the triangle"));
    }
    if !close(top_right, CLEAR) {
        return Err(format!("top right {top_right:?} is not the clear colour"));
    }
    let total = (w * h) as usize;
    let triangle = image.pixels().filter(|p| close(p, TRIANGLE)).count();
    let clear = image.pixels().filter(|p| close(p, CLEAR)).count();
    if triangle + clear != total {
        return Err(format!("{} stray pixels in the read-back", total - triangle - clear));
    }
    let share = triangle as f64 / total as f64;
    if (share - TRIANGLE_SHARE).abs() > 0.02 {
        return Err(format!("triangle covers {share:.3}, expected {TRIANGLE_SHARE}"));
    }
    Ok(())
}

#[test]
fn the_image_check_rejects_wrong_pictures() {
    let blank = RgbaImage::from_pixel(SIZE.x, SIZE.y, Rgba(CLEAR));
    let problem = check_smoke_image(&blank).expect_err("a blank picture passed");
    assert!(problem.contains("bottom left"), "{problem}");
    let mut flipped = RgbaImage::from_pixel(SIZE.x, SIZE.y, Rgba(CLEAR));
    for (x, y, pixel) in flipped.enumerate_pixels_mut() {
        // The triangle mirrored top to bottom: right angle at the top left.
        if (x as f64 + 0.5) / SIZE.x as f64 + (y as f64 + 0.5) / SIZE.y as f64 <= 0.95 {
            *pixel = Rgba(TRIANGLE);
        }
    }
    assert!(check_smoke_image(&flipped).is_err(), "an upside-down picture passed");
}

fn report(context: &GlContext, started: Instant) {
    let info = context.info();
    println!(
        "{}: GL_VERSION {:?}, GL_RENDERER {:?}, GLSL {:?}, platform {:?}, level {:?}, caps {:?} ({:.0} ms)",
        info.backend.name(),
        info.version,
        info.renderer,
        info.shading_language_version,
        info.platform,
        info.caps.level,
        info.caps,
        started.elapsed().as_secs_f64() * 1e3
    );
}

#[test]
fn egl_es3_draws_and_reads_back() {
    let _turn = take_turn();
    let started = Instant::now();
    let context = GlContext::new(&ContextRequest::new(GlBackend::Egl, GlesVersion::Es3, SIZE))
        .expect("headless EGL context (Mesa's llvmpipe needs libegl-mesa0)");
    let info = context.info();
    assert_eq!(info.backend, OpenedBackend::Egl);
    assert!(info.is_es() && info.version.starts_with("OpenGL ES 3"), "{}", info.version);
    let caps = context.caps();
    assert_eq!(caps.level, GlesVersion::Es3);
    assert!(
        caps.glsl_es_300 && caps.vertex_array_objects && caps.instancing && caps.uint32_indices
    );
    assert_eq!(context.size(), SIZE);
    draw_check_and_report(&context, started);
}

#[test]
fn egl_es2_keeps_to_the_es2_level() {
    let _turn = take_turn();
    let started = Instant::now();
    let context = GlContext::new(&ContextRequest::new(GlBackend::Egl, GlesVersion::Es2, SIZE))
        .expect("headless EGL ES 2 context");
    let info = context.info();
    assert!(info.is_es() && info.version.starts_with("OpenGL ES"), "{}", info.version);
    let caps = context.caps();
    assert_eq!(caps.level, GlesVersion::Es2);
    assert!(caps.glsl_es_100 && !caps.glsl_es_300 && !caps.instancing && !caps.base_vertex);
    draw_check_and_report(&context, started);
}

#[test]
fn osmesa_runs_the_es_shaders_on_desktop_gl() {
    let _turn = take_turn();
    let started = Instant::now();
    let request = ContextRequest::new(GlBackend::OsMesa, GlesVersion::Es2, SIZE);
    let context = match GlContext::new(&request) {
        Err(error)
            if skip_for_missing_osmesa("osmesa_runs_the_es_shaders_on_desktop_gl", &error) =>
        {
            return
        }
        other => other.expect("OSMesa context"),
    };
    let info = context.info();
    assert_eq!(info.backend, OpenedBackend::OsMesa);
    assert!(!info.is_es(), "OSMesa gives desktop GL, got {}", info.version);
    assert!(context.caps().glsl_es_100);
    draw_check_and_report(&context, started);
}

/// One run of [`child_context`] in a new process of this test binary.
struct ChildRun<'a> {
    backend: &'a str,
    version: &'a str,
    /// The backend it must open.
    expect: &'a str,
    /// What GL_VERSION must start with.
    expect_version: &'a str,
    /// DISPLAY for the child; None removes it.
    display: Option<&'a str>,
    /// Extra environment, e.g. Mesa overrides.
    env: &'a [(&'a str, &'a str)],
}

impl ChildRun<'_> {
    fn run(&self) {
        let mut command = child_test("child_context");
        command
            .env("RIDGELINE_CHILD_BACKEND", self.backend)
            .env("RIDGELINE_CHILD_VERSION", self.version)
            .env("RIDGELINE_CHILD_EXPECT", self.expect)
            .env("RIDGELINE_CHILD_EXPECT_VERSION", self.expect_version)
            .envs(self.env.iter().copied());
        match self.display {
            Some(display) => command.env("DISPLAY", display),
            None => command.env_remove("DISPLAY"),
        };
        run_child(&mut command, &format!("{} {}", self.backend, self.version));
    }
}

#[test]
fn window_under_xvfb_draws_and_reads_back() {
    let _turn = take_turn();
    let started = Instant::now();
    // A display of our own (a developer's) is used only when it answers.
    let Some(window_display) = window_display("window_under_xvfb_draws_and_reads_back") else {
        return;
    };
    let display = Some(window_display.display.as_str());
    let window = ChildRun {
        backend: "window",
        version: "es3",
        expect: "window",
        expect_version: "OpenGL ES 3",
        display,
        env: &[],
    };
    window.run();
    ChildRun { backend: "auto", ..window }.run();
    println!("window and auto under {display:?}: {:.0} ms", started.elapsed().as_secs_f64() * 1e3);
}

#[test]
fn auto_without_a_display_opens_egl() {
    let _turn = take_turn();
    let child = ChildRun {
        backend: "auto",
        version: "es3",
        expect: "egl",
        expect_version: "OpenGL ES 3",
        display: None,
        env: &[],
    };
    child.run();
}

/// Mesa hands out ES 3.2 when 2.0 is asked for; its override gives a true
/// ES 2.0 context, where only ES 2.0 entry points and extensions exist.
#[test]
fn egl_true_es2_context_draws() {
    let _turn = take_turn();
    let child = ChildRun {
        backend: "egl",
        version: "es2",
        expect: "egl",
        expect_version: "OpenGL ES 2.0",
        display: None,
        env: &[("MESA_GLES_VERSION_OVERRIDE", "2.0")],
    };
    child.run();
}

/// The body of the child processes: opens RIDGELINE_CHILD_BACKEND at
/// RIDGELINE_CHILD_VERSION, checks it resolved to RIDGELINE_CHILD_EXPECT with
/// a GL_VERSION starting RIDGELINE_CHILD_EXPECT_VERSION, draws and checks the
/// smoke picture.
#[test]
#[ignore = "run in a child process by the window and auto tests"]
fn child_context() {
    let backend = std::env::var("RIDGELINE_CHILD_BACKEND").expect("RIDGELINE_CHILD_BACKEND");
    let expected = std::env::var("RIDGELINE_CHILD_EXPECT").expect("RIDGELINE_CHILD_EXPECT");
    let version = std::env::var("RIDGELINE_CHILD_VERSION").expect("RIDGELINE_CHILD_VERSION");
    let expected_version =
        std::env::var("RIDGELINE_CHILD_EXPECT_VERSION").expect("RIDGELINE_CHILD_EXPECT_VERSION");
    let backend = GlBackend::from_str(&backend, true).expect("a --backend value");
    let version = GlesVersion::from_str(&version, true).expect("a GLES version");
    let started = Instant::now();
    let mut context = GlContext::new(&ContextRequest::new(backend, version, SIZE))
        .unwrap_or_else(|e| panic!("{backend:?} context: {e}"));
    let info = context.info();
    assert_eq!(info.backend.name(), expected, "auto fallback: {:?}", info.auto_fallback);
    assert!(info.version.starts_with(&expected_version), "GL_VERSION {}", info.version);
    assert_eq!(info.caps.level, version);
    if context.info().backend == OpenedBackend::Window {
        assert_eq!(context.size(), SIZE, "Xvfb has no window manager to change the size");
    }
    draw_check_and_report(&context, started);
    let events = context.pump_events(Some(std::time::Duration::ZERO));
    assert!(!events.close_requested);
}
