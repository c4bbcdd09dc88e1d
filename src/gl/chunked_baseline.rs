//! [`ChunkedBaseline`]: plain Chunked LOD (Ulrich), the baseline that Polok's
//! batching is measured against by `benches/lod.rs`. It draws the same tiles
//! as the display, with the same shaders, but each tile's vertices live in a
//! vertex buffer of their own: created and uploaded by its own call when the
//! tile first appears, deleted when it is no longer drawn, and bound before
//! each tile's draw. Nothing else differs, so the comparison isolates the
//! one contiguous buffer and the one transfer per frame.

use std::collections::{HashMap, HashSet};
use std::ops::Range;
use std::rc::Rc;

use super::error::GlError;
use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, BufferUsage};
use super::renderer::GlRenderer;
use super::terrain_pass::{TerrainOutput, TerrainPass, TileVertices};
use crate::lod::TileKey;
use crate::render::{check_uploads, CallStats, DrawList, FrameOutput, RenderBackend};
use crate::tiles::vertex::tile_bytes;

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

/// One vertex buffer per drawn tile. A tile regenerated from better data may
/// land at its old offset, so the frame's dirty ranges (what the batched
/// renderer would upload) tell which existing buffers to rewrite.
pub struct ChunkedBaseline {
    gl: Rc<Gl>,
    /// Clear and sky, as the display draws them.
    background: GlRenderer,
    pass: TerrainPass,
    buffers: HashMap<(TileKey, u32), Buffer>,
    wanted: HashSet<(TileKey, u32)>,
    tile_bytes: usize,
    /// What the last frame transferred.
    last: BaselineFrameStats,
}

impl ChunkedBaseline {
    /// The baseline for tiles of `grid_size` cells a side; no tile buffers yet.
    pub fn new(gl: &Rc<Gl>, grid_size: u32) -> Result<ChunkedBaseline, GlError> {
        let tile_bytes = tile_bytes(grid_size);
        Ok(ChunkedBaseline {
            gl: Rc::clone(gl),
            background: GlRenderer::new(gl, grid_size, tile_bytes)?,
            // The pass's own height buffer is unused: one tile's worth.
            pass: TerrainPass::new(gl, grid_size, tile_bytes)?,
            buffers: HashMap::new(),
            wanted: HashSet::new(),
            tile_bytes: tile_bytes as usize,
            last: BaselineFrameStats::default(),
        })
    }

    /// What the last frame transferred.
    pub fn last_frame(&self) -> BaselineFrameStats {
        self.last
    }

    /// Uploads, each by itself, the tiles of `list` that have no buffer yet
    /// or whose bytes lie in the frame's `dirty` ranges of `staging` (the
    /// scene's staging copy); frees the buffers of tiles no longer drawn; and
    /// draws the tiles into the bound target (not cleared).
    fn tiles(
        &mut self,
        list: &DrawList,
        staging: &[u8],
        dirty: &[Range<u32>],
    ) -> Result<BaselineFrameStats, GlError> {
        self.wanted.clear();
        self.wanted.extend(list.tiles.iter().map(|t| (t.key, t.byte_offset)));
        self.buffers.retain(|key, _| self.wanted.contains(key));
        let mut stats = BaselineFrameStats::default();
        for tile in &list.tiles {
            let key = (tile.key, tile.byte_offset);
            let (start, end) = (tile.byte_offset, tile.byte_offset + self.tile_bytes as u32);
            let rewritten = dirty.iter().any(|range| range.start < end && start < range.end);
            if self.buffers.contains_key(&key) && !rewritten {
                continue;
            }
            let bytes = &staging[start as usize..end as usize];
            match self.buffers.get(&key) {
                Some(buffer) => self.upload(buffer, bytes)?,
                None => {
                    let buffer = Buffer::new(
                        &self.gl,
                        BufferTarget::Vertices,
                        self.tile_bytes,
                        BufferUsage::Static,
                    )?;
                    self.upload(&buffer, bytes)?;
                    self.buffers.insert(key, buffer);
                }
            }
            stats.uploads += 1;
            stats.bytes_uploaded += self.tile_bytes as u64;
        }
        let buffers = &self.buffers;
        let buffer_of =
            |tile: &crate::render::TileUniforms| buffers.get(&(tile.key, tile.byte_offset));
        self.pass.draw_from(list, TerrainOutput::Colour, TileVertices::PerTile(&buffer_of))?;
        stats.buffers = self.buffers.len();
        Ok(stats)
    }
}

impl ChunkedBaseline {
    /// One tile's bytes into its own buffer (counted as the GL calls it
    /// makes: an unbound vertex array, a bind, a glBufferSubData).
    fn upload(&self, buffer: &Buffer, bytes: &[u8]) -> Result<(), GlError> {
        buffer.upload_range(0, bytes)?;
        let vertex_arrays = self.gl.caps().vertex_array_objects as u64;
        self.gl.tally(|c| {
            c.vertex_array_binds += vertex_arrays;
            c.buffer_binds += 1;
            c.upload_calls += 1;
            c.bytes_uploaded += bytes.len() as u64;
        });
        Ok(())
    }
}

impl RenderBackend for ChunkedBaseline {
    type Error = GlError;

    fn render(&mut self, frame: &FrameOutput<'_>) -> Result<(), GlError> {
        check_uploads(frame.staging, frame.staging.len() as u32, frame.dirty)?;
        let Some(uniforms) = frame.list.uniforms else { return Ok(()) };
        self.gl.tally(|c| c.frames += 1);
        self.background.draw_background(&uniforms)?;
        self.last = self.tiles(frame.list, frame.staging, frame.dirty)?;
        Ok(())
    }

    fn finish(&mut self) {
        self.background.finish();
    }

    fn take_calls(&mut self) -> CallStats {
        self.gl.take_calls()
    }
}
