//! An OpenGL ES context on a real window: winit opens the window on X11 or
//! Wayland, glutin (EGL first, then GLX) gives the context and its surface.
//! The event loop is pumped by [`super::GlContext::pump_events`], so the
//! caller keeps control of the frame loop.
//!
//! winit allows one event loop per process, so a process opens at most one
//! window context in its life; a second attempt fails with winit's
//! "recreation" error.

use std::num::NonZeroU32;
use std::time::Duration;

use glam::UVec2;
use glutin::config::{Api, Config, ConfigTemplate, ConfigTemplateBuilder, GlConfig};
use glutin::context::{
    ContextApi, ContextAttributesBuilder, NotCurrentGlContext, PossiblyCurrentContext,
    PossiblyCurrentGlContext, Version,
};
use glutin::display::{Display, DisplayApiPreference, GetGlDisplay, GlDisplay};
use glutin::surface::{GlSurface, Surface, SurfaceAttributesBuilder, WindowSurface};
use glutin_winit::GlWindow;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::platform::pump_events::EventLoopExtPumpEvents;
use winit::platform::x11::EventLoopExtX11;
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowAttributes, WindowId};

use super::caps::GlesVersion;
use super::error::GlError;

const BACKEND: &str = "window";

/// What happened to the window since the last pump.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WindowEvents {
    /// The user or the window system asked to close.
    pub close_requested: bool,
    /// The drawable size changed to this (the surface is already resized).
    pub resized: Option<UVec2>,
}

impl ApplicationHandler for WindowEvents {
    fn resumed(&mut self, _event_loop: &ActiveEventLoop) {}

    fn window_event(&mut self, _event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.close_requested = true,
            WindowEvent::Resized(size) => self.resized = Some(UVec2::new(size.width, size.height)),
            _ => {}
        }
    }
}

/// The window and its GL objects, declared in drop order: surface and
/// context go before the window they draw to, the event loop last.
pub(crate) struct WindowContext {
    surface: Surface<WindowSurface>,
    context: PossiblyCurrentContext,
    window: Window,
    event_loop: EventLoop<()>,
    /// Window system and GL display, for reports.
    pub(crate) platform: String,
}

impl WindowContext {
    pub(crate) fn open(
        version: GlesVersion,
        size: UVec2,
        title: &str,
    ) -> Result<(WindowContext, glow::Context), GlError> {
        let event_loop = new_event_loop()?;
        let attributes = WindowAttributes::default()
            .with_title(title)
            .with_inner_size(winit::dpi::PhysicalSize::new(size.x, size.y))
            .with_resizable(true);
        let api = match version {
            GlesVersion::Es2 => Api::GLES2,
            GlesVersion::Es3 => Api::GLES3,
        };
        let display = window_system_display(&event_loop)?;
        let template = ConfigTemplateBuilder::new().with_api(api).with_depth_size(24).build();
        let config = pick_config(&display, template)?;
        let window = glutin_winit::finalize_window(&event_loop, attributes, &config)
            .map_err(|e| creation(&format!("window: {e}")))?;
        let (surface, context) = surface_and_context(&window, &config, version)?;
        let glow = load_glow(&config);
        let window_system = if event_loop.is_x11() { "X11" } else { "Wayland" };
        let platform = format!("{} on {window_system}", display.version_string());
        let mut opened = WindowContext { surface, context, window, event_loop, platform };
        // Let the window system map the window and report its size.
        opened.pump(Some(Duration::from_millis(10)));
        Ok((opened, glow))
    }

    /// The drawable size in pixels.
    pub(crate) fn size(&self) -> UVec2 {
        let size = self.window.inner_size();
        UVec2::new(size.width, size.height)
    }

    pub(crate) fn make_current(&self) -> Result<(), GlError> {
        self.context
            .make_current(&self.surface)
            .map_err(|e| creation(&format!("make current: {e}")))
    }

    pub(crate) fn swap_buffers(&self) -> Result<(), GlError> {
        self.surface
            .swap_buffers(&self.context)
            .map_err(|e| creation(&format!("swap buffers: {e}")))
    }

