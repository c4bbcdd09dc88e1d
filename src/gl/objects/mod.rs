//! Owner types, one per kind of GL object: each creates its object, frees it
//! on Drop while its context lives, and checks GL errors where it can fail.
//! They hold an `Rc<Gl>`, so they are bound to the context's thread.

/// Gives an owner type its `raw()` name and a Drop that deletes the object
/// while its context lives (after that, destroying the context freed it).
macro_rules! owns_gl_object {
    ($owner:ty, $raw:ty, $delete:ident) => {
        impl $owner {
            /// The GL name, for draw code in the GL layer.
            pub fn raw(&self) -> $raw {
                self.raw
            }
        }

        impl Drop for $owner {
            #[allow(unsafe_code)]
            fn drop(&mut self) {
                if self.gl.is_alive() {
                    // SAFETY: `raw` was created in this context, is never
                    // handed out to another owner, and is deleted only here.
                    unsafe { glow::HasContext::$delete(&**self.gl, self.raw) };
                }
            }
        }
    };
}

mod buffer;
mod framebuffer;
mod program;
mod vertex_array;

pub use buffer::{Buffer, BufferTarget, BufferUsage};
pub use framebuffer::{Framebuffer, Renderbuffer};
pub use program::{Program, Shader};
pub use vertex_array::VertexArray;

use super::error::GlError;

/// Converts a byte count or dimension to the `GLsizei`/`GLsizeiptr` the GL
/// takes, refusing what does not fit rather than wrapping.
fn gl_size(value: usize, what: &str) -> Result<i32, GlError> {
    i32::try_from(value).map_err(|_| {
        GlError::InvalidRequest(format!("{what} {value} exceeds the GL's 2^31-1 limit"))
    })
}
