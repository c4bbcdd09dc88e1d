//! Seams: which edges of a tile cut from a node's mesh meet the tile across
//! them, cut from the neighbouring node's mesh, without a crack (issue 25).
//!
//! A mesh's vertices along a node's edge are the posts whose codes lie
//! above the thresholds there: its own map's and those of the resident
//! ancestors whose vertices it keeps (`super::extract`). Maps built in one
//! block code the posts of the block's inner node edges alike on both sides
//! ([`ErrorMap::shared_edges`]); the thresholds are the rings' (the same
//! at the same place for the same generations). So two tiles of one level
//! and sub-level, made with the same ring generations and the same resident
//! ancestor levels, whose every map along the line shares it (or is the
//! same node's), keep the same vertices there and morph them alike: the
//! edge is watertight, and hangs no skirt
//! ([`crate::render::draw_list::skirt_edges`]).

use crate::lod::TileKey;
use crate::node::{ErrorMap, NodeId, NodeLayout};

use super::errors::TileErrors;
use super::ResidentNodes;

/// What a tile's neighbour across a node's edge must match for the two to
/// meet without a crack.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Seams {
    /// The tile's edges (bit 0 south, 1 east, 2 north, 3 west) on its
    /// node's boundary whose every map along the line shares it.
    pub shared: u8,
    /// The ring generations its mesh was made with ([`TileErrors::views`]).
    pub views: u32,
    /// The levels of the resident ancestors whose vertices its mesh keeps,
    /// one bit each.
    pub ancestors: u32,
    /// Made as a leaf tile ([`TileErrors::banded`]): two such tiles made
    /// this frame keep the same vertices along a line and morph them alike
    /// whatever their sub-levels (a frame remakes every tile whose rings
    /// moved, so both were made with this frame's).
    pub banded: bool,
}

impl Seams {
    /// Whether this tile's edge `edge` meets `other`, the tile across it
    /// (of another node, the same level and sub-level), without a crack.
    pub fn meets(&self, other: &Seams, edge: usize) -> bool {
        let facing = (edge + 2) % 4;
        self.shared & (1 << edge) != 0
            && other.shared & (1 << facing) != 0
            && self.alike(other)
            && self.ancestors == other.ancestors
    }
}

impl Seams {
    /// Whether two tiles' meshes follow the same errors and bands along a
    /// line both keep: the same generations of the same rings, or both
    /// banded.
    pub fn alike(&self, other: &Seams) -> bool {
        self.views == other.views || (self.banded && other.banded)
    }
}

/// The seams of tile `key` cut from the mesh of `source` (of the tile's
/// level) with `errors`, `grid_size` cells a side, given the nodes resident
/// now (the ancestors its mesh keeps, as `super::cache` extracts them).
pub fn seams_of(
    nodes: &dyn ResidentNodes,
    key: TileKey,
    source: NodeId,
    grid_size: u32,
    errors: TileErrors,
) -> Seams {
    let layout: NodeLayout = *nodes.layout();
    let mut seams = Seams { shared: 0, views: errors.views, ancestors: 0, banded: errors.banded };
    let Some(own) = nodes.resident(source).filter(|d| !d.map.is_empty()) else {
        return seams;
    };
    let per_node = (layout.node_size / grid_size).max(1);
    let on_node_edge = [
        key.y % per_node == 0,
        (key.x + 1) % per_node == 0,
        (key.y + 1) % per_node == 0,
        key.x % per_node == 0,
    ];
    let mut shared: u8 = (0..4).filter(|&e| on_node_edge[e]).fold(0, |s, e| s | 1 << e);
    shared &= shared_bits(&own.map, source, source);
    let mut id = source;
    while let Some(parent) = id.parent().filter(|p| p.level < layout.levels) {
        if let Some(data) = nodes.resident(parent).filter(|d| !d.map.is_empty()) {
            seams.ancestors |= 1 << parent.level.min(31);
            shared &= shared_bits(&data.map, parent, source);
        }
        id = parent;
    }
    seams.shared = shared;
    seams
}

/// The tile edges (bits as [`Seams::shared`]) along which `map`, node
/// `id`'s, meets its neighbour alike, seen from `source` (a node under
/// `id`, or `id`): a line of `source`'s boundary inside `id` is no seam of
/// `id`'s, so it passes.
fn shared_bits(map: &ErrorMap, id: NodeId, source: NodeId) -> u8 {
    let shift = (id.level - source.level).min(31);
    let span = 1u32 << shift;
    let on_boundary = [
        source.y % span == 0,
        (source.x + 1) % span == 0,
        (source.y + 1) % span == 0,
        source.x % span == 0,
    ];
    (0..4)
        .filter(|&e| !on_boundary[e] || map.shared_edges & ErrorMap::BY_TILE_EDGE[e] != 0)
        .fold(0, |s, e| s | 1 << e)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(shared_edges: u8) -> ErrorMap {
        ErrorMap { cells: 4, codes: vec![0; 25], shared_edges, ..ErrorMap::default() }
    }

    #[test]
    fn an_ancestor_counts_only_along_its_own_boundary() {
        let source = NodeId::new(0, 5, 2);
        // Node (0, 5, 2) is the south-east child of (1, 2, 1): its east
        // and south edges are the parent's, its west and north lie inside.
        let parent = NodeId::new(1, 2, 1);
        assert_eq!(shared_bits(&map(0), source, source), 0);
        assert_eq!(shared_bits(&map(15), source, source), 15);
        // The parent shares nothing: only the lines inside it pass.
        assert_eq!(shared_bits(&map(0), parent, source), 4 | 8);
        assert_eq!(shared_bits(&map(ErrorMap::EAST), parent, source), 2 | 4 | 8);
    }

    #[test]
    fn seams_meet_only_when_both_sides_share_and_match() {
        let a = Seams { shared: 0b0010, views: 3, ancestors: 0b110, banded: false };
        let b = Seams { shared: 0b1000, views: 3, ancestors: 0b110, banded: false };
        assert!(a.meets(&b, 1) && b.meets(&a, 3));
        assert!(!a.meets(&b, 3), "a's west is not shared");
        assert!(!a.meets(&Seams { views: 4, ..b }, 1), "other generations");
        assert!(!a.meets(&Seams { ancestors: 0b10, ..b }, 1), "other ancestors");
    }
}
