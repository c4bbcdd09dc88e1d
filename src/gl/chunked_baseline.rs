//! [`ChunkedBaseline`]: plain Chunked LOD (Ulrich), the baseline that Polok's
//! batching is measured against by `benches/lod.rs`. It draws the same tiles
//! as the display, with the same shaders, but each tile's block (vertices
//! and indices) lives in a buffer of its own: created and uploaded by its
//! own call when the tile first appears, deleted when it is no longer drawn,
//! and bound (as vertex and as index buffer) before each tile's draw.
//! Nothing else differs, so the comparison isolates the one contiguous
//! buffer and the one transfer per frame.

use std::collections::{HashMap, HashSet};
use std::ops::Range;
use std::rc::Rc;

use super::error::GlError;
use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, BufferUsage};
use super::renderer::GlRenderer;
use super::terrain_pass::{TerrainOutput, TerrainPass, TileBlocks};
use crate::lod::TileKey;
use crate::render::{
    check_uploads, BufferPlan, CallStats, DrawList, FrameOutput, FrameUniforms, RenderBackend,
    TileUniforms,
};
use crate::tiles::grid::tile_bytes;

/// What one baseline frame transferred.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct BaselineFrameStats {
    /// Buffer uploads (one per tile that appeared).
    pub uploads: usize,
    /// Bytes uploaded this frame.
    pub bytes_uploaded: u64,
    /// Vertex buffers alive after the frame.
    pub buffers: usize,
}

/// Where a tile's block is in the scene's staging copy: its key, what
/// names its buffer.
type BlockKey = (TileKey, Range<u32>);

/// One buffer per drawn tile. A tile regenerated from better data may land
/// at its old offset, so the frame's dirty ranges (what the batched renderer
/// would upload) tell which existing buffers to rewrite.
pub struct ChunkedBaseline {
    gl: Rc<Gl>,
    /// Clear and sky, as the display draws them.
    background: GlRenderer,
    pass: TerrainPass,
    buffers: HashMap<BlockKey, Buffer>,
    wanted: HashSet<BlockKey>,
    /// What the last frame transferred.
    last: BaselineFrameStats,
}

impl ChunkedBaseline {
    /// The baseline for tiles of `grid_size` cells a side; no tile buffers yet.
    pub fn new(gl: &Rc<Gl>, grid_size: u32) -> Result<ChunkedBaseline, GlError> {
        // The passes' own tile buffers are unused: one regular tile's worth.
        let tile_bytes = tile_bytes(grid_size);
        Ok(ChunkedBaseline {
            gl: Rc::clone(gl),
            background: GlRenderer::new(gl, &BufferPlan::new(tile_bytes, false))?,
            pass: TerrainPass::new(gl, tile_bytes)?,
            buffers: HashMap::new(),
            wanted: HashSet::new(),
            last: BaselineFrameStats::default(),
        })
    }

    /// What the last frame transferred.
    pub fn last_frame(&self) -> BaselineFrameStats {
        self.last
    }

    /// Uploads, each by itself, the tiles of `list` that have no buffer yet
    /// or whose bytes lie in the frame's `dirty` ranges of `staging` (the
    /// scene's staging copy), and frees the buffers of tiles no longer drawn.
    fn uploads(
        &mut self,
        list: &DrawList,
        staging: &[u8],
        dirty: &[Range<u32>],
    ) -> Result<BaselineFrameStats, GlError> {
        self.wanted.clear();
        self.wanted.extend(list.tiles.iter().map(block_key));
        self.buffers.retain(|key, _| self.wanted.contains(key));
        let mut stats = BaselineFrameStats::default();
        for tile in &list.tiles {
            let key = block_key(tile);
            let block = key.1.clone();
            let rewritten = dirty.iter().any(|r| r.start < block.end && block.start < r.end);
            if self.buffers.contains_key(&key) && !rewritten {
                continue;
            }
            let bytes = &staging[block.start as usize..block.end as usize];
            match self.buffers.get(&key) {
                Some(buffer) => self.upload(buffer, bytes)?,
                None => {
                    let buffer = Buffer::new(
                        &self.gl,
                        BufferTarget::Vertices,
                        bytes.len(),
                        BufferUsage::Static,
                    )?;
                    self.upload(&buffer, bytes)?;
                    self.buffers.insert(key, buffer);
                }
            }
            stats.uploads += 1;
            stats.bytes_uploaded += bytes.len() as u64;
        }
        stats.buffers = self.buffers.len();
        Ok(stats)
    }
}

fn block_key(tile: &TileUniforms) -> BlockKey {
    (tile.key, tile.block_range())
}

impl ChunkedBaseline {
    /// One tile's block into its own buffer (counted as the GL calls it
    /// makes: a bind as vertex buffer, which no vertex array records, and a
    /// glBufferSubData).
    fn upload(&self, buffer: &Buffer, bytes: &[u8]) -> Result<(), GlError> {
        buffer.upload_range(0, bytes)?;
        self.gl.tally(|c| {
            c.buffer_binds += 1;
            c.upload_calls += 1;
            c.bytes_uploaded += bytes.len() as u64;
        });
        Ok(())
    }
}

impl RenderBackend for ChunkedBaseline {
    type Error = GlError;

    fn upload_frame(&mut self, frame: &FrameOutput<'_>) -> Result<(), GlError> {
        check_uploads(frame.staging, frame.staging.len() as u32, frame.dirty)?;
        self.last = self.uploads(frame.list, frame.staging, frame.dirty)?;
        Ok(())
    }

    fn draw_frame(&mut self, list: &DrawList, uniforms: &FrameUniforms) -> Result<(), GlError> {
        self.gl.tally(|c| c.frames += 1);
        self.background.draw_background(uniforms)?;
        let buffers = &self.buffers;
        let buffer_of = |tile: &TileUniforms| buffers.get(&block_key(tile));
        let blocks = TileBlocks::PerTile(&buffer_of);
        self.pass.draw_from(list, uniforms, TerrainOutput::Colour, blocks)
    }

    fn finish(&mut self) {
        self.background.finish();
    }

    fn take_calls(&mut self) -> CallStats {
        self.gl.take_calls()
    }
}
