//! A tile's block in the allocator: everything the GPU needs to draw the
//! tile, so tiles may differ in vertex count, positions and triangles.
//!
//! Layout, from the block's start (4-aligned):
//! 1. the tile's vertices, [`TileVertex`] (20 bytes each);
//! 2. right after them, its triangles as 16-bit indices into those
//!    vertices, counter-clockwise seen from above;
//! 3. zero bytes up to the next multiple of 4.
//!
//! The one GPU buffer the blocks live in is bound both as vertex and as
//! index buffer; a tile is drawn with its attribute pointers at the block's
//! start and `glDrawElements` from its first index.

/// One vertex of a tile's block, 20 bytes: where it is in the tile, whether
/// it hangs from an edge as skirt, and the surface there (this level's and
/// the parent level's height and normal). Positions are post numbers, so a
/// vertex two tiles share gets the same bits from both.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TileVertex {
    /// Post column and row from the tile's south-west post, in units of the
    /// tile's post step (`TileUniforms::post_step` level-0 posts): 0 to
    /// `grid_size` each (`a_grid.xy` in the shader).
    pub post: [u16; 2],
    /// Bits 0 to 2: the edge a skirt vertex hangs from, 1 south, 2 east,
    /// 3 north, 4 west (lowered by the tile's skirt depth when that edge
    /// hangs a skirt), 5 a curtain's foot, or 0 for a vertex of the
    /// surface ([`Self::edge`]); bits 3 up: the morph band it follows
    /// ([`Self::band`]). `a_grid.z` in the shader.
    pub skirt: u16,
    /// 0 in a tile's block; in a cluster's block (`crate::clusters`) the
    /// member slot that selects the tile's uniforms (`a_grid.w`). Aligns the
    /// heights to 4 bytes.
    pub _pad: u16,
    /// Height of this level's surface, metres ([`super::NO_DATA`] where the
    /// data have none).
    pub height: f32,
    /// Height of the parent level's surface here, metres: the morph target.
    pub target: f32,
    /// Unit normals, x and y scaled to -127..127 (z is positive, derived):
    /// this level's, then the parent level's.
    pub normal: [i8; 4],
}

impl TileVertex {
    /// The low bits of [`Self::skirt`] that hold the edge code.
    pub const EDGE_MASK: u16 = 7;

    /// The edge code of [`Self::skirt`] (0 on the surface).
    pub fn edge(&self) -> u16 {
        self.skirt & Self::EDGE_MASK
    }

    /// The morph band it follows: 0 the tile's level's morph toward the
    /// level above, `k >= 1` sub-level `k`'s toward sub-level `k - 1`
    /// (`crate::lod::morph::band_range`).
    pub fn band(&self) -> u8 {
        (self.skirt >> 3) as u8
    }

    /// This vertex with edge code `edge`, its band kept.
    pub fn with_edge(self, edge: u16) -> TileVertex {
        debug_assert!(edge <= Self::EDGE_MASK);
        TileVertex { skirt: (self.skirt & !Self::EDGE_MASK) | edge, ..self }
    }

    /// The `skirt` field of a surface vertex of morph band `band`.
    pub fn surface_code(band: u8) -> u16 {
        (band as u16) << 3
    }

    /// This vertex with the surface `height`, `target` and `normal`, its
    /// position kept.
    pub fn with_surface(self, height: f32, target: f32, normal: [i8; 4]) -> TileVertex {
        TileVertex { height, target, normal, ..self }
    }

    /// This vertex with `other`'s surface, its own position kept.
    pub fn with_surface_of(self, other: TileVertex) -> TileVertex {
        self.with_surface(other.height, other.target, other.normal)
    }
}

/// Bytes of one [`TileVertex`].
pub const VERTEX_BYTES: u32 = std::mem::size_of::<TileVertex>() as u32;
/// Byte offset of [`TileVertex::height`] (then `target`) in a vertex.
pub const HEIGHT_OFFSET: u32 = std::mem::offset_of!(TileVertex, height) as u32;
/// Byte offset of [`TileVertex::normal`] in a vertex.
pub const NORMAL_OFFSET: u32 = std::mem::offset_of!(TileVertex, normal) as u32;
/// Bytes of one index.
pub const INDEX_BYTES: u32 = std::mem::size_of::<u16>() as u32;
/// Blocks start and end on multiples of this many bytes.
pub const BLOCK_ALIGNMENT: u32 = 4;

/// How many vertices and indices a tile's mesh has: what sizes its block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshCounts {
    /// Vertices, skirts included (at most 2^16: indices are 16-bit).
    pub vertices: u32,
    /// Indices, three per triangle, skirts included.
    pub indices: u32,
    /// Of those, the skirts' (0 where not counted: a grid's).
    pub skirt_indices: u32,
}

impl MeshCounts {
    /// Bytes of the vertices: where the indices start in the block.
    pub fn vertex_bytes(self) -> u32 {
        self.vertices * VERTEX_BYTES
    }

