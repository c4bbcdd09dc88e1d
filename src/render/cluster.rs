//! Cluster draws (Judnich & Ling's batches): what the GL terrain pass and the
//! cost model need to draw a frame's clusters, each of up to 16 tiles, with
//! one glDrawElements per cluster and depth slice.
//!
//! A cluster's vertex block (made by `crate::clusters`) holds its member
//! tiles' vertices one after another, each vertex carrying its member's
//! slot; its index block one list of 16-bit indices numbered from the
//! cluster's attribute base ([`Cluster::base`]): the start of the
//! [`window`] its vertex block lies in. Windows are fixed for the buffer's
//! life, so the GL pass gives each its own vertex array object, its
//! attribute pointers set once when the pass is made, and a change of base
//! is a vertex array bind (without vertex array objects, three pointers;
//! clusters of one window share them either way). The vertex
//! shader takes the member's placement, morph and skirts from
//! `u_members[6 slot]` to `u_members[6 slot + 5]` (a uniform array indexed
//! by a vertex attribute: GLSL ES 1.00 allows it in vertex shaders).

use crate::tiles::block::VERTEX_BYTES;
use std::ops::Range;

/// Most tiles a cluster holds: the 16 of a two-level cluster.
pub const MAX_MEMBERS: usize = 16;

/// Vertices of one window: all that 16-bit indices reach from its start.
pub const WINDOW_VERTICES: u32 = 1 << 16;

/// Bytes from one window's start to the next: its vertices, then one
/// vertex of fence that no block may take, so no block crosses into the
/// next window.
pub const WINDOW_STRIDE: u32 = (WINDOW_VERTICES + 1) * VERTEX_BYTES;

/// Window `k` of a cluster vertex buffer of `capacity` bytes: the bytes
/// blocks may take (every one of them within 2^16 vertices of its start,
/// the attribute base of the clusters placed there). The last window may
/// be shorter; `None` past the buffer.
pub fn window(k: u32, capacity: u32) -> Option<Range<u32>> {
    let start = k.checked_mul(WINDOW_STRIDE).filter(|&s| s < capacity)?;
    let end = start.saturating_add(WINDOW_VERTICES * VERTEX_BYTES).min(capacity);
    Some(start..end - (end - start) % VERTEX_BYTES)
}

/// How many windows a cluster vertex buffer of `capacity` bytes has.
pub fn window_count(capacity: u32) -> u32 {
    capacity.div_ceil(WINDOW_STRIDE)
}

/// The window holding byte `offset`.
pub fn window_of(offset: u32) -> u32 {
    offset / WINDOW_STRIDE
}

/// Floats of one member's uniforms: six vec4 (placement, morph and
/// skirts; the node's place on the ellipsoid; a projected grid's node
/// series). Sixteen members take 96 of GLES 2.0's 128 vertex uniform
/// vectors; the frame's take 8 more.
pub const MEMBER_FLOATS: usize = 24;

/// Which morph range each member of a cluster takes (feature
/// `test-support`: only tests choose).
#[cfg(feature = "test-support")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum ClusterMorph {
    /// Its own tile's (what per-tile drawing does): the right one.
    #[default]
    PerMember,
    /// The first member's, for every member: deliberately broken, so
    /// tests can show that the crack and pop tests catch a wrong cluster
    /// morph (members of two levels then morph over one level's range).
    FirstMember,
}

/// In which order a frame's clusters are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum ClusterOrder {
    /// Grouped by attribute base (each base's pointers set once a part),
    /// the groups by their nearest cluster, nearest first within a group.
    #[default]
    ByBase,
    /// Nearest first (by each cluster's nearest member), as tiles are:
    /// early depth rejection, at the price of more pointer changes.
    NearestFirst,
}

/// One cluster of the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cluster {
    /// Byte offset, in the GPU buffer, of vertex 0 of its indices: where
    /// its attribute pointers point, the start of its [`window`].
    pub base: u32,
    /// Byte offset of its first index.
    pub index_byte_offset: u32,
    /// Its first member in [`super::DrawList::members`] (its members follow in
    /// block order).
    pub first_member: u32,
    /// How many members it has (1 to [`MAX_MEMBERS`]).
    pub member_count: u32,
    /// Some member has posts without data: drawn by the no-data program.
    pub no_data: bool,
    /// The parts of the terrain pass it is drawn in ([`super::cluster_draws::part_bit`]).
    pub parts: u8,
}

/// One member tile of a cluster.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Member {
    /// The tile, an index into [`super::DrawList::tiles`].
    pub tile: u32,
    /// Its slot in the cluster (0..16): which `u_members` entries its
    /// vertices read.
    pub slot: u8,
    /// Its first index, counted from the cluster's first index.
    pub first_index: u32,
    /// Its indices (its tile's, rebased).
    pub index_count: u32,
}

/// One glDrawElements of a cluster: consecutive members in one depth slice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClusterRun {
    /// Byte offset of its first index.
    pub index_byte_offset: u32,
    /// Indices drawn.
    pub index_count: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_hold_2_16_vertices_and_never_touch() {
        let capacity = 84 << 20;
        let n = window_count(capacity);
        assert_eq!(n, 68, "67 whole windows and a shorter last one");
        for k in 0..n {
            let w = window(k, capacity).expect("inside");
            assert_eq!(w.start % VERTEX_BYTES, 0);
            assert!(w.end - w.start <= WINDOW_VERTICES * VERTEX_BYTES);
            assert_eq!((w.end - w.start) % VERTEX_BYTES, 0);
            assert!(w.end <= capacity && window_of(w.start) == k && window_of(w.end - 1) == k);
            if k + 1 < n {
                assert_eq!(w.end - w.start, WINDOW_VERTICES * VERTEX_BYTES);
                assert!(w.end < window(k + 1, capacity).expect("next").start, "a fence between");
            }
        }
        assert_eq!(window(n, capacity), None);
    }
}
