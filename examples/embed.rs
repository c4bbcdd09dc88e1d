//! An integrator's entry point: an application that owns its GL context,
//! its framebuffer and its render loop hands the context to Ridgeline and
//! asks for one frame per call, drawn into whatever framebuffer is bound.
//!
//! Here the application is headless: it opens its own EGL context on the
//! device platform, makes an offscreen framebuffer of its own, flies a few
//! frames of the built-in approach over the built-in terrain and writes the
//! last one to `target/embed/frame.png`. After every frame it checks the GL
//! state Ridgeline documents leaving behind (`gl::GlRenderer`'s module doc).
//! With `--clusters` the tiles are drawn as cluster batches (Judnich &
//! Ling), and it says how many clusters it drew.
//!
//! `cargo run --release --example embed [-- --clusters]`;
//! `tests/embed_example.rs` runs it both ways.

use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use glow::HasContext;
use glutin::api::egl::{device::Device, display::Display};
use glutin::config::{Api, ConfigSurfaceTypes, ConfigTemplateBuilder};
use glutin::context::{ContextApi, ContextAttributesBuilder, Version};
use glutin::prelude::*;
use ridgeline::camera::Camera;
use ridgeline::clipmap::LoaderMode;
use ridgeline::flight::default_flight;
use ridgeline::gl::{Gl, GlRenderer, GlesVersion};
use ridgeline::pipeline::{FramePipeline, FrameStats, PipelineConfig};
use ridgeline::pyramid::Silent;
use ridgeline::scene::TerrainSummary;

type Error = Box<dyn std::error::Error>;

const WIDTH: u32 = 320;
const HEIGHT: u32 = 180;

fn main() -> Result<(), Error> {
    let clusters = clusters_flag(std::env::args().skip(1))?;
    let out = PathBuf::from("target/embed");
    let flight = run(&out, Path::new("cache"), 8, clusters)?;
    if clusters {
        let drawn: usize = flight.frames.iter().map(|f| f.scene.clusters).sum();
        println!("drew {drawn} clusters in {} frames", flight.frames.len());
    }
    println!("wrote {}", flight.picture.display());
    Ok(())
}

/// Whether the arguments ask for clusters: `--clusters`, or nothing.
pub fn clusters_flag(mut args: impl Iterator<Item = String>) -> Result<bool, Error> {
    match (args.next().as_deref(), args.next()) {
        (None, _) => Ok(false),
        (Some("--clusters"), None) => Ok(true),
        _ => Err("usage: embed [--clusters]".into()),
    }
}

/// What [`run`] drew: each frame's stats and the last frame's picture.
pub struct Flight {
    pub frames: Vec<FrameStats>,
    pub picture: PathBuf,
}

