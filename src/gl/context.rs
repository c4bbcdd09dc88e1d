//! [`GlContext`]: one OpenGL (ES) context from the backend asked for, its
//! function table and capabilities, and the render target it draws to (an
//! offscreen framebuffer when headless, the window otherwise).

use std::rc::Rc;
use std::time::Duration;

use glam::UVec2;
use glow::HasContext;
use image::RgbaImage;

use super::caps::{Capabilities, GlApi, GlesVersion};
use super::egl::EglHeadless;
use super::error::GlError;
use super::handle::Gl;
use super::offscreen::{read_rgba, OffscreenTarget};
use super::osmesa::OsMesaContext;
use super::probe::display_answers;
use super::window::{WindowContext, WindowEvents};

/// Which platform to open a context on (`--backend`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum GlBackend {
    /// A window when a display answers, else headless EGL.
    #[default]
    Auto,
    /// A window through winit (X11 or Wayland).
    Window,
    /// Headless OpenGL ES through EGL's device platform.
    Egl,
    /// Headless desktop GL through libOSMesa, loaded at run time.
    #[value(name = "osmesa")]
    OsMesa,
}

/// The platform a context was actually opened on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpenedBackend {
    /// A window through winit (X11 or Wayland).
    Window,
    /// Headless OpenGL ES through EGL.
    Egl,
    /// Headless desktop GL through libOSMesa.
    OsMesa,
}

impl OpenedBackend {
    /// The backend's name as `--backend` spells it: `window`, `egl` or `osmesa`.
    pub fn name(self) -> &'static str {
        match self {
            OpenedBackend::Window => "window",
            OpenedBackend::Egl => "egl",
            OpenedBackend::OsMesa => "osmesa",
        }
    }

    /// True for backends drawing into an offscreen framebuffer.
    pub fn is_headless(self) -> bool {
        self != OpenedBackend::Window
    }
}

/// What to open.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ContextRequest {
    /// Which platform to open the context on (`auto` tries them in turn).
    pub backend: GlBackend,
    /// The OpenGL ES level the code asks for.
    pub version: GlesVersion,
    /// Offscreen target size, or the window's initial inner size.
    pub size: UVec2,
    /// Window title (ignored when headless).
    pub title: String,
    /// Use vertex array objects where the driver offers them; `false`
    /// takes the path of bare ES 2.0 boards (no OES_vertex_array_object)
    /// on any driver.
    pub vertex_arrays: bool,
}

impl ContextRequest {
    /// A request titled `Ridgeline`.
    pub fn new(backend: GlBackend, version: GlesVersion, size: UVec2) -> ContextRequest {
        ContextRequest {
            backend,
            version,
            size,
            title: "Ridgeline".to_owned(),
            vertex_arrays: true,
        }
    }
}

/// What the driver says about itself, and what was asked of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GlInfo {
    /// The platform the context was actually opened on.
    pub backend: OpenedBackend,
    /// The platform underneath: EGL version and device, OSMesa library, or
    /// window system and GL display.
    pub platform: String,
    /// The OpenGL ES level that was asked for.
    pub requested: GlesVersion,
    /// GL_VERSION, GL_RENDERER, GL_VENDOR, GL_SHADING_LANGUAGE_VERSION.
    pub version: String,
    /// GL_RENDERER: the driver's name for the GPU or rasteriser.
    pub renderer: String,
    /// GL_VENDOR.
    pub vendor: String,
    /// GL_SHADING_LANGUAGE_VERSION.
    pub shading_language_version: String,
    /// What the renderer may use on this context.
    pub caps: Capabilities,
    /// Why `--backend auto` did not open a window, when it did not.
    pub auto_fallback: Option<String>,
}

impl GlInfo {
    /// OpenGL ES (true) or desktop OpenGL running the ES shaders (false).
    pub fn is_es(&self) -> bool {
        self.caps.reported.api == GlApi::Es
    }
}

/// The platform objects; each variant destroys its context on drop.
enum Platform {
    Egl(EglHeadless),
    OsMesa(OsMesaContext),
    Window(Box<WindowContext>),
}

/// An open, current context with its render target. Bound to the thread that
/// opened it (GL contexts are current per thread).
pub struct GlContext {
    /// Headless only; dropped first, while the context still lives.
    offscreen: Option<OffscreenTarget>,
    gl: Rc<Gl>,
    info: GlInfo,
    platform: Platform,
}

impl GlContext {
    /// Opens a context as `request` asks and makes it current.
    pub fn new(request: &ContextRequest) -> Result<GlContext, GlError> {
        match request.backend {
            GlBackend::Window => Self::open_window(request),
            GlBackend::Egl => Self::open_egl(request),
            GlBackend::OsMesa => Self::open_osmesa(request),
            GlBackend::Auto => Self::open_auto(request),
        }
    }

    fn open_auto(request: &ContextRequest) -> Result<GlContext, GlError> {
        let window_refusal = match display_answers() {
            Ok(()) => match Self::open_window(request) {
                Ok(context) => return Ok(context),
                Err(e) => e.to_string(),
            },
            Err(reason) => format!("no display: {reason}"),
        };
        let mut context = Self::open_egl(request)?;
        context.info.auto_fallback = Some(window_refusal);
        Ok(context)
    }

