//! [`Renderbuffer`] and [`Framebuffer`]: offscreen render targets.

use std::rc::Rc;

use glam::UVec2;
use glow::HasContext;

use crate::gl::{error::GlError, handle::Gl};
use crate::gl_check;

/// Renderbuffer storage of one internal format and size.
#[derive(Debug)]
pub struct Renderbuffer {
    gl: Rc<Gl>,
    raw: glow::Renderbuffer,
    internal_format: u32,
    size: UVec2,
}

impl Renderbuffer {
    /// Allocates storage; refuses a zero size or one past
    /// GL_MAX_RENDERBUFFER_SIZE before asking the GL.
    #[allow(unsafe_code)]
    pub fn new(gl: &Rc<Gl>, internal_format: u32, size: UVec2) -> Result<Renderbuffer, GlError> {
        check_size(gl, size)?;
        // SAFETY: creating a name needs only a current context.
        let raw = unsafe { gl.create_renderbuffer() }
            .map_err(|reason| GlError::ObjectCreation { what: "renderbuffer", reason })?;
        let renderbuffer = Renderbuffer { gl: Rc::clone(gl), raw, internal_format, size };
        // SAFETY: `raw` is live and bound; the size was checked against the
        // implementation's maximum, so it fits GLsizei.
        unsafe {
            gl.bind_renderbuffer(glow::RENDERBUFFER, Some(raw));
            gl.renderbuffer_storage(
                glow::RENDERBUFFER,
                internal_format,
                size.x as i32,
                size.y as i32,
            );
        }
        gl_check!(gl)?;
        Ok(renderbuffer)
    }

    /// Width and height of the storage, pixels.
    pub fn size(&self) -> UVec2 {
        self.size
    }

    /// The GL internal format of the storage, such as GL_RGBA8.
    pub fn internal_format(&self) -> u32 {
        self.internal_format
    }
}

owns_gl_object!(Renderbuffer, glow::Renderbuffer, delete_renderbuffer);

/// Refuses sizes the GL would reject, naming the limit.
fn check_size(gl: &Gl, size: UVec2) -> Result<(), GlError> {
    let max = gl.caps().limits.max_renderbuffer_size.max(0) as u32;
    if size.x == 0 || size.y == 0 || size.x > max || size.y > max {
        return Err(GlError::InvalidRequest(format!(
            "render target {}x{} outside 1..={max} (GL_MAX_RENDERBUFFER_SIZE)",
            size.x, size.y
        )));
    }
    Ok(())
}

/// A framebuffer object. It does not own its attachments: whoever attaches a
/// renderbuffer keeps it alive (see `OffscreenTarget`).
#[derive(Debug)]
pub struct Framebuffer {
    gl: Rc<Gl>,
    raw: glow::Framebuffer,
}

impl Framebuffer {
    /// The context this framebuffer belongs to.
    pub fn gl(&self) -> &Gl {
        &self.gl
    }

    /// Creates a framebuffer with no attachments.
    #[allow(unsafe_code)]
    pub fn new(gl: &Rc<Gl>) -> Result<Framebuffer, GlError> {
        // SAFETY: creating a name needs only a current context.
        let raw = unsafe { gl.create_framebuffer() }
            .map_err(|reason| GlError::ObjectCreation { what: "framebuffer", reason })?;
        Ok(Framebuffer { gl: Rc::clone(gl), raw })
    }

    /// Binds this framebuffer for drawing and reading.
    #[allow(unsafe_code)]
    pub fn bind(&self) {
        // SAFETY: `raw` is a live framebuffer of this context.
        unsafe { self.gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.raw)) };
    }

    /// Attaches `renderbuffer` at `attachment` (GL_COLOR_ATTACHMENT0,
    /// GL_DEPTH_ATTACHMENT); leaves this framebuffer bound.
    #[allow(unsafe_code)]
    pub fn attach(&self, attachment: u32, renderbuffer: &Renderbuffer) -> Result<(), GlError> {
        self.bind();
        // SAFETY: both objects are live in this context and the framebuffer
        // is bound; a bad attachment enum only raises a GL error.
        unsafe {
            self.gl.framebuffer_renderbuffer(
                glow::FRAMEBUFFER,
                attachment,
                glow::RENDERBUFFER,
                Some(renderbuffer.raw()),
            )
        };
        gl_check!(self.gl)
    }

    /// Checks completeness of the bound framebuffer; `size` labels the error.
    #[allow(unsafe_code)]
    pub fn check_complete(&self, size: UVec2) -> Result<(), GlError> {
        self.bind();
        // SAFETY: a status query on the bound framebuffer.
        let status = unsafe { self.gl.check_framebuffer_status(glow::FRAMEBUFFER) };
        if status != glow::FRAMEBUFFER_COMPLETE {
            return Err(GlError::FramebufferIncomplete { width: size.x, height: size.y, status });
        }
        Ok(())
    }
}

owns_gl_object!(Framebuffer, glow::Framebuffer, delete_framebuffer);