/// Flies `frames` frames into the application's framebuffer with the
/// terrain cache in `cache`, as cluster batches with `clusters`; writes the
/// last frame under `out`.
pub fn run(out: &Path, cache: &Path, frames: u32, clusters: bool) -> Result<Flight, Error> {
    // 1. The application's own context and framebuffer.
    let (display, context, glow) = open_egl()?;
    let framebuffer = AppFramebuffer::new(&glow, WIDTH, HEIGHT)?;
    // 2. Ridgeline adopts the context: the same function table, its
    //    capabilities read once. The terrain and the pipeline are GL-free;
    //    the renderer's buffers are the ones the pipeline planned.
    let gl: Rc<Gl> = Gl::adopt(glow, GlesVersion::Es3)?;
    std::fs::create_dir_all(cache)?;
    let pyramid = Arc::new(ridgeline::dataset::open(None, cache, &Silent)?);
    let summary = TerrainSummary::from_pyramid(pyramid.info());
    let mut config =
        PipelineConfig { loader: LoaderMode::Inline, ..PipelineConfig::new([WIDTH, HEIGHT]) };
    config.scene.clusters = clusters;
    let mut pipeline = FramePipeline::new(&config, pyramid.clone(), summary)?;
    let mut renderer = GlRenderer::new(&gl, &pipeline.buffer_plan())?;
    let path = default_flight(&pyramid);
    let mut flown = Vec::new();
    // 3. The application's loop: bind its target, ask for a frame, go on.
    for t in path.frame_times(frames) {
        let camera: Camera = path.sample(t).camera(60.0, [WIDTH, HEIGHT]);
        framebuffer.bind(&gl);
        pipeline.settle(&camera, 1000)?;
        let stats = pipeline.frame(&camera, &mut renderer)?;
        check_state_left(&gl, &framebuffer)?;
        let (tiles, clusters, draws) =
            (stats.scene.tiles, stats.scene.clusters, stats.calls.draw_calls);
        println!("t = {t:5.1} s: {tiles} tiles, {clusters} clusters, {draws} draw calls");
        flown.push(stats);
    }
    std::fs::create_dir_all(out)?;
    let picture = out.join("frame.png");
    framebuffer.read(&gl)?.save(&picture)?;
    // 4. Ridgeline's objects go before the context they live in.
    drop(renderer);
    framebuffer.delete(&gl);
    drop(gl);
    drop(context);
    drop(display);
    Ok(Flight { frames: flown, picture })
}

/// A surfaceless GLES 3 context on the first EGL device that gives one.
fn open_egl(
) -> Result<(Display, glutin::api::egl::context::PossiblyCurrentContext, glow::Context), Error> {
    for device in Device::query_devices()? {
        // SAFETY: no native display handle is passed, so none must outlive it.
        #[allow(unsafe_code)]
        let Ok(display) = (unsafe { Display::with_device(&device, None) }) else {
            continue;
        };
        let template = ConfigTemplateBuilder::new()
            .with_api(Api::GLES3)
            .with_surface_type(ConfigSurfaceTypes::empty())
            .build();
        // SAFETY: the display is alive for the call.
        #[allow(unsafe_code)]
        let Some(config) = (unsafe { display.find_configs(template) })?.next() else {
            continue;
        };
        let attributes = ContextAttributesBuilder::new()
            .with_context_api(ContextApi::Gles(Some(Version::new(3, 0))))
            .build(None);
        // SAFETY: the config comes from this display.
        #[allow(unsafe_code)]
        let context = unsafe { display.create_context(&config, &attributes) }?;
        let context = context.make_current_surfaceless()?;
        // SAFETY: the context is current; names are looked up on its display.
        #[allow(unsafe_code)]
        let glow = unsafe {
            glow::Context::from_loader_function_cstr(|name| display.get_proc_address(name))
        };
        return Ok((display, context, glow));
    }
    Err("no EGL device gives a GLES 3 context".into())
}

/// The application's own render target.
struct AppFramebuffer {
    framebuffer: glow::Framebuffer,
    renderbuffers: [glow::Renderbuffer; 2],
    size: [u32; 2],
}

