//! The GL-free half of drawing: what a frame must upload and draw, expressed
//! as plain data that a backend consumes. The GL backend turns it into calls;
//! the [`null::NullBackend`] only counts them, so tests can check what would
//! be drawn without any context.

pub mod draw_list;
pub mod null;
pub mod palette;

pub use draw_list::{DepthSlices, DrawList, FrameUniforms, PostFrame, TileUniforms};
pub use null::NullBackend;

use std::ops::Range;

/// What a renderer does with a frame's data. Implemented by the GL layer and
/// by the counting null backend.
pub trait RenderBackend {
    type Error: std::error::Error;
    /// Copies `ranges` of `staging` into the GPU vertex buffer at the same
    /// offsets: one transfer per range.
    fn upload(&mut self, staging: &[u8], ranges: &[Range<u32>]) -> Result<(), Self::Error>;
    /// Clears, draws the sky and the terrain tiles of `list`.
    fn draw(&mut self, list: &DrawList) -> Result<(), Self::Error>;
}
