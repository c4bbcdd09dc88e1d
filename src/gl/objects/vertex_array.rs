//! [`VertexArray`]: a vertex array object, only on contexts that have them.

use std::rc::Rc;

use glow::HasContext;

use crate::gl::{error::GlError, handle::Gl};

/// A vertex array object. Creation is refused on contexts without VAOs
/// (bare ES 2.0), where draw code sets attributes every pass instead.
#[derive(Debug)]
pub struct VertexArray {
    gl: Rc<Gl>,
    raw: glow::VertexArray,
}

impl VertexArray {
    /// Creates a vertex array; refused on contexts without vertex array objects.
    #[allow(unsafe_code)]
    pub fn new(gl: &Rc<Gl>) -> Result<VertexArray, GlError> {
        if !gl.caps().vertex_array_objects {
            return Err(GlError::InvalidRequest(
                "this context has no vertex array objects (ES 2.0 without OES_vertex_array_object)"
                    .to_owned(),
            ));
        }
        // SAFETY: VAOs are supported (checked above); creating a name needs
        // only a current context.
        let raw = unsafe { gl.create_vertex_array() }
            .map_err(|reason| GlError::ObjectCreation { what: "vertex array", reason })?;
        Ok(VertexArray { gl: Rc::clone(gl), raw })
    }

    /// Binds the vertex array (glBindVertexArray).
    #[allow(unsafe_code)]
    pub fn bind(&self) {
        // SAFETY: `raw` is a live vertex array of this context.
        unsafe { self.gl.bind_vertex_array(Some(self.raw)) };
    }
}

owns_gl_object!(VertexArray, glow::VertexArray, delete_vertex_array);
