//! The GL layer's one error type: every way opening a context, building a GL
//! object or drawing can fail, each naming what failed and why.

use std::fmt;

/// Which stage a shader belongs to, for error messages and [`super::Shader`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaderStage {
    Vertex,
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

#[derive(Debug, thiserror::Error)]
pub enum GlError {
    /// No window system answered: the window backend cannot run here.
    #[error("no display: {reason}")]
    NoDisplay { reason: String },

    /// A GL library loaded at run time is not installed.
    #[error("library {library} could not be loaded: {reason}")]
    LibraryMissing { library: String, reason: String },

    /// The platform (EGL, OSMesa, the window system) refused a context.
    #[error("{backend} context creation failed: {reason}")]
    ContextCreation { backend: &'static str, reason: String },

    /// A shader did not compile; `log` is the driver's info log.
    #[error("{stage} shader `{name}` failed to compile:\n{log}")]
    ShaderCompile { name: String, stage: ShaderStage, log: String },

    /// A program did not link; `log` is the driver's info log.
    #[error("program `{name}` failed to link:\n{log}")]
    ProgramLink { name: String, log: String },

    /// glGetError reported `code` at the checked call site.
    #[error("GL error {name} (0x{code:04X}) at {file}:{line}")]
    Gl { code: u32, name: &'static str, file: &'static str, line: u32 },

    /// The driver could not create a GL object (out of names or memory).
    #[error("could not create a GL {what}: {reason}")]
    ObjectCreation { what: &'static str, reason: String },

    /// A framebuffer is not complete; `status` is glCheckFramebufferStatus.
    #[error("framebuffer {width}x{height} incomplete: status 0x{status:04X}")]
    FramebufferIncomplete { width: u32, height: u32, status: u32 },

    /// A request the GL cannot represent or the object cannot hold
    /// (zero or oversized dimensions, a range past a buffer's end).
    #[error("invalid request: {0}")]
    InvalidRequest(String),

    /// A request every backend refuses alike (an upload past the buffer).
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
}
