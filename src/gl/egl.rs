//! Headless OpenGL ES through EGL's device platform (EGL_EXT_platform_device):
//! no window system, a surfaceless context, drawing into an offscreen
//! framebuffer. On Mesa without a GPU the only device is llvmpipe's
//! (EGL_MESA_device_software).

use std::ffi::CStr;

use glutin::api::egl::context::PossiblyCurrentContext;
use glutin::api::egl::device::Device;
use glutin::api::egl::display::Display;
use glutin::config::{Api, ConfigSurfaceTypes, ConfigTemplateBuilder};
use glutin::context::{ContextApi, ContextAttributesBuilder, Version};
use glutin::error::ErrorKind;
use glutin::prelude::*;

use super::caps::GlesVersion;
use super::error::GlError;

const BACKEND: &str = "EGL";

/// A current, surfaceless EGL context and its display. The context is
/// declared first so it is destroyed before the display.
pub(crate) struct EglHeadless {
    context: PossiblyCurrentContext,
    /// Held so the display outlives the context.
    _display: Display,
    /// The EGL version and device it runs on, for reports.
    pub(crate) platform: String,
}

impl EglHeadless {
    /// Opens a context on the first device that gives one.
    pub(crate) fn open(version: GlesVersion) -> Result<(EglHeadless, glow::Context), GlError> {
        let devices: Vec<Device> = Device::query_devices().map_err(device_error)?.collect();
        if devices.is_empty() {
            return Err(creation("EGL lists no devices (llvmpipe needs EGL_MESA_device_software)"));
        }
        let mut refusals = Vec::new();
        for device in &devices {
            match open_on(device, version) {
                Ok(opened) => return Ok(opened),
                Err(e) => refusals.push(format!("{}: {e}", describe(device))),
            }
        }
        Err(creation(&refusals.join("; ")))
    }

    /// Makes the context current on this thread again.
    pub(crate) fn make_current(&self) -> Result<(), GlError> {
        self.context.make_current_surfaceless().map_err(|e| creation(&format!("make current: {e}")))
    }
}

fn open_on(device: &Device, version: GlesVersion) -> Result<(EglHeadless, glow::Context), String> {
    let display = with_device(device)?;
    let api = match version {
        GlesVersion::Es2 => Api::GLES2,
        GlesVersion::Es3 => Api::GLES3,
    };
    // No surface type: the context is only made current surfaceless.
    let template = ConfigTemplateBuilder::new()
        .with_api(api)
        .with_surface_type(ConfigSurfaceTypes::empty())
        .build();
    let config = find_config(&display, template)?;
    let major = if version == GlesVersion::Es2 { 2 } else { 3 };
    let attributes = ContextAttributesBuilder::new()
        .with_context_api(ContextApi::Gles(Some(Version::new(major, 0))))
        .build(None);
    let context = create_context(&display, &config, &attributes)?
        .make_current_surfaceless()
        .map_err(|e| format!("surfaceless make current: {e}"))?;
    let glow = load_glow(&display);
    let platform = format!("{} on device {}", display.version_string(), describe(device));
    Ok((EglHeadless { context, _display: display, platform }, glow))
}

#[allow(unsafe_code)]
fn with_device(device: &Device) -> Result<Display, String> {
    // SAFETY: `raw_display` is None, the only case with no handle to keep
    // valid; the device comes from eglQueryDevicesEXT.
    unsafe { Display::with_device(device, None) }.map_err(|e| format!("display: {e}"))
}

#[allow(unsafe_code)]
fn find_config(
    display: &Display,
    template: glutin::config::ConfigTemplate,
) -> Result<glutin::api::egl::config::Config, String> {
    // SAFETY: the template names no native window, so no handle must outlive
    // the call.
    let mut configs =
        unsafe { display.find_configs(template) }.map_err(|e| format!("configs: {e}"))?;
    configs.next().ok_or_else(|| "no EGL config for the requested ES version".to_owned())
}

#[allow(unsafe_code)]
fn create_context(
    display: &Display,
    config: &glutin::api::egl::config::Config,
    attributes: &glutin::context::ContextAttributes,
) -> Result<glutin::api::egl::context::NotCurrentContext, String> {
    // SAFETY: the attributes name no window and share no context, so there
    // is no foreign handle whose lifetime glutin relies on.
    unsafe { display.create_context(config, attributes) }.map_err(|e| format!("context: {e}"))
}

#[allow(unsafe_code)]
fn load_glow(display: &Display) -> glow::Context {
    // SAFETY: the context is current on this thread, and eglGetProcAddress
    // returns entry points valid for it (null for unknown names, which glow
    // treats as not loaded).
    unsafe {
        glow::Context::from_loader_function_cstr(|name: &CStr| display.get_proc_address(name))
    }
}

/// The device's name where EGL_EXT_device_query_name gives one, and
/// whether it is Mesa's software device.
fn describe(device: &Device) -> String {
    let software = device.extensions().contains("EGL_MESA_device_software");
    match (device.name(), software) {
        (Some(name), true) => format!("{name} (software)"),
        (Some(name), false) => name.to_owned(),
        (None, true) => "the software device (EGL_MESA_device_software)".to_owned(),
        (None, false) => "an unnamed device".to_owned(),
    }
}

fn device_error(e: glutin::error::Error) -> GlError {
    if e.error_kind() == ErrorKind::NotFound {
        GlError::LibraryMissing { library: "libEGL.so.1".to_owned(), reason: e.to_string() }
    } else {
        creation(&format!("listing EGL devices: {e}"))
    }
}

fn creation(reason: &str) -> GlError {
    GlError::ContextCreation { backend: BACKEND, reason: reason.to_owned() }
}
