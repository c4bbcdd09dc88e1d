//! A pyramid built in memory: per level, the present nodes' posts and
//! summaries, and where each node of the layout is stored. What the builder
//! fills, the delta measures against, and the writer writes.

use super::format::{NodeSummary, PyramidInfo};
use crate::node::{NodeId, NodeLayout};

/// One level's present nodes in memory.
pub(crate) struct BuiltLevel {
    /// Per node of the level (row by row, south first): its slot among the
    /// present nodes, `None` where the node is absent.
    pub(super) slots: Vec<Option<u32>>,
    /// Present node in slot `s` has posts `heights[s * side^2..(s + 1) * side^2]`.
    pub(super) heights: Vec<f32>,
    /// Summaries of the present nodes in slot order.
    pub(super) summaries: Vec<NodeSummary>,
    /// Per slot, whether any centre post has data.
    pub(super) has_data: Vec<bool>,
}

/// A whole pyramid in memory, ready for [`write_atomic`](super::write_atomic).
pub struct BuiltPyramid {
    /// What the header will say.
    pub info: PyramidInfo,
    pub(super) levels: Vec<BuiltLevel>,
}

impl BuiltPyramid {
    /// The node layout over the union of all layers.
    pub fn layout(&self) -> &NodeLayout {
        &self.info.layout
    }

    /// The stored posts (border included) and summary of node `id`; `None`
    /// for a node outside the layout or absent.
    pub fn node(&self, id: NodeId) -> Option<(&[f32], NodeSummary)> {
        node_of(&self.levels, &self.info.layout, id)
    }

    /// Whether node `id` is stored.
    pub fn is_present(&self, id: NodeId) -> bool {
        self.node(id).is_some()
    }

    /// Every present node's posts and summary in file order (finest level first).
    pub(crate) fn levels(&self) -> impl Iterator<Item = (&[f32], &[NodeSummary])> {
        self.levels.iter().map(|l| (l.heights.as_slice(), l.summaries.as_slice()))
    }

    /// The node index ([`NodeLayout::node_index`]) of every present node,
    /// in file order: records are written in node order.
    pub(crate) fn present_indices(&self) -> Vec<u64> {
        let mut base = 0u64;
        let mut indices = Vec::new();
        for level in &self.levels {
            let slots = level.slots.iter().enumerate().filter_map(|(k, s)| s.map(|s| (k, s)));
            for (n, (k, slot)) in slots.enumerate() {
                debug_assert_eq!(n, slot as usize, "slots are in node order");
                indices.push(base + k as u64);
            }
            base += level.slots.len() as u64;
        }
        indices
    }

    /// Summaries of all nodes of the layout in file order, `None` for absent ones.
    pub fn node_summaries(&self) -> Vec<Option<NodeSummary>> {
        self.levels
            .iter()
            .flat_map(|l| l.slots.iter().map(|s| s.map(|s| l.summaries[s as usize])))
            .collect()
    }
}

/// The posts and summary of `id` in `levels`.
pub(crate) fn node_of<'a>(
    levels: &'a [BuiltLevel],
    layout: &NodeLayout,
    id: NodeId,
) -> Option<(&'a [f32], NodeSummary)> {
    if !layout.contains(id) {
        return None;
    }
    let level = levels.get(id.level as usize)?;
    let index = id.y as usize * layout.nodes_at(id.level)[0] as usize + id.x as usize;
    let slot = (*level.slots.get(index)?)? as usize;
    let posts = (layout.stored_side() as usize).pow(2);
    Some((&level.heights[slot * posts..(slot + 1) * posts], level.summaries[slot]))
}
