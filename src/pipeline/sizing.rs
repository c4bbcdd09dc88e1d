//! Sizing the clipmap from the scene's rings: every tile the rings can
//! select must find its own level's node within the view's load radius.

use super::PipelineConfig;
use crate::camera::Camera;
use crate::clipmap::ViewConfig;
use crate::lod::LevelRings;
use crate::node::NodeLayout;
use crate::scene::{ring_inputs, SceneError, TerrainSummary};
use glam::DVec3;

/// The clipmap view for `config` over `layout`: for each level, the far edge
/// of its ring (the rings the scene draws with, at the configured field of
/// view and viewport) plus a tile diagonal, in node sizes.
pub fn clipmap_view(
    config: &PipelineConfig,
    summary: &TerrainSummary,
    layout: &NodeLayout,
) -> Result<ViewConfig, SceneError> {
    let camera = Camera {
        position: DVec3::ZERO,
        heading_deg: 0.0,
        pitch_deg: 0.0,
        roll_deg: 0.0,
        fov_x_deg: config.fov_x_deg,
        viewport: config.viewport,
    };
    camera.validate()?;
    let lod = &config.scene.lod;
    let (low, high) = summary.height_range;
    let height_range_m = (high - low) as f64;
    let inputs =
        ring_inputs(layout, lod.grid_size, &summary.delta_per_level, height_range_m, &camera);
    let tile_size_m = inputs.tile_size_m;
    let rings = LevelRings::new(lod, inputs);
    let mut load_distance: f64 = 2.0;
    for level in 0..layout.levels.saturating_sub(1) {
        let node = layout.node_size_m(level);
        let tile = tile_size_m * (1u64 << level) as f64;
        let reach = rings.split_distance(level + 1) + tile * std::f64::consts::SQRT_2;
        load_distance = load_distance.max(reach / node[0].min(node[1]) + 0.5);
    }
    let load_distance = load_distance.min(40.0);
    let node_count = (2.0 * load_distance).ceil() as u32 + 4;
    Ok(ViewConfig { node_count, view_distance: load_distance, load_distance })
}

/// Room for every node a view can want (a disc of the load radius per level)
/// and as many again as a cache of recently used ones.
pub fn atlas_slots(view: &ViewConfig, levels: u8) -> u32 {
    let disc = std::f64::consts::PI * (view.load_distance + 1.5).powi(2);
    (2.0 * disc * levels as f64).ceil() as u32 + 64
}

/// Bytes of Ridgeline's heap the memory budget keeps for everything but
/// the node buffers and the staging copy (tile cache tables, draw list,
/// selection lists: 2.4 MB measured on the default flight), with room.
pub const RESERVE_BYTES: u64 = 3 << 20;
/// Most of what is left after the reserve that the node buffers (atlas
/// slots and the loader's buffers) may take.
pub const NODE_SHARE: f64 = 0.3;
/// The smallest budget a display is planned for, bytes: the reserve and
/// a few megabytes for nodes and tiles.
pub const MIN_BUDGET_BYTES: u64 = RESERVE_BYTES + (2 << 20);

/// How a memory budget is shared: the node buffers (atlas slots and the
/// loader's), and the GPU tile buffer with its staging copy (the same
/// size, one on each side of the bus).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct MemoryPlan {
    /// The budget, bytes: Ridgeline's own heap and its GPU buffer.
    pub budget_bytes: u64,
    /// Atlas slots (fewer than the view wants: coarser data, never holes).
    pub atlas_slots: u32,
    /// Requests the loader thread may queue (it keeps two buffers more).
    pub loader_queue: u32,
    /// Bytes a node buffer is counted at ([`crate::node::NodeSource::node_bytes`]).
    pub node_bytes: u64,
    /// The GPU tile buffer and its staging copy, bytes each.
    pub buffer_bytes: u32,
}

/// Shares `budget_bytes` when the view wants `wanted_slots` atlas slots of
/// `node_bytes` each and the loader up to `queue` requests: `RESERVE_BYTES`
/// kept for the rest of the heap; the node buffers up to `NODE_SHARE` of
/// what is left (a quarter of them, at most `queue`, for the loader, never
/// more slots than wanted); half of the remainder each to the GPU buffer
/// and its staging copy (never more than `max_buffer_bytes`). A smaller
/// buffer makes the scene coarsen its tiles, a smaller atlas makes tiles
/// fall back to coarser resident nodes: the display degrades, never leaves
/// holes. `None` when the budget is below [`MIN_BUDGET_BYTES`] or leaves
/// the atlas fewer than two slots.
pub fn plan_memory(
    budget_bytes: u64,
    node_bytes: u64,
    wanted_slots: u32,
    queue: u32,
    max_buffer_bytes: u32,
) -> Option<MemoryPlan> {
    let usable = budget_bytes.checked_sub(RESERVE_BYTES)?;
    if budget_bytes < MIN_BUDGET_BYTES {
        return None;
    }
    let buffers = ((usable as f64 * NODE_SHARE) as u64 / node_bytes.max(1)) as u32;
    let loader_queue = (buffers / 4).clamp(1, queue.max(1));
    let atlas_slots = buffers.saturating_sub(loader_queue + 2).min(wanted_slots);
    if atlas_slots < 2.min(wanted_slots) {
        // Not even the root and one node more: no display to degrade to.
        return None;
    }
    let nodes = (atlas_slots + loader_queue + 2) as u64 * node_bytes;
    let left = usable.saturating_sub(nodes);
    let buffer_bytes = (left / 2).min(max_buffer_bytes as u64) as u32 & !3;
    debug_assert!(nodes + 2 * buffer_bytes as u64 <= budget_bytes || atlas_slots == 0);
    Some(MemoryPlan { budget_bytes, atlas_slots, loader_queue, node_bytes, buffer_bytes })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Node buffers, the GPU buffer and its staging copy fit the budget
        /// less the reserve; too small a budget has no plan.
        #[test]
        fn plans_fit_their_budget(
            budget in 0u64..(1 << 32),
            node_bytes in 1u64..(1 << 21),
            wanted in 0u32..100_000,
            queue in 0u32..512,
        ) {
            match plan_memory(budget, node_bytes, wanted, queue, 84 << 20) {
                None => prop_assert!(
                    budget < MIN_BUDGET_BYTES
                        || (budget - RESERVE_BYTES) as f64 * NODE_SHARE < (8 * node_bytes) as f64
                ),
                Some(plan) => {
                    let nodes = (plan.atlas_slots + plan.loader_queue + 2) as u64 * node_bytes;
                    let used = nodes + 2 * plan.buffer_bytes as u64;
                    prop_assert!(plan.atlas_slots <= wanted);
                    prop_assert!(used + RESERVE_BYTES <= budget || plan.atlas_slots == 0);
                }
            }
        }
    }
}
