//! The GL-free half of drawing: what a frame must upload and draw, expressed
//! as plain data that a backend consumes. The GL backend turns it into calls;
//! the [`null::NullBackend`] only counts them, so tests can check what would
//! be drawn without any context.

pub mod cluster;
pub mod cluster_draws;
pub mod cost;
pub mod draw_list;
pub mod null;
pub mod palette;
pub mod plan;

#[cfg(feature = "test-support")]
pub use cluster::ClusterMorph;
pub use cluster::{Cluster, ClusterOrder, ClusterRun, Member};
pub use cost::{CallStats, CostModel};
pub use draw_list::{
    ClusterDraws, DepthSlices, DrawList, DrawnTile, FrameUniforms, PostFrame, Slice, TileUniforms,
};
pub use null::NullBackend;
pub use plan::BufferPlan;

use std::ops::Range;

use crate::symbology::SymbolMesh;

/// What a frame hands its backend: the draw list, the staging copy the GPU
/// buffer mirrors, and the ranges of it this frame changed.
#[derive(Clone, Copy, Debug)]
pub struct FrameOutput<'a> {
    /// What to draw.
    pub list: &'a DrawList,
    /// The tile allocator's staging copy.
    pub staging: &'a [u8],
    /// The byte ranges of `staging` written since the last frame: one
    /// transfer each.
    pub dirty: &'a [Range<u32>],
    /// With clusters: the index buffer's staging copy and its ranges to
    /// upload (the buffer `staging` mirrors then holds only vertices).
    pub indices: Option<(&'a [u8], &'a [Range<u32>])>,
}

/// What a renderer does with a frame. Implemented by the GL renderer, the
/// plain Chunked LOD baseline and the counting null backend; the frame
/// pipeline drives any of them.
pub trait RenderBackend {
    /// What can go wrong; an upload past the buffer is [`RenderError`] in
    /// every backend.
    type Error: std::error::Error + From<RenderError>;
    /// Uploads the frame's dirty ranges (and, with clusters, its index
    /// ranges) into the backend's buffers.
    fn upload_frame(&mut self, frame: &FrameOutput<'_>) -> Result<(), Self::Error>;
    /// Clears, draws the sky and `list`'s terrain, for the frame whose
    /// uniforms are `uniforms`.
    fn draw_frame(&mut self, list: &DrawList, uniforms: &FrameUniforms) -> Result<(), Self::Error>;
    /// Uploads, then draws the frame. The one place that decides that a
    /// draw list built for no frame (no uniforms) draws nothing: no clear,
    /// no sky, no frame counted; its uploads still go.
    fn render(&mut self, frame: &FrameOutput<'_>) -> Result<(), Self::Error> {
        self.upload_frame(frame)?;
        match &frame.list.uniforms {
            Some(uniforms) => self.draw_frame(frame.list, uniforms),
            None => Ok(()),
        }
    }
    /// Waits until the frame is drawn (glFinish), so frame times are whole.
    fn finish(&mut self) {}
    /// The calls issued since the last take, and a new count from zero.
    fn take_calls(&mut self) -> CallStats;
}

/// A backend that also draws the reference symbols over a frame, and the
/// frame without terrain that stale data call for. The GL renderer and the
/// counting null backend implement it.
pub trait SymbolBackend: RenderBackend {
    /// Draws `symbols` over the frame just rendered (before
    /// [`RenderBackend::finish`]).
    fn draw_symbols(&mut self, symbols: &SymbolMesh) -> Result<(), Self::Error>;
    /// Draws a frame with no terrain and no sky: the target cleared to
    /// [`crate::symbology::flag::WITHDRAWN_CLEAR`] and `flag` (laid out
    /// for the frame's viewport) over it.
    fn render_withdrawn(&mut self, flag: &SymbolMesh) -> Result<(), Self::Error>;
}

/// Errors every backend reports the same way.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RenderError {
    /// An upload range reaches past the GPU buffer or the staging copy.
    #[error(
        "upload of bytes {start}..{end} past the buffer ({capacity} bytes, staging {staging})"
    )]
    UploadPastBuffer {
        /// First byte of the range.
        start: u32,
        /// One past its last byte.
        end: u32,
        /// Bytes of the GPU buffer.
        capacity: u32,
        /// Bytes of the staging copy.
        staging: usize,
    },
    /// A frame with clusters on a backend whose [`BufferPlan`] has none.
    #[error("clusters drawn by a backend whose buffer plan has no cluster index buffer")]
    ClustersNotPlanned,
}

/// Refuses `ranges` that reach past a GPU buffer of `capacity` bytes or
/// past `staging`. Both backends check their uploads with this.
pub fn check_uploads(
    staging: &[u8],
    capacity: u32,
    ranges: &[Range<u32>],
) -> Result<(), RenderError> {
    for range in ranges {
        if range.end > capacity || range.end as usize > staging.len() || range.start > range.end {
            return Err(RenderError::UploadPastBuffer {
                start: range.start,
                end: range.end,
                capacity,
                staging: staging.len(),
            });
        }
    }
    Ok(())
}
