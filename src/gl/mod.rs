//! The thin GL layer: the only place with OpenGL calls and FFI. It opens
//! contexts (window, headless EGL, OSMesa), owns GL objects through one type
//! per kind that frees it on Drop, and checks GL errors with file and line in
//! debug builds.
//!
//! | file | owns |
//! |---|---|
//! | `context` | [`GlContext`]: backend choice, info strings, render target, read-back |
//! | `caps` | [`Capabilities`]: features detected from version and extensions |
//! | `egl`, `osmesa`, `window` | the platform contexts |
//! | `probe` | whether a window system answers (for `--backend auto`) |
//! | `handle` | [`Gl`]: the shared function table and the context's liveness |
//! | `objects` | owner types: [`Buffer`], [`Shader`], [`Program`], [`Renderbuffer`], [`Framebuffer`], [`VertexArray`] |
//! | `offscreen` | [`OffscreenTarget`] and pixel read-back |
//! | `calls` | `Calls`: every call of the display's passes, counted by kind as it is made |
//! | `check` | [`gl_check!`](crate::gl_check) |
//! | `smoke` | `SmokePass`: clear and one triangle, proving a context draws (the context tests'; feature `test-support`) |
//! | `terrain_pass`, `sky_pass` | the terrain tiles (heights as attributes, transforms as uniforms) and the sky |
//! | `symbol_pass` | the reference symbols and the failure flag, one draw of a [`SymbolMesh`](crate::symbology::SymbolMesh) |
//! | `chunked_baseline` | `ChunkedBaseline`: plain Chunked LOD, a vertex buffer and an upload per tile (the bench's baseline; feature `test-support`) |
//! | `truth_pass` | [`TruthPass`]: the brute-force ground truth, every level-0 post drawn with the terrain shaders |
//! | `renderer` | [`GlRenderer`]: the GL [`RenderBackend`](crate::render::RenderBackend) |
//!
//! unsafe here is allowed per item, each block with a `// SAFETY:` comment.

mod calls;
mod caps;
pub mod check;
#[cfg(feature = "test-support")]
mod chunked_baseline;
mod context;
mod egl;
mod error;
mod handle;
mod objects;
mod offscreen;
mod osmesa;
pub mod probe;
mod renderer;
mod sky_pass;
#[cfg(feature = "test-support")]
mod smoke;
mod symbol_pass;
mod terrain_pass;
mod truth_pass;
mod window;

pub use caps::{Capabilities, GlApi, GlesVersion, Limits, ReportedVersion};
#[cfg(feature = "test-support")]
pub use chunked_baseline::{BaselineFrameStats, ChunkedBaseline};
pub use context::{ContextRequest, GlBackend, GlContext, GlInfo, OpenedBackend};
pub use error::{GlError, ShaderStage};
pub use handle::Gl;
pub use objects::{
    Buffer, BufferTarget, BufferUsage, Framebuffer, Program, Renderbuffer, Shader, VertexArray,
};
pub use offscreen::OffscreenTarget;
pub use renderer::GlRenderer;
#[cfg(feature = "test-support")]
pub use smoke::{SmokePass, SMOKE_TRIANGLE};
pub use terrain_pass::TerrainOutput;
pub use truth_pass::{
    TruthChunk, TruthError, TruthFrameStats, TruthMesh, TruthPass, TruthRegion, CHUNK_CELLS,
    CHUNK_TRIANGLES, MAX_TRUTH_POSTS, MAX_TRUTH_SIDE,
};
pub use window::WindowEvents;
