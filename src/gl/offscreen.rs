//! The headless render targets (a framebuffer with colour and depth
//! renderbuffers: RGBA8 for pictures, RGBA32F for the accuracy tool's
//! positions) and reading them back with row 0 at the top.

use std::rc::Rc;

use glam::UVec2;
use glow::HasContext;
use image::RgbaImage;

use super::error::GlError;
use super::handle::Gl;
use super::objects::{Framebuffer, Renderbuffer};
use crate::accuracy::PositionImage;
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
        let colour_format = if gl.caps().rgba8_renderbuffer { glow::RGBA8 } else { glow::RGBA4 };
        OffscreenTarget::with_colour(gl, colour_format, size)
    }

    /// RGBA32F colour (camera-relative positions, in metres) and the best
    /// depth the context has. Refused where float colour buffers are missing
    /// (a bare ES 2.0 or ES 3.0 context without `GL_EXT_color_buffer_float`).
    pub fn positions(gl: &Rc<Gl>, size: UVec2) -> Result<OffscreenTarget, GlError> {
        if !gl.caps().float_colour_buffer {
            let why = "position targets need RGBA32F colour buffers (ES 3.2, or GL_EXT_color_buffer_float)";
            return Err(GlError::InvalidRequest(why.to_owned()));
        }
        OffscreenTarget::with_colour(gl, glow::RGBA32F, size)
    }

    fn with_colour(
        gl: &Rc<Gl>,
        colour_format: u32,
        size: UVec2,
    ) -> Result<OffscreenTarget, GlError> {
        let depth_format = if gl.caps().depth24_renderbuffer {
            glow::DEPTH_COMPONENT24
        } else {
            glow::DEPTH_COMPONENT16
        };
        let colour = Renderbuffer::new(gl, colour_format, size)?;
        let depth = Renderbuffer::new(gl, depth_format, size)?;
        let framebuffer = Framebuffer::new(gl)?;
        framebuffer.attach(glow::COLOR_ATTACHMENT0, &colour)?;
        framebuffer.attach(glow::DEPTH_ATTACHMENT, &depth)?;
        framebuffer.check_complete(size)?;
        debug_assert_eq!(colour.size(), depth.size());
        Ok(OffscreenTarget { framebuffer, colour, depth })
    }

    /// Width and height of the target, pixels.
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

impl OffscreenTarget {
    /// Reads this RGBA32F target (see [`Self::positions`]) into `out`, then
    /// leaves it bound.
    pub fn read_positions(&self, out: &mut PositionImage) -> Result<(), GlError> {
        self.bind();
        out.size = self.size();
        read_positions(self.framebuffer.gl(), out.size, &mut out.texels)
    }
}

/// Reads the bound RGBA32F framebuffer's `size` pixels into `out` (resized
/// to width * height), row 0 at the top.
#[allow(unsafe_code)]
pub(crate) fn read_positions(gl: &Gl, size: UVec2, out: &mut Vec<[f32; 4]>) -> Result<(), GlError> {
    let (width, height) = (size.x as usize, size.y as usize);
    out.resize(width * height, [0.0; 4]);
    // SAFETY: RGBA/FLOAT writes exactly width * height * 16 bytes, the
    // length of `out` as bytes; sizes come from a target the GL accepted.
    unsafe {
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(out.as_mut_slice());
        let data = glow::PixelPackData::Slice(Some(bytes));
        gl.read_pixels(0, 0, size.x as i32, size.y as i32, glow::RGBA, glow::FLOAT, data);
    }
    gl_check!(gl)?;
    // GL's row 0 is the bottom: swap rows in place.
    for row in 0..height / 2 {
        let (top, bottom) = out.split_at_mut((height - 1 - row) * width);
        top[row * width..(row + 1) * width].swap_with_slice(&mut bottom[..width]);
    }
    Ok(())
}

/// Reads the bound framebuffer's `size` pixels as RGBA8, flipped so that
/// row 0 is the top of the picture (GL's row 0 is the bottom).
#[allow(unsafe_code)]
pub(crate) fn read_rgba(gl: &Gl, size: UVec2) -> Result<RgbaImage, GlError> {
    let row_bytes = size.x as usize * 4;
    let mut pixels = vec![0u8; row_bytes * size.y as usize];
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
            glow::PixelPackData::Slice(Some(&mut pixels)),
        );
    }
    gl_check!(gl)?;
    // GL's rows run bottom up; flipped in place, so a read-back takes one
    // image's heap (a memory budget counts snapshots).
    let rows = size.y as usize;
    for y in 0..rows / 2 {
        let (top, bottom) = pixels.split_at_mut((rows - 1 - y) * row_bytes);
        top[y * row_bytes..(y + 1) * row_bytes].swap_with_slice(&mut bottom[..row_bytes]);
    }
    RgbaImage::from_raw(size.x, size.y, pixels).ok_or_else(|| {
        GlError::InvalidRequest(format!("read-back of {}x{} pixels", size.x, size.y))
    })
}
