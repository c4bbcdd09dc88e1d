//! [`BufferPlan`]: the GPU buffers a backend holds for one pipeline. The
//! pipeline publishes it (`FramePipeline::buffer_plan`), built once from the
//! scene's configuration after any memory budget has shrunk the buffer, and
//! every backend sizes itself from it, so a backend never guesses a size the
//! frame's staging copies do not have.

/// The GPU buffers of one pipeline, bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct BufferPlan {
    /// The buffer the frame's staging copy mirrors: the tile buffer, or
    /// with clusters the cluster vertex buffer (the same size).
    pub buffer_bytes: u32,
    /// With clusters: the cluster index buffer; `None` without clusters.
    pub cluster_index_bytes: Option<u32>,
}

impl BufferPlan {
    /// The plan for a tile buffer of `buffer_bytes` and, with `clusters`,
    /// an index buffer of half its size (whole 4-byte words), as
    /// `pipeline::buffer_copies` counts it.
    pub fn new(buffer_bytes: u32, clusters: bool) -> BufferPlan {
        let cluster_index_bytes = clusters.then_some((buffer_bytes / 2) & !3);
        BufferPlan { buffer_bytes, cluster_index_bytes }
    }
}
