//! Cluster batches (Judnich & Ling, "Symmetric Cluster Set Level of
//! Detail"): the frame's tiles gathered into clusters of neighbours, each
//! drawn with one glDrawElements, GL-free.
//!
//! **Formation** ([`Formation`], Judnich & Ling IV.A–C). The drawn tiles
//! are the leaves of a quadtree. A node is *flat* when every drawn tile
//! inside it is one of its children (the paper's cluster type #1, four
//! leaves; fewer where the frustum culled some). A tile whose parent is
//! flat joins the cluster of its grandparent as one of up to 16 *fine*
//! members; any other tile joins its parent's cluster as one of up to 4
//! *coarse* members. So a cluster rooted at node R holds, per quadrant of
//! R, nothing, one tile a level below R, or the tiles two levels below R:
//! the paper's two-level clusters, 3^4 states, 23 up to rotation besides
//! the empty one ([`shapes`]). Every tile is in exactly one cluster.
//!
//! **Blocks** ([`ClusterCache`]). Heights stay in vertex buffers (Polok):
//! a cluster's block in its own allocator holds its members' vertices,
//! copied from the tile cache's blocks with each vertex's member slot in
//! [`crate::tiles::TileVertex::_pad`], then one 16-bit index list over
//! them numbered from the cluster's attribute base. A block is made again
//! only when its members change (a tile joins or leaves, or is remade from
//! finer data); a still camera makes none.
//!
//! **Placement.** ES 2.0 has no base vertex: a draw's indices number
//! vertices from where the attribute pointers point, and are 16-bit. The
//! vertex blocks live in an allocator of their own (the indices in
//! another), each a whole number of 20-byte vertices, so every block starts
//! on a vertex of one lattice from byte 0 and vertex data pack densely. The
//! vertex buffer is cut into fixed *windows* of 2^16 vertices
//! ([`crate::render::cluster::window`]), fenced from each other; each
//! cluster's vertex block lies in one, and its indices are numbered from
//! the window's start, its *attribute base*. Clusters sharing a window
//! share their attribute pointers (or the window's vertex array): the pass
//! changes them only when the base changes, and the frame's clusters are
//! packed into few windows (best fit among the windows in use).

mod cache;
pub mod mirror;
pub mod shapes;

pub use cache::{ClusterCache, ClusterConfig, ClusterError, ClusterFrameStats};

use crate::lod::TileKey;
use crate::render::cluster::MAX_MEMBERS;
use crate::render::TileUniforms;
use crate::tiles::block::VERTEX_BYTES;
use std::collections::HashSet;

/// Most vertices one cluster's indices can reach: 16-bit indices.
pub const MAX_CLUSTER_VERTICES: u32 = 1 << 16;

/// Names a cluster: the node it is rooted at (as a tile key of its level)
/// and, when its members' vertices are too many for 16-bit indices, which
/// part of it (0 the whole cluster, 1 to 4 a quadrant, 5 to 20 one slot).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ClusterKey {
    /// The cluster's root node.
    pub root: TileKey,
    /// Which part of the root's cluster.
    pub part: u8,
}

/// One tile's place in the frame's clusters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Placement {
    /// Its cluster.
    pub key: ClusterKey,
    /// Its slot in the cluster: `x + 4 y` of its place on the 4 x 4 lattice
    /// of fine members (a coarse member takes its quadrant's south-west one).
    pub slot: u8,
    /// Its index in the draw list's tiles.
    pub tile: u32,
    /// Its vertices.
    pub vertices: u32,
}

/// The slot of a fine member `key` (two levels below its root).
pub fn fine_slot(key: TileKey) -> u8 {
    ((key.x & 3) + 4 * (key.y & 3)) as u8
}

/// The slot of a coarse member `key` (one level below its root): the
/// south-west fine slot of its quadrant.
pub fn coarse_slot(key: TileKey) -> u8 {
    (2 * (key.x & 1) + 8 * (key.y & 1)) as u8
}

/// The quadrant (0 south-west, 1 south-east, 2 north-west, 3 north-east) a slot lies in.
pub fn slot_quadrant(slot: u8) -> u8 {
    ((slot & 3) >> 1) + 2 * ((slot >> 2) >> 1)
}

/// The frame's clusters: reused from frame to frame, so forming them
/// allocates nothing once its tables have grown.
#[derive(Debug, Default)]
pub struct Formation {
    /// Nodes with a drawn tile two or more levels below them (not flat).
    deep: HashSet<TileKey>,
    /// Every tile's placement, sorted by cluster and slot.
    placements: Vec<Placement>,
}

impl Formation {
    /// Room for `tiles` tiles a frame.
    pub fn with_capacity(tiles: usize) -> Self {
        Formation {
            deep: HashSet::with_capacity(tiles * 16),
            placements: Vec::with_capacity(tiles),
        }
    }

