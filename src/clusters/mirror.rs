//! The frame's tiles as its clusters draw them, read back from the cluster
//! buffers' staging copies: for CPU checks (cracks, the accuracy tool's
//! mirror) that must see what the GPU is given, slot and uniform array
//! included, not the tile cache's blocks the clusters were made from.

use crate::render::cluster::{MAX_MEMBERS, MEMBER_FLOATS};
use crate::render::{DrawList, TileUniforms};
use crate::tiles::block::{write_block, MeshCounts, VERTEX_BYTES};
use crate::tiles::TileBlock;
use crate::tiles::TileVertex;

/// `list`'s tiles rebuilt from its clusters (vertex blocks in `vertices`,
/// index blocks in `indices`): per member, the vertices its indices number
/// and its triangles, in a staging copy of their own, and its uniforms as
/// the shader takes them: from the cluster's uniform array at the slot its
/// vertices carry. Returns the per-tile list and that staging copy; a
/// list drawn tile by tile comes back as it is.
pub fn drawn_tiles(list: &DrawList, vertices: &[u8], indices: &[u8]) -> (DrawList, Vec<u8>) {
    let mut out = list.per_tile();
    let mut staging = Vec::new();
    if !list.clustered() {
        return (out, staging);
    }
    let mut uniforms = [0.0; MAX_MEMBERS * MEMBER_FLOATS];
    for cluster in &list.clusters {
        list.cluster_uniforms(cluster, &mut uniforms);
        for member in list.members_of(cluster) {
            let start = cluster.index_byte_offset as usize + 2 * member.first_index as usize;
            let bytes = &indices[start..start + 2 * member.index_count as usize];
            let numbers: Vec<u32> =
                bytes.chunks_exact(2).map(|b| u16::from_ne_bytes([b[0], b[1]]) as u32).collect();
            let first = numbers.iter().copied().min().unwrap_or(0);
            let last = numbers.iter().copied().max().unwrap_or(0);
            let block = TileBlock::new(
                vertices,
                cluster.base + first * VERTEX_BYTES,
                cluster.base + (last + 1) * VERTEX_BYTES,
                0,
            );
            let own: Vec<TileVertex> = block.vertices().collect();
            let local: Vec<u16> = numbers.iter().map(|&n| (n - first) as u16).collect();
            let counts = MeshCounts {
                vertices: own.len() as u32,
                indices: local.len() as u32,
                skirt_indices: 0,
            };
            let offset = staging.len() as u32;
            staging.resize(staging.len() + counts.block_bytes() as usize, 0);
            write_block(&mut staging[offset as usize..], &own, &local);
            // Its uniforms, from the slot its vertices carry.
            let slot = own.first().map_or(member.slot, |v| v._pad as u8) as usize;
            let u = &uniforms[slot * MEMBER_FLOATS..(slot + 1) * MEMBER_FLOATS];
            let tile = &mut out.tiles[member.tile as usize];
            tile.first_post = [u[0], u[1]];
            tile.vertex_step = u[2];
            tile.skirt_shares = TileUniforms::unpack_skirt_shares(u[3]);
            tile.skirt_slope = TileUniforms::unpack_skirt_slope(u[3]);
            tile.skirt_edges =
                (0..4).filter(|&e| tile.skirt_shares[e] > 0).fold(0, |b, e| b | 1 << e);
            tile.morph = [u[4], u[5]];
            tile.skirt_depth = u[6];
            tile.place = crate::earth::NodePlace {
                centre: [u[11], u[7]],
                offset: [u[8], u[9], u[10]],
                rotation: [u[12], u[13], u[14], u[15]],
                expansion: [u[16], u[17], u[18], u[19], u[20], u[21], u[22], 0.0],
            };
            tile.sub_morph_end = u[23];
            tile.byte_offset = offset;
            tile.index_byte_offset = offset + counts.vertex_bytes();
            tile.index_count = counts.indices;
        }
    }
    (out, staging)
}
