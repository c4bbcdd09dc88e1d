//! [`Buffer`]: a vertex or index buffer of fixed size, written in ranges.

use std::rc::Rc;

use glow::HasContext;

use super::gl_size;
use crate::gl::{error::GlError, handle::Gl};
use crate::gl_check;

/// Where a buffer binds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferTarget {
    /// Vertex attributes (GL_ARRAY_BUFFER).
    Vertices,
    /// Indices (GL_ELEMENT_ARRAY_BUFFER).
    Indices,
}

impl BufferTarget {
    pub(crate) fn gl_enum(self) -> u32 {
        match self {
            BufferTarget::Vertices => glow::ARRAY_BUFFER,
            BufferTarget::Indices => glow::ELEMENT_ARRAY_BUFFER,
        }
    }
}

/// How often the contents change, as a hint to the driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferUsage {
    /// Written once, drawn many times.
    Static,
    /// Rewritten in ranges now and then (the tile cache).
    Dynamic,
    /// Rewritten every frame.
    Stream,
}

impl BufferUsage {
    pub(crate) fn gl_enum(self) -> u32 {
        match self {
            BufferUsage::Static => glow::STATIC_DRAW,
            BufferUsage::Dynamic => glow::DYNAMIC_DRAW,
            BufferUsage::Stream => glow::STREAM_DRAW,
        }
    }
}

/// A GL buffer object with storage of `size` bytes allocated up front.
#[derive(Debug)]
pub struct Buffer {
    gl: Rc<Gl>,
    raw: glow::Buffer,
    target: BufferTarget,
    /// Bytes of storage; fixed for the buffer's life.
    size: usize,
}

impl Buffer {
    /// Creates a buffer with `size` bytes of undefined contents.
    #[allow(unsafe_code)]
    pub fn new(
        gl: &Rc<Gl>,
        target: BufferTarget,
        size: usize,
        usage: BufferUsage,
    ) -> Result<Buffer, GlError> {
        let gl_bytes = gl_size(size, "buffer size")?;
        // SAFETY: creating a name needs only a current context.
        let raw = unsafe { gl.create_buffer() }
            .map_err(|reason| GlError::ObjectCreation { what: "buffer", reason })?;
        // Owned from here on, so an error below frees the name.
        let buffer = Buffer { gl: Rc::clone(gl), raw, target, size };
        buffer.bind();
        // SAFETY: `raw` is bound to `target`; a null-data glBufferData of a
        // size checked to fit GLsizeiptr only allocates.
        unsafe { gl.buffer_data_size(target.gl_enum(), gl_bytes, usage.gl_enum()) };
        gl_check!(gl)?;
        Ok(buffer)
    }

    /// Bytes of storage.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Vertex attributes or indices: the target it binds to.
    pub fn target(&self) -> BufferTarget {
        self.target
    }

    /// Binds the buffer to its target. For index buffers the vertex array
    /// bound at the time records the binding.
    pub fn bind(&self) {
        self.bind_to(self.target);
    }

    /// Binds the buffer to `target`, which may be the other one than it was
    /// made for: OpenGL ES lets one buffer hold vertices and indices (a
    /// tile's block) and be bound as both. The vertex array bound at the
    /// time records an index binding.
    #[allow(unsafe_code)]
    pub fn bind_to(&self, target: BufferTarget) {
        // SAFETY: `raw` is a live buffer name of this context.
        unsafe { self.gl.bind_buffer(target.gl_enum(), Some(self.raw)) };
    }

    /// Writes `bytes` at `offset` (glBufferSubData). Refuses a range past the
    /// end instead of letting the GL raise GL_INVALID_VALUE. Index uploads
    /// unbind any vertex array first so they cannot rewire one.
    #[allow(unsafe_code)]
    pub fn upload_range(&self, offset: usize, bytes: &[u8]) -> Result<(), GlError> {
        let end = offset.checked_add(bytes.len()).filter(|&end| end <= self.size);
        if end.is_none() {
            return Err(GlError::InvalidRequest(format!(
                "upload of {} bytes at offset {offset} overruns a buffer of {} bytes",
                bytes.len(),
                self.size
            )));
        }
        if self.target == BufferTarget::Indices && self.gl.caps().vertex_array_objects {
            // SAFETY: binding vertex array 0 is always valid where VAOs exist.
            unsafe { self.gl.bind_vertex_array(None) };
        }
        self.bind();
        // The range check above bounds offset by size, which fits i32.
        let gl_offset = gl_size(offset, "buffer offset")?;
        // SAFETY: the buffer is bound and [offset, offset + len) lies inside
        // its storage; glow passes the slice's pointer and length.
        unsafe { self.gl.buffer_sub_data_u8_slice(self.target.gl_enum(), gl_offset, bytes) };
        gl_check!(self.gl)
    }
}

owns_gl_object!(Buffer, glow::Buffer, delete_buffer);