    /// Gathers `tiles` into clusters; returns the placements sorted by
    /// cluster, then slot (a cluster's members are consecutive).
    pub fn form(&mut self, tiles: &[TileUniforms]) -> &[Placement] {
        self.deep.clear();
        self.placements.clear();
        let top = tiles.iter().map(|t| t.key.level).max().unwrap_or(0) as u32 + 1;
        for tile in tiles {
            let mut node = tile.key.parent();
            while (node.level as u32) < top {
                node = node.parent();
                if !self.deep.insert(node) {
                    break;
                }
            }
        }
        for (index, tile) in tiles.iter().enumerate() {
            let parent = tile.key.parent();
            let (root, slot) = if self.deep.contains(&parent) {
                (parent, coarse_slot(tile.key))
            } else {
                (parent.parent(), fine_slot(tile.key))
            };
            let vertices = (tile.index_byte_offset - tile.byte_offset) / VERTEX_BYTES;
            self.placements.push(Placement {
                key: ClusterKey { root, part: 0 },
                slot,
                tile: index as u32,
                vertices,
            });
        }
        self.sort();
        // Clusters whose vertices 16-bit indices cannot reach: by quadrant,
        // then by tile.
        for split in [1u8, 2] {
            let mut changed = false;
            let mut start = 0;
            while start < self.placements.len() {
                let end = self.group_end(start);
                let vertices: u32 = self.placements[start..end].iter().map(|p| p.vertices).sum();
                if vertices > MAX_CLUSTER_VERTICES {
                    for p in &mut self.placements[start..end] {
                        p.key.part =
                            if split == 1 { 1 + slot_quadrant(p.slot) } else { 5 + p.slot };
                    }
                    changed = true;
                }
                start = end;
            }
            if !changed {
                break;
            }
            self.sort();
        }
        &self.placements
    }

    fn sort(&mut self) {
        self.placements.sort_unstable_by_key(|p| (p.key, p.slot));
    }

    /// One past the last placement of the cluster starting at `start`.
    fn group_end(&self, start: usize) -> usize {
        let key = self.placements[start].key;
        let mut end = start + 1;
        while end < self.placements.len() && self.placements[end].key == key {
            end += 1;
        }
        debug_assert!(end - start <= MAX_MEMBERS);
        end
    }

    /// The last frame's placements.
    pub fn placements(&self) -> &[Placement] {
        &self.placements
    }

    /// The last frame's clusters: ranges of [`Self::placements`].
    pub fn clusters(&self) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let mut start = 0;
        std::iter::from_fn(move || {
            if start == self.placements.len() {
                return None;
            }
            let end = self.group_end(start);
            let range = start..end;
            start = end;
            Some(range)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(level: u8, x: u32, y: u32) -> TileUniforms {
        TileUniforms {
            key: TileKey::new(level, x, y),
            first_post: [0.0; 2],
            post_step: 1.0,
            vertex_step: 1.0,
            morph: [0.0, 1.0],
            sub_morph_end: 0.0,
            skirt_depth: 1.0,
            skirt_edges: 0,
            skirt_shares: [0; 4],
            skirt_slope: f32::INFINITY,
            byte_offset: 0,
            index_byte_offset: 100 * VERTEX_BYTES,
            index_count: 6,
            no_data: false,
            place: crate::earth::NodePlace::default(),
            ground: None,
        }
    }

    #[test]
    fn a_quadtree_collapses_into_two_level_clusters() {
        // Root node (level 3, 0, 0): its south-west quadrant (level 2, 0, 0)
        // split into four level-1 tiles, of which the south-west one split
        // again into four level-0 tiles; the other three quadrants leaves.
        let mut tiles = vec![tile(2, 1, 0), tile(2, 0, 1), tile(2, 1, 1)];
        tiles.extend([tile(1, 1, 0), tile(1, 0, 1), tile(1, 1, 1)]);
        tiles.extend([tile(0, 0, 0), tile(0, 1, 0), tile(0, 0, 1), tile(0, 1, 1)]);
        let mut formation = Formation::default();
        formation.form(&tiles);
        let clusters: Vec<Vec<(TileKey, u8)>> = formation
            .clusters()
            .map(|r| {
                formation.placements()[r]
                    .iter()
                    .map(|p| (tiles[p.tile as usize].key, p.slot))
                    .collect()
            })
            .collect();
        // The four level-0 tiles are a flat node's: fine members of the
        // level-2 node (0, 0), with the three level-1 tiles as coarse ones;
        // the three level-2 tiles are coarse members of the root.
        assert_eq!(clusters.len(), 2, "{clusters:?}");
        assert_eq!(
            clusters[0],
            [
                (TileKey::new(0, 0, 0), 0),
                (TileKey::new(0, 1, 0), 1),
                (TileKey::new(1, 1, 0), 2),
                (TileKey::new(0, 0, 1), 4),
                (TileKey::new(0, 1, 1), 5),
                (TileKey::new(1, 0, 1), 8),
                (TileKey::new(1, 1, 1), 10),
            ]
        );
        assert_eq!(
            clusters[1],
            [(TileKey::new(2, 1, 0), 2), (TileKey::new(2, 0, 1), 8), (TileKey::new(2, 1, 1), 10)]
        );
    }

    #[test]
    fn clusters_too_large_for_16_bit_indices_are_split() {
        let mut tiles: Vec<TileUniforms> =
            (0..16).map(|k| tile(0, k % 4, k / 4)).collect::<Vec<_>>();
        for t in &mut tiles {
            t.index_byte_offset = 5000 * VERTEX_BYTES;
        }
        let mut formation = Formation::default();
        formation.form(&tiles);
        let sizes: Vec<usize> = formation.clusters().map(|r| r.len()).collect();
        assert_eq!(sizes, [4, 4, 4, 4], "80 000 vertices: one cluster per quadrant");
    }
}