    /// Handles pending window events, waiting up to `timeout` for one, and
    /// resizes the surface to follow the window.
    pub(crate) fn pump(&mut self, timeout: Option<Duration>) -> WindowEvents {
        let mut events = WindowEvents::default();
        self.event_loop.pump_app_events(timeout, &mut events);
        if events.resized.is_some() {
            self.window.resize_surface(&self.surface, &self.context);
        }
        events
    }
}

fn new_event_loop() -> Result<EventLoop<()>, GlError> {
    let mut builder = EventLoop::builder();
    // Tests and tools open windows off the main thread; X11 and Wayland allow
    // it, and winit needs to be told.
    winit::platform::x11::EventLoopBuilderExtX11::with_any_thread(&mut builder, true);
    builder.build().map_err(|e| match e {
        winit::error::EventLoopError::Os(os) => GlError::NoDisplay { reason: os.to_string() },
        other => creation(&format!("event loop: {other}")),
    })
}

/// The GL display of the window system winit connected to: EGL first (it
/// gives OpenGL ES directly), GLX where EGL is missing.
#[allow(unsafe_code)]
fn window_system_display(event_loop: &EventLoop<()>) -> Result<Display, GlError> {
    let raw_display = event_loop
        .display_handle()
        .map_err(|e| GlError::NoDisplay { reason: e.to_string() })?
        .as_raw();
    let preference =
        DisplayApiPreference::EglThenGlx(Box::new(winit::platform::x11::register_xlib_error_hook));
    // SAFETY: `raw_display` is the event loop's live connection, and the
    // event loop outlives every GL object made from this display (it is the
    // last field of WindowContext).
    unsafe { Display::new(raw_display, preference) }
        .map_err(|e| creation(&format!("GL display: {e}")))
}

/// Prefers a config with 24 depth bits, no multisampling (the read-back
/// tests compare exact pixels) and 8 alpha bits.
#[allow(unsafe_code)]
fn pick_config(display: &Display, template: ConfigTemplate) -> Result<Config, GlError> {
    // SAFETY: the template names no native window whose handle must stay
    // valid.
    let configs = unsafe { display.find_configs(template) }
        .map_err(|e| creation(&format!("configs: {e}")))?;
    configs
        .max_by_key(|config| {
            (config.depth_size() >= 24, config.num_samples() == 0, config.alpha_size() == 8)
        })
        .ok_or_else(|| creation("no config offers the requested OpenGL ES version"))
}

#[allow(unsafe_code)]
fn surface_and_context(
    window: &Window,
    config: &Config,
    version: GlesVersion,
) -> Result<(Surface<WindowSurface>, PossiblyCurrentContext), GlError> {
    let display = config.display();
    let raw_window =
        window.window_handle().map_err(|e| creation(&format!("window handle: {e}")))?.as_raw();
    let major = if version == GlesVersion::Es2 { 2 } else { 3 };
    let context_attributes = ContextAttributesBuilder::new()
        .with_context_api(ContextApi::Gles(Some(Version::new(major, 0))))
        .build(Some(raw_window));
    let size = window.inner_size();
    let (width, height) = NonZeroU32::new(size.width)
        .zip(NonZeroU32::new(size.height))
        .ok_or_else(|| creation("the window has a zero size"))?;
    let surface_attributes =
        SurfaceAttributesBuilder::<WindowSurface>::new().build(raw_window, width, height);
    // SAFETY: `raw_window` is the handle of `window`, which the returned
    // surface and context are stored beside and dropped before (see
    // WindowContext's field order).
    let (surface, context) = unsafe {
        let context = display
            .create_context(config, &context_attributes)
            .map_err(|e| creation(&format!("context: {e}")))?;
        let surface = display
            .create_window_surface(config, &surface_attributes)
            .map_err(|e| creation(&format!("surface: {e}")))?;
        (surface, context)
    };
    let context =
        context.make_current(&surface).map_err(|e| creation(&format!("make current: {e}")))?;
    Ok((surface, context))
}

#[allow(unsafe_code)]
fn load_glow(config: &Config) -> glow::Context {
    let display = config.display();
    // SAFETY: the context is current on this thread and the display's
    // GetProcAddress returns entry points valid for it, or null.
    unsafe { glow::Context::from_loader_function_cstr(|name| display.get_proc_address(name)) }
}

fn creation(reason: &str) -> GlError {
    GlError::ContextCreation { backend: BACKEND, reason: reason.to_owned() }
}
