//! The GL layer's one error type: every way opening a context, building a GL
//! object or drawing can fail, each naming what failed and why.

use std::fmt;

/// Which stage a shader belongs to, for error messages and [`super::Shader`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaderStage {
    /// The vertex shader.
    Vertex,
    /// The fragment shader.
    Fragment,
}

impl fmt::Display for ShaderStage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ShaderStage::Vertex => "vertex",
            ShaderStage::Fragment => "fragment",
        })
    }
}

/// Why the GL layer failed.
#[derive(Debug, thiserror::Error)]
pub enum GlError {
    /// No window system answered: the window backend cannot run here.
    #[error("no display: {reason}")]
    NoDisplay {
        /// What the window system said.
        reason: String,
    },

    /// A GL library loaded at run time is not installed.
    #[error("library {library} could not be loaded: {reason}")]
    LibraryMissing {
        /// The library's file name.
        library: String,
        /// What the loader said.
        reason: String,
    },

    /// The platform (EGL, OSMesa, the window system) refused a context.
    #[error("{backend} context creation failed: {reason}")]
    ContextCreation {
        /// The context backend that failed: window, EGL or OSMesa.
        backend: &'static str,
        /// What the platform said.
        reason: String,
    },

    /// A shader did not compile; `log` is the driver's info log.
    #[error("{stage} shader `{name}` failed to compile:\n{log}")]
    ShaderCompile {
        /// The shader's name (its source file).
        name: String,
        /// Vertex or fragment.
        stage: ShaderStage,
        /// The driver's info log.
        log: String,
    },

    /// A program did not link; `log` is the driver's info log.
    #[error("program `{name}` failed to link:\n{log}")]
    ProgramLink {
        /// The program's name.
        name: String,
        /// The driver's info log.
        log: String,
    },

    /// glGetError reported `code` at the checked call site.
    #[error("GL error {name} (0x{code:04X}) at {file}:{line}")]
    Gl {
        /// The GL error code glGetError returned.
        code: u32,
        /// The code's GL name, such as `GL_INVALID_OPERATION`.
        name: &'static str,
        /// Source file of the checked call.
        file: &'static str,
        /// Source line of the checked call.
        line: u32,
    },

    /// The driver could not create a GL object (out of names or memory).
    #[error("could not create a GL {what}: {reason}")]
    ObjectCreation {
        /// The kind of object: shader, program, buffer, framebuffer, ...
        what: &'static str,
        /// What the driver said.
        reason: String,
    },

    /// A framebuffer is not complete; `status` is glCheckFramebufferStatus.
    #[error("framebuffer {width}x{height} incomplete: status 0x{status:04X}")]
    FramebufferIncomplete {
        /// Width of the framebuffer, pixels.
        width: u32,
        /// Height of the framebuffer, pixels.
        height: u32,
        /// The glCheckFramebufferStatus value.
        status: u32,
    },

    /// A request the GL cannot represent or the object cannot hold
    /// (zero or oversized dimensions, a range past a buffer's end).
    #[error("invalid request: {0}")]
    InvalidRequest(String),

    /// A request every backend refuses alike (an upload past the buffer).
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
}