    fn open_egl(request: &ContextRequest) -> Result<GlContext, GlError> {
        let (egl, glow) = EglHeadless::open(request.version)?;
        Self::finish(glow, Platform::Egl(egl), request)
    }

    fn open_osmesa(request: &ContextRequest) -> Result<GlContext, GlError> {
        let (osmesa, glow) = OsMesaContext::open()?;
        Self::finish(glow, Platform::OsMesa(osmesa), request)
    }

    fn open_window(request: &ContextRequest) -> Result<GlContext, GlError> {
        let (window, glow) = WindowContext::open(request.version, request.size, &request.title)?;
        Self::finish(glow, Platform::Window(Box::new(window)), request)
    }

    /// Reads what the driver offers, refuses a context that cannot run the
    /// GLSL ES shaders, and gives headless contexts their render target.
    fn finish(
        glow: glow::Context,
        platform: Platform,
        request: &ContextRequest,
    ) -> Result<GlContext, GlError> {
        let mut caps = Capabilities::detect(&glow, request.version);
        caps.vertex_array_objects &= request.vertex_arrays;
        let [version, renderer, vendor, shading_language_version] = read_strings(&glow);
        let (backend, platform_name) = match &platform {
            Platform::Egl(egl) => (OpenedBackend::Egl, egl.platform.clone()),
            Platform::OsMesa(osmesa) => (OpenedBackend::OsMesa, osmesa.platform()),
            Platform::Window(window) => (OpenedBackend::Window, window.platform.clone()),
        };
        if !caps.glsl_es_100 {
            return Err(GlError::ContextCreation {
                backend: backend.name(),
                reason: format!(
                    "{version} cannot compile GLSL ES 1.00 (no GL_ARB_ES2_compatibility)"
                ),
            });
        }
        let gl = Rc::new(Gl::new(glow, caps));
        let offscreen = if backend.is_headless() {
            Some(OffscreenTarget::new(&gl, request.size)?)
        } else {
            None
        };
        let info = GlInfo {
            backend,
            platform: platform_name,
            requested: request.version,
            version,
            renderer,
            vendor,
            shading_language_version,
            caps,
            auto_fallback: None,
        };
        Ok(GlContext { offscreen, gl, info, platform })
    }

    /// The shared function table, for owner types and passes.
    pub fn gl(&self) -> &Rc<Gl> {
        &self.gl
    }

    /// What the driver says about itself, and what was asked of it.
    pub fn info(&self) -> &GlInfo {
        &self.info
    }

    /// Features the renderer may use on this context.
    pub fn caps(&self) -> &Capabilities {
        self.gl.caps()
    }

    /// The render target's size in pixels.
    pub fn size(&self) -> UVec2 {
        match (&self.offscreen, &self.platform) {
            (Some(target), _) => target.size(),
            (None, Platform::Window(window)) => window.size(),
            (None, _) => unreachable!("headless contexts always have an offscreen target"),
        }
    }

    /// Makes this context current on the calling thread again (needed only
    /// when a thread switches between contexts).
    pub fn make_current(&self) -> Result<(), GlError> {
        match &self.platform {
            Platform::Egl(egl) => egl.make_current(),
            Platform::OsMesa(osmesa) => osmesa.make_current(),
            Platform::Window(window) => window.make_current(),
        }
    }

    /// Binds the render target: the offscreen framebuffer, or the window's.
    #[allow(unsafe_code)]
    pub fn bind_target(&self) {
        match &self.offscreen {
            Some(target) => target.bind(),
            // SAFETY: framebuffer 0 is the window surface, always valid.
            None => unsafe { self.gl.bind_framebuffer(glow::FRAMEBUFFER, None) },
        }
    }

    /// Reads the render target back as RGBA8, row 0 at the top. On a window
    /// this reads the back buffer, so call it before [`Self::present`].
    pub fn read_pixels(&self) -> Result<RgbaImage, GlError> {
        self.bind_target();
        read_rgba(&self.gl, self.size())
    }

    /// Shows the frame: swaps a window's buffers; flushes a headless context.
    #[allow(unsafe_code)]
    pub fn present(&self) -> Result<(), GlError> {
        match &self.platform {
            Platform::Window(window) => window.swap_buffers(),
            _ => {
                // SAFETY: glFlush has no arguments and this context is current.
                unsafe { self.gl.flush() };
                Ok(())
            }
        }
    }

    /// Handles window events, waiting up to `timeout`; headless contexts
    /// have none.
    pub fn pump_events(&mut self, timeout: Option<Duration>) -> WindowEvents {
        match &mut self.platform {
            Platform::Window(window) => window.pump(timeout),
            _ => WindowEvents::default(),
        }
    }
}

impl Drop for GlContext {
    fn drop(&mut self) {
        // A failure here leaves objects to die with the context anyway.
        let _ = self.make_current();
        self.offscreen = None;
        // Owner types still alive must not call into a destroyed context.
        self.gl.mark_dead();
    }
}

#[allow(unsafe_code)]
fn read_strings(gl: &glow::Context) -> [String; 4] {
    // SAFETY: glGetString of four enums valid in every GL and ES version;
    // glow copies the driver's static strings.
    unsafe {
        [glow::VERSION, glow::RENDERER, glow::VENDOR, glow::SHADING_LANGUAGE_VERSION]
            .map(|name| gl.get_parameter_string(name))
    }
}
