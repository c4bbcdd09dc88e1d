//! The brute-force ground truth: every level-0 post of a region drawn as a
//! vertex, with no LOD, no morph, no skirts and no culling, by the terrain
//! pass itself. Each chunk of the [`TruthMesh`] is a tile of
//! [`CHUNK_CELLS`] cells whose morph never starts and whose skirts hang 0 m
//! (so they have no area); its south-west post is numbered from the frame's
//! anchor post, exactly as tiles are placed, and the frame uniforms are the
//! scene's, so an image of it compares pixel for pixel with
//! the LOD image. Chunks are drawn nearest first, as the display's tiles
//! are, so that both get the same early depth rejection.
//!
//! The accuracy tool (`display::measure`) draws it into the display's own
//! context (clear and sky as the display does, then this pass).

mod mesh;

pub use mesh::{
    TruthChunk, TruthError, TruthMesh, TruthRegion, CHUNK_CELLS, CHUNK_TRIANGLES, MAX_TRUTH_POSTS,
    MAX_TRUTH_SIDE,
};

use std::rc::Rc;

use super::error::GlError;
use super::handle::Gl;
use super::terrain_pass::{TerrainOutput, TerrainPass};
use crate::earth::NodePlace;
use crate::lod::TileKey;
use crate::render::{DrawList, FrameUniforms, TileUniforms};
use crate::tiles::block::write_block;
use crate::tiles::{MeshCounts, TileGrid};

/// `u_morph` that never morphs: the factor is 0 at every distance a frame can have.
const NO_MORPH: [f32; 2] = [1e30, 2e30];

/// What drawing the truth cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TruthFrameStats {
    /// Surface triangles (the chunks' zero-depth skirts are submitted too).
    pub triangles: u64,
    /// Draw calls: one per chunk.
    pub draw_calls: usize,
    /// Clear, sky and every chunk, measured up to glFinish.
    pub frame_ms: f64,
}

struct ChunkDraw {
    key: TileKey,
    /// South-west level-0 post (numbered from the frame's anchor per frame).
    first_post: [i64; 2],
    /// Where the chunk's block (its vertices) starts in the tile buffer.
    byte_offset: u32,
    /// Where its indices start there.
    index_byte_offset: u32,
    /// Its indices: the grid's, skirts included, then its curtains'.
    index_count: u32,
    /// Some posts have no data.
    no_data: bool,
}

/// The truth mesh on the GPU, drawn by a terrain pass of its own.
pub struct TruthPass {
    terrain: TerrainPass,
    chunks: Vec<ChunkDraw>,
    triangles: u64,
}

impl TruthPass {
    /// Uploads `mesh` into the tile buffer of a terrain pass, a block per
    /// chunk laid out as a regular tile of [`CHUNK_CELLS`] cells.
    pub fn new(gl: &Rc<Gl>, mesh: &TruthMesh) -> Result<TruthPass, GlError> {
        let grid = TileGrid::new(CHUNK_CELLS);
        // A chunk's block: the grid's, then its curtains' feet and triangles.
        let counts_of = |chunk: &TruthChunk| MeshCounts {
            vertices: chunk.vertices.len() as u32,
            indices: (grid.indices.len() + chunk.curtains.len()) as u32,
            skirt_indices: 0,
        };
        let bytes: u64 = mesh.chunks.iter().map(|c| counts_of(c).block_bytes() as u64).sum();
        let too_large =
            || GlError::InvalidRequest(format!("truth mesh of {bytes} bytes exceeds 2^32-1"));
        let terrain = TerrainPass::new(gl, u32::try_from(bytes).map_err(|_| too_large())?)?;
        let (mut block, mut indices) = (Vec::new(), Vec::new());
        let mut chunks = Vec::with_capacity(mesh.chunks.len());
        let mut byte_offset = 0u32;
        for chunk in &mesh.chunks {
            let counts = counts_of(chunk);
            debug_assert!(counts.vertices <= 1 << 16);
            block.resize(counts.block_bytes() as usize, 0);
            indices.clear();
            indices.extend_from_slice(&grid.indices);
            indices.extend_from_slice(&chunk.curtains);
            write_block(&mut block, &chunk.vertices, &indices);
            terrain.upload_at(byte_offset, &block)?;
            chunks.push(ChunkDraw {
                key: TileKey::new(
                    0,
                    chunk.first_post[0] / CHUNK_CELLS,
                    chunk.first_post[1] / CHUNK_CELLS,
                ),
                first_post: mesh.chunk_first_post(chunk),
                byte_offset,
                index_byte_offset: byte_offset + counts.vertex_bytes(),
                index_count: counts.indices,
                no_data: chunk.no_data,
            });
            byte_offset += counts.block_bytes();
        }
        Ok(TruthPass { terrain, chunks, triangles: mesh.triangles() })
    }

    /// Surface triangles drawn per frame (all of them: nothing is culled).
    pub fn triangles(&self) -> u64 {
        self.triangles
    }

    /// Draw calls per frame: one per chunk.
    pub fn draw_calls(&self) -> usize {
        self.chunks.len()
    }

    /// Draws every chunk into the bound target with `frame`'s uniforms
    /// (whose post numbering places the chunks relative to the camera),
    /// writing `output`. Sets the terrain pass's state; does not clear.
    pub fn draw(&self, frame: &FrameUniforms, output: TerrainOutput) -> Result<(), GlError> {
        // One place for every chunk (the anchor's, next to the camera): the
        // chunks share their edge posts bit for bit, with f32 rounding of
        // 1e-7 of the distance (a centimetre at 100 km) on the ellipsoid.
        let place = frame.earth.map_or(NodePlace::default(), |e| e.place(frame.posts.anchor));
        let tiles = self
            .chunks
            .iter()
            .map(|chunk| TileUniforms {
                key: chunk.key,
                first_post: frame.posts.number(chunk.first_post),
                post_step: 1.0,
                vertex_step: 1.0,
                morph: NO_MORPH,
                sub_morph_end: 0.0,
                skirt_depth: 0.0,
                skirt_edges: 0,
                skirt_shares: [0; 4],
                skirt_slope: f32::INFINITY,
                byte_offset: chunk.byte_offset,
                index_byte_offset: chunk.index_byte_offset,
                index_count: chunk.index_count,
                no_data: chunk.no_data,
                place,
                ground: None,
            })
            .collect();
        let mut list = DrawList::default();
        (list.uniforms, list.tiles, list.grid_size) = (Some(*frame), tiles, CHUNK_CELLS);
        // As the display does: a fair brute force gets early z too.
        list.sort_front_to_back(CHUNK_CELLS);
        self.terrain.draw(&list, frame, output)
    }
}
