//! The golden views from other contexts, each compared with headless EGL
//! ES 3 under [`TOLERANCE`]: a true OpenGL ES 2.0 context (Mesa's
//! MESA_GLES_VERSION_OVERRIDE=2.0; without it Mesa hands out ES 3.2 when 2.0
//! is asked for), and a real window under Xvfb, read back before the swap.
//!
//! Both render in a child process of this test binary (the override must be
//! set before Mesa loads; winit allows one event loop per process) and leave
//! PNGs in CARGO_TARGET_TMPDIR for the parent. The window test starts Xvfb
//! (or uses a display that answers) and skips loudly without one unless
//! RIDGELINE_REQUIRE_WINDOW=1.

use clap::ValueEnum;
use image::RgbaImage;
use ridgeline::gl::{GlBackend, GlesVersion, OpenedBackend};
use std::path::PathBuf;
use testkit::compare::assert_similar;
use testkit::gl::{child_test, run_child, take_turn, window_display};
use testkit::render::{config, open, render, View, SIZE, TOLERANCE, VIEWS};
use testkit::target_tmp;

fn child_png(tag: &str, view: &View) -> PathBuf {
    target_tmp().join(format!("render-{tag}-{}.png", view.name))
}

/// One run of [`child_render`].
struct ChildRender<'a> {
    /// Names the PNGs the child leaves.
    tag: &'a str,
    backend: &'a str,
    version: &'a str,
    expect_backend: OpenedBackend,
    /// What GL_VERSION must start with.
    expect_version: &'a str,
    /// DISPLAY for the child; None removes it.
    display: Option<&'a str>,
    env: &'a [(&'a str, &'a str)],
}

impl ChildRender<'_> {
    /// Runs the child, then renders every view on EGL ES 3 here and compares.
    fn run_and_compare(&self) {
        for view in &VIEWS {
            let _ = std::fs::remove_file(child_png(self.tag, view));
        }
        let mut command = child_test("child_render");
        command
            .env("RIDGELINE_RENDER_TAG", self.tag)
            .env("RIDGELINE_RENDER_BACKEND", self.backend)
            .env("RIDGELINE_RENDER_VERSION", self.version)
            .env("RIDGELINE_RENDER_EXPECT_BACKEND", self.expect_backend.name())
            .env("RIDGELINE_RENDER_EXPECT_VERSION", self.expect_version)
            .envs(self.env.iter().copied());
        match self.display {
            Some(display) => command.env("DISPLAY", display),
            None => command.env_remove("DISPLAY"),
        };
        run_child(&mut command, self.tag);
        let mut egl = open(&config(GlBackend::Egl, GlesVersion::Es3)).expect("EGL display");
        assert!(
            egl.context.info().version.starts_with("OpenGL ES 3"),
            "{}",
            egl.context.info().version
        );
        for view in &VIEWS {
            let path = child_png(self.tag, view);
            let from_child: RgbaImage =
                image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
            let (from_egl, _) = render(&mut egl, &view.camera());
            let name = format!("{}-vs-egl-es3-{}", self.tag, view.name);
            let difference = assert_similar(&name, &from_egl, &from_child, &TOLERANCE);
            println!("{}: {difference}", name);
        }
    }
}

#[test]
fn es2_context_renders_what_es3_renders() {
    let _turn = take_turn();
    ChildRender {
        tag: "egl-es2",
        backend: "egl",
        version: "es2",
        expect_backend: OpenedBackend::Egl,
        expect_version: "OpenGL ES 2.0",
        display: None,
        env: &[("MESA_GLES_VERSION_OVERRIDE", "2.0")],
    }
    .run_and_compare();
}

#[test]
fn window_under_xvfb_renders_what_egl_renders() {
    let _turn = take_turn();
    let Some(window) = window_display("window_under_xvfb_renders_what_egl_renders") else { return };
    ChildRender {
        tag: "window-es3",
        backend: "window",
        version: "es3",
        expect_backend: OpenedBackend::Window,
        expect_version: "OpenGL ES 3",
        display: Some(&window.display),
        env: &[],
    }
    .run_and_compare();
}

fn child_env(var: &str) -> String {
    std::env::var(var).unwrap_or_else(|_| panic!("{var} is set by the parent test"))
}

/// The child: opens RIDGELINE_RENDER_BACKEND at RIDGELINE_RENDER_VERSION,
/// checks what it got, renders every view and saves each as a PNG.
#[test]
#[ignore = "run in a child process by the ES 2.0 and window tests"]
fn child_render() {
    let tag = child_env("RIDGELINE_RENDER_TAG");
    let backend = GlBackend::from_str(&child_env("RIDGELINE_RENDER_BACKEND"), true)
        .expect("a --backend value");
    let version = GlesVersion::from_str(&child_env("RIDGELINE_RENDER_VERSION"), true)
        .expect("a GLES version");
    let mut display = open(&config(backend, version))
        .unwrap_or_else(|e| panic!("{backend:?} {version:?} display: {e}"));
    let info = display.context.info().clone();
    println!("{tag}: {} on {} ({})", info.version, info.renderer, info.platform);
    assert_eq!(info.backend.name(), child_env("RIDGELINE_RENDER_EXPECT_BACKEND"));
    assert!(
        info.version.starts_with(&child_env("RIDGELINE_RENDER_EXPECT_VERSION")),
        "GL_VERSION {}",
        info.version
    );
    assert_eq!(info.caps.level, version);
    assert_eq!(display.context.size(), SIZE, "Xvfb has no window manager to change the size");
    for view in &VIEWS {
        let (image, _) = render(&mut display, &view.camera());
        display.context.present().expect("present");
        let path = child_png(&tag, view);
        image.save(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
    let events = display.context.pump_events(Some(std::time::Duration::ZERO));
    assert!(!events.close_requested);
}