    /// Bytes of the whole block: vertices, indices, padding.
    pub fn block_bytes(self) -> u32 {
        (self.vertex_bytes() + self.indices * INDEX_BYTES).next_multiple_of(BLOCK_ALIGNMENT)
    }

    /// Triangles drawn, skirts included.
    pub fn triangles(self) -> u32 {
        self.indices / 3
    }
}

/// Writes `vertices`, then `indices`, then zero padding into `block`, whose
/// length must be their [`MeshCounts::block_bytes`].
pub fn write_block(block: &mut [u8], vertices: &[TileVertex], indices: &[u16]) {
    let (vertex_bytes, rest) = block.split_at_mut(vertices.len() * VERTEX_BYTES as usize);
    let (index_bytes, padding) = rest.split_at_mut(indices.len() * INDEX_BYTES as usize);
    debug_assert!(padding.len() < BLOCK_ALIGNMENT as usize);
    vertex_bytes.copy_from_slice(bytemuck::cast_slice(vertices));
    index_bytes.copy_from_slice(bytemuck::cast_slice(indices));
    padding.fill(0);
}

/// A tile's block read back from the staging copy (byte for byte what the
/// GPU holds): its vertices and triangles, for the CPU mirrors of the drawn
/// surface.
#[derive(Clone, Copy, Debug)]
pub struct TileBlock<'a> {
    vertices: &'a [u8],
    indices: &'a [u8],
}

impl<'a> TileBlock<'a> {
    /// The block in `staging` whose vertices start at `vertex_offset` and
    /// whose `index_count` indices start at `index_offset` (bytes).
    pub fn new(
        staging: &'a [u8],
        vertex_offset: u32,
        index_offset: u32,
        index_count: u32,
    ) -> TileBlock<'a> {
        let index_end = index_offset + index_count * INDEX_BYTES;
        TileBlock {
            vertices: &staging[vertex_offset as usize..index_offset as usize],
            indices: &staging[index_offset as usize..index_end as usize],
        }
    }

    /// Vertices, skirts included.
    pub fn vertex_count(&self) -> usize {
        self.vertices.len() / VERTEX_BYTES as usize
    }

    /// Vertex `k`.
    pub fn vertex(&self, k: usize) -> TileVertex {
        let at = k * VERTEX_BYTES as usize;
        bytemuck::pod_read_unaligned(&self.vertices[at..at + VERTEX_BYTES as usize])
    }

    /// Every vertex in block order.
    pub fn vertices(&self) -> impl Iterator<Item = TileVertex> + '_ {
        (0..self.vertex_count()).map(|k| self.vertex(k))
    }

    /// Triangles, skirts included.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / (3 * INDEX_BYTES as usize)
    }

    /// The vertex numbers of triangle `t`, counter-clockwise from above.
    pub fn triangle(&self, t: usize) -> [u16; 3] {
        let at = 3 * t * INDEX_BYTES as usize;
        let bytes = &self.indices[at..at + 3 * INDEX_BYTES as usize];
        bytemuck::pod_read_unaligned(bytes)
    }

    /// Whether triangle `t` is part of a skirt (touches a skirt vertex).
    pub fn is_skirt(&self, t: usize) -> bool {
        self.triangle(t).iter().any(|&v| self.vertex(v as usize).edge() != 0)
    }

    /// Triangles of the surface, skirts left out.
    pub fn surface_triangle_count(&self) -> usize {
        (0..self.triangle_count()).filter(|&t| !self.is_skirt(t)).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_block_is_its_vertices_then_its_indices_padded_to_four_bytes() {
        assert_eq!((VERTEX_BYTES, HEIGHT_OFFSET, NORMAL_OFFSET), (20, 8, 16));
        let counts = MeshCounts { vertices: 3, indices: 3, skirt_indices: 0 };
        assert_eq!((counts.vertex_bytes(), counts.block_bytes()), (60, 68));
        let vertex = |i: u16, skirt: u16| TileVertex {
            post: [i, 1],
            skirt,
            height: i as f32,
            target: 2.0,
            normal: [1, 2, 3, 4],
            ..TileVertex::default()
        };
        let vertices = [vertex(0, 0), vertex(1, 0), vertex(2, 3)];
        let mut staging = vec![0xffu8; 8 + counts.block_bytes() as usize];
        write_block(&mut staging[8..], &vertices, &[0, 1, 2]);
        assert_eq!(&staging[8 + 66..], &[0, 0], "padding is zeroed");
        let block = TileBlock::new(&staging, 8, 8 + counts.vertex_bytes(), 3);
        assert_eq!(block.vertices().collect::<Vec<_>>(), vertices);
        assert_eq!((block.triangle_count(), block.triangle(0)), (1, [0, 1, 2]));
        assert!(block.is_skirt(0));
        assert_eq!(block.surface_triangle_count(), 0);
    }
}
