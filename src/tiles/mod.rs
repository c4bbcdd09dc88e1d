//! Per-tile mesh blocks (Polok's per-tile height buffers, grown to whole
//! meshes): each tile's block holds its vertices (positions, heights, morph
//! targets and normals as vertex attributes) and its indices; the regular
//! grid mesh the tiles are made as today; and the cache that keeps tiles
//! resident in the contiguous allocator, regenerating a tile only when it
//! is new or its source data got finer, and uploading everything a frame
//! changed in one batched transfer per run piece.

pub mod block;
pub mod by_distance;
pub mod cache;
pub mod curtain;
pub mod errors;
pub mod extract;
pub mod fan;
pub mod grid;
pub mod kept;
pub mod mesh_tile;
pub mod seams;
pub mod vertex;

pub use block::{MeshCounts, TileBlock, TileVertex};
pub use cache::{
    MadeFrom, TileCache, TileCacheConfig, TileDraw, TileError, TileFrameStats, TileMeshKind,
};
pub use grid::TileGrid;
pub use vertex::{TileCoverage, NO_DATA};

use crate::node::{NodeData, NodeId, NodeLayout};

/// Nodes the tiles can read: whatever is resident in the node atlas.
pub trait ResidentNodes {
    /// Layout of the pyramid the nodes come from.
    fn layout(&self) -> &NodeLayout;
    /// The node's data if it is resident now.
    fn resident(&self, id: NodeId) -> Option<&NodeData>;
    /// Whether the source stores node `id` (resident or not): a tile whose
    /// child node is not stored has no finer data and is drawn however near
    /// the camera comes. The default: every node of the layout is stored.
    fn is_stored(&self, id: NodeId) -> bool {
        self.layout().contains(id)
    }
}

/// The finest resident node that contains node `id`: itself or an ancestor.
pub fn best_resident(nodes: &dyn ResidentNodes, id: NodeId) -> Option<(NodeId, &NodeData)> {
    let levels = nodes.layout().levels;
    let mut node = id;
    loop {
        if let Some(data) = nodes.resident(node) {
            return Some((node, data));
        }
        if node.level + 1 >= levels {
            return None;
        }
        node = node.parent()?;
    }
}
