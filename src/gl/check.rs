//! GL error checking at call sites: [`gl_check!`](crate::gl_check) drains
//! glGetError in debug builds and names the file and line that noticed it; in
//! release builds it is `Ok(())` and the optimiser removes it.

use glow::HasContext;

use super::error::GlError;

/// glGetError keeps one flag per error kind; a lost context may keep
/// reporting, so draining stops after this many.
const MAX_DRAINED: usize = 8;

/// Checks the GL error flags of the current context (debug builds only).
///
/// Expands to a `Result<(), GlError>`; use it as `gl_check!(gl)?;` after the
/// calls it guards. `gl` is anything that derefs to a `glow::Context`.
#[macro_export]
macro_rules! gl_check {
    ($gl:expr) => {
        $crate::gl::check::errors_at(&$gl, file!(), line!())
    };
}

/// What [`gl_check!`](crate::gl_check) calls: the first pending error, if any, with
/// the caller's file and line. The rest are drained so the next check starts
/// clean.
#[inline(always)]
pub fn errors_at(gl: &glow::Context, file: &'static str, line: u32) -> Result<(), GlError> {
    if cfg!(debug_assertions) {
        first_error(gl)
            .map_or(Ok(()), |code| Err(GlError::Gl { code, name: error_name(code), file, line }))
    } else {
        Ok(())
    }
}

#[allow(unsafe_code)]
fn first_error(gl: &glow::Context) -> Option<u32> {
    let mut first = None;
    for _ in 0..MAX_DRAINED {
        // SAFETY: glGetError takes no pointers and is valid on any current
        // context; the caller's Gl handle guarantees one is current.
        let code = unsafe { gl.get_error() };
        if code == glow::NO_ERROR {
            break;
        }
        first.get_or_insert(code);
    }
    first
}

/// The GL name of an error code, for messages.
pub fn error_name(code: u32) -> &'static str {
    match code {
        glow::INVALID_ENUM => "GL_INVALID_ENUM",
        glow::INVALID_VALUE => "GL_INVALID_VALUE",
        glow::INVALID_OPERATION => "GL_INVALID_OPERATION",
        glow::INVALID_FRAMEBUFFER_OPERATION => "GL_INVALID_FRAMEBUFFER_OPERATION",
        glow::OUT_OF_MEMORY => "GL_OUT_OF_MEMORY",
        glow::STACK_OVERFLOW => "GL_STACK_OVERFLOW",
        glow::STACK_UNDERFLOW => "GL_STACK_UNDERFLOW",
        glow::CONTEXT_LOST => "GL_CONTEXT_LOST",
        _ => "unknown GL error",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_every_core_error() {
        assert_eq!(error_name(0x0500), "GL_INVALID_ENUM");
        assert_eq!(error_name(0x0502), "GL_INVALID_OPERATION");
        assert_eq!(error_name(0x0505), "GL_OUT_OF_MEMORY");
        assert_eq!(error_name(0x1234), "unknown GL error");
    }
}
