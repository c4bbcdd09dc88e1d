//! The headless render target (a framebuffer with colour and depth
//! renderbuffers) and reading pixels back into an image with row 0 at the top.

use std::rc::Rc;

use glam::UVec2;
use glow::HasContext;
use image::RgbaImage;

use super::error::GlError;
use super::handle::Gl;
use super::objects::{Framebuffer, Renderbuffer};
use crate::gl_check;

/// Colour and depth storage of one size, drawn to by headless contexts.
#[derive(Debug)]
pub struct OffscreenTarget {
    framebuffer: Framebuffer,
    colour: Renderbuffer,
    depth: Renderbuffer,
}

impl OffscreenTarget {
    /// RGBA8 colour and 24-bit depth where the context has them; RGBA4 and
    /// 16-bit depth on a bare ES 2.0 context, which has nothing larger.
    pub fn new(gl: &Rc<Gl>, size: UVec2) -> Result<OffscreenTarget, GlError> {
        let caps = gl.caps();
        let colour_format = if caps.rgba8_renderbuffer { glow::RGBA8 } else { glow::RGBA4 };
        let depth_format =
            if caps.depth24_renderbuffer { glow::DEPTH_COMPONENT24 } else { glow::DEPTH_COMPONENT16 };
        let colour = Renderbuffer::new(gl, colour_format, size)?;
        let depth = Renderbuffer::new(gl, depth_format, size)?;
        let framebuffer = Framebuffer::new(gl)?;
        framebuffer.attach(glow::COLOR_ATTACHMENT0, &colour)?;
        framebuffer.attach(glow::DEPTH_ATTACHMENT, &depth)?;
        framebuffer.check_complete(size)?;
        debug_assert_eq!(colour.size(), depth.size());
        Ok(OffscreenTarget { framebuffer, colour, depth })
    }

    pub fn size(&self) -> UVec2 {
        self.colour.size()
    }

    /// Binds the target for drawing and reading.
    pub fn bind(&self) {
        self.framebuffer.bind();
    }

    /// The colour and depth formats actually allocated.
    pub fn formats(&self) -> (u32, u32) {
        (self.colour.internal_format(), self.depth.internal_format())
    }
}

/// Reads the bound framebuffer's `size` pixels as RGBA8, flipped so that
/// row 0 is the top of the picture (GL's row 0 is the bottom).
#[allow(unsafe_code)]
pub(crate) fn read_rgba(gl: &Gl, size: UVec2) -> Result<RgbaImage, GlError> {
    let row_bytes = size.x as usize * 4;
    let mut bottom_up = vec![0u8; row_bytes * size.y as usize];
    // SAFETY: RGBA/UNSIGNED_BYTE with pack alignment 1 writes exactly
    // width * height * 4 bytes, the length of `bottom_up`; sizes come from a
    // target the GL accepted, so they fit GLsizei.
    unsafe {
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        gl.read_pixels(
            0,
            0,
            size.x as i32,
            size.y as i32,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelPackData::Slice(Some(&mut bottom_up)),
        );
    }
    gl_check!(gl)?;
    let top_down: Vec<u8> = bottom_up.chunks_exact(row_bytes.max(1)).rev().flatten().copied().collect();
    RgbaImage::from_raw(size.x, size.y, top_down)
        .ok_or_else(|| GlError::InvalidRequest(format!("read-back of {}x{} pixels", size.x, size.y)))
}
