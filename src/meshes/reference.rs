//! The reference grid of one node: the best data under it on the lattice of
//! a finer level, the grid its adaptive mesh is simplified from.
//!
//! The node's square is cut into the squares of its descendants at the
//! reference level. Each is read from that descendant where the source
//! stores it, else from its deepest stored ancestor (best available, as the
//! tiles do), with [`PostReader`]: so posts past the data's last post carry
//! the extrapolation the terrain program clips at, and posts without data
//! are NaN, exactly as a tile of the reference level would have them.

use crate::lod::TileKey;
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::tiles::vertex::PostReader;

/// A node's reference grid and what it was read from.
pub struct ReferenceGrid {
    /// Posts a side: `node_size << (level - post_level) + 1`.
    pub side: u32,
    /// The heights, row-major, row 0 south; NaN where the data have none.
    pub heights: Vec<f32>,
    /// The level whose lattice the posts are on.
    pub post_level: u8,
    /// The largest delta of the reference-level nodes read: how far the
    /// reference surface may be from the best data (0 at level 0, and
    /// where a block came from an ancestor, which is the best data there).
    pub delta: f32,
}

/// Reads the reference grid of node `id` on the lattice of `post_level`
/// (at most `id.level`).
pub fn reference_grid(
    source: &dyn NodeSource,
    id: NodeId,
    post_level: u8,
) -> Result<ReferenceGrid, NodeError> {
    debug_assert!(post_level <= id.level);
    let layout = *source.layout();
    let shift = id.level - post_level;
    let blocks = 1u32 << shift;
    let n = layout.node_size;
    let side = n * blocks + 1;
    let mut grid = ReferenceGrid {
        side,
        heights: vec![f32::NAN; side as usize * side as usize],
        post_level,
        delta: 0.0,
    };
    let mut data = NodeData::with_capacity(&layout);
    let mut loaded: Option<NodeId> = None;
    for by in 0..blocks {
        for bx in 0..blocks {
            let block = NodeId::new(post_level, id.x * blocks + bx, id.y * blocks + by);
            let from = stored_ancestor(source, &layout, block, id);
            if loaded != Some(from) {
                source.read_node(from, &mut data)?;
                loaded = Some(from);
            }
            // A block read from an ancestor has no finer data (presence is
            // hierarchical): the ancestor's surface is the best data there,
            // so it adds no error; its own delta covers other places.
            if from == block {
                grid.delta = grid.delta.max(data.delta);
            }
            let key = TileKey::new(post_level, block.x, block.y);
            let reader = PostReader::new(&layout, key, n, from, &data);
            let (x0, y0) = ((bx * n) as usize, (by * n) as usize);
            for j in 0..=n {
                let row = (y0 + j as usize) * side as usize + x0;
                for i in 0..=n {
                    grid.heights[row + i as usize] = reader.post(i as i64, j as i64);
                }
            }
        }
    }
    Ok(grid)
}

/// `block` itself if the source stores it, else its deepest stored
/// ancestor, which is at most `top` (stored by the caller's contract).
fn stored_ancestor(
    source: &dyn NodeSource,
    layout: &NodeLayout,
    block: NodeId,
    top: NodeId,
) -> NodeId {
    let mut node = block;
    while node.level < top.level && !(layout.contains(node) && source.has_node(node)) {
        node = node.parent().expect("below the top node there is a parent");
    }
    node
}