#[allow(unsafe_code)]
impl AppFramebuffer {
    fn new(gl: &glow::Context, width: u32, height: u32) -> Result<AppFramebuffer, Error> {
        // SAFETY: the context is current; every name is made here.
        unsafe {
            let framebuffer = gl.create_framebuffer()?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(framebuffer));
            let mut renderbuffers = Vec::new();
            for (format, attachment) in [
                (glow::RGBA8, glow::COLOR_ATTACHMENT0),
                (glow::DEPTH_COMPONENT24, glow::DEPTH_ATTACHMENT),
            ] {
                let renderbuffer = gl.create_renderbuffer()?;
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(renderbuffer));
                gl.renderbuffer_storage(glow::RENDERBUFFER, format, width as i32, height as i32);
                gl.framebuffer_renderbuffer(
                    glow::FRAMEBUFFER,
                    attachment,
                    glow::RENDERBUFFER,
                    Some(renderbuffer),
                );
                renderbuffers.push(renderbuffer);
            }
            if gl.check_framebuffer_status(glow::FRAMEBUFFER) != glow::FRAMEBUFFER_COMPLETE {
                return Err("the application's framebuffer is incomplete".into());
            }
            Ok(AppFramebuffer {
                framebuffer,
                renderbuffers: [renderbuffers[0], renderbuffers[1]],
                size: [width, height],
            })
        }
    }

    fn bind(&self, gl: &glow::Context) {
        // SAFETY: a live framebuffer of this context.
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.framebuffer)) };
    }

    fn read(&self, gl: &glow::Context) -> Result<image::RgbaImage, Error> {
        let [w, h] = self.size;
        let mut pixels = vec![0u8; (w * h * 4) as usize];
        self.bind(gl);
        // SAFETY: RGBA8 of w x h into a buffer of exactly that many bytes.
        unsafe {
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
            let data = glow::PixelPackData::Slice(Some(&mut pixels));
            gl.read_pixels(0, 0, w as i32, h as i32, glow::RGBA, glow::UNSIGNED_BYTE, data);
        }
        let image = image::RgbaImage::from_raw(w, h, pixels).ok_or("pixel buffer size")?;
        Ok(image::imageops::flip_vertical(&image))
    }

    fn delete(self, gl: &glow::Context) {
        // SAFETY: names made by `new` in this context, deleted once.
        unsafe {
            gl.delete_framebuffer(self.framebuffer);
            self.renderbuffers.into_iter().for_each(|r| gl.delete_renderbuffer(r));
        }
    }
}

/// The state `GlRenderer` documents leaving behind, queried from the driver.
#[allow(unsafe_code)]
fn check_state_left(gl: &glow::Context, target: &AppFramebuffer) -> Result<(), Error> {
    let mut failures = Vec::new();
    // SAFETY: plain state queries on the current context.
    unsafe {
        let mut expect = |what: &str, ok: bool| {
            if !ok {
                failures.push(what.to_owned());
            }
        };
        expect("depth test on", gl.is_enabled(glow::DEPTH_TEST));
        expect("depth func LESS", gl.get_parameter_i32(glow::DEPTH_FUNC) as u32 == glow::LESS);
        expect("culling on", gl.is_enabled(glow::CULL_FACE));
        expect("blend off", !gl.is_enabled(glow::BLEND));
        expect("scissor off", !gl.is_enabled(glow::SCISSOR_TEST));
        expect("no vertex array", gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING) == 0);
        let mut viewport = [0i32; 4];
        gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
        expect("viewport of the frame", viewport == [0, 0, WIDTH as i32, HEIGHT as i32]);
        expect(
            "the application's framebuffer still bound",
            gl.get_parameter_framebuffer(glow::FRAMEBUFFER_BINDING) == Some(target.framebuffer),
        );
        for index in 0..3 {
            let on = gl.get_vertex_attrib_parameter_f32_slice_enabled(index);
            expect("attribute arrays disabled", !on);
        }
        expect("no GL error", gl.get_error() == glow::NO_ERROR);
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(format!("GL state after a frame: {}", failures.join(", ")).into())
    }
}

/// Whether vertex attribute array `index` is enabled.
trait AttributeEnabled {
    /// # Safety
    /// A current context.
    unsafe fn get_vertex_attrib_parameter_f32_slice_enabled(&self, index: u32) -> bool;
}

impl AttributeEnabled for glow::Context {
    #[allow(unsafe_code)]
    unsafe fn get_vertex_attrib_parameter_f32_slice_enabled(&self, index: u32) -> bool {
        let mut value = [0.0f32; 4];
        self.get_vertex_attrib_parameter_f32_slice(
            index,
            glow::VERTEX_ATTRIB_ARRAY_ENABLED,
            &mut value,
        );
        value[0] != 0.0
    }
}
