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
/// the node buffers and the staging copies (tile cache tables, draw list,
/// selection lists, the atlas's slot table): measured 2.4 MB on the
/// default flight and 3.1 MB on the cruise flight, with room.
pub const RESERVE_BYTES: u64 = 4 << 20;
/// The share of what is left after the reserve and the loader's buffers
/// that the atlas's nodes may take; the rest goes to the tile buffer and
/// its copies. Measured on the default flight at 1280x720, tau 1: the view's
/// nodes take 30 MB and its tiles 7.5 MB of buffer.
pub const NODE_SHARE: f64 = 0.45;
/// The most requests a budgeted loader queues: enough to keep its thread
/// reading, few enough that its buffers (each up to the largest node) stay
/// a small part of the budget.
pub const MAX_LOADER_QUEUE: u32 = 8;
/// The smallest tile buffer a budget gives (less only when the scene asks
/// for less): the coarsest selection a low flight falls back to, blocks
/// of node meshes up to 170 KB, needs about 3 MB of a buffer whose free
/// room is in pieces (2.2 MB failed the default flight at its first frame).
pub const MIN_BUFFER_BYTES: u64 = 4 << 20;
/// The smallest budget a display is planned for, bytes: the reserve and
/// a few megabytes for nodes and tiles.
pub const MIN_BUDGET_BYTES: u64 = RESERVE_BYTES + (2 << 20);

/// How a memory budget is shared: the atlas's nodes (counted in bytes, each
/// at its own size), the loader's buffers, and the tile buffer with its
/// copies (the GPU buffer and its staging copy; with clusters, the cluster
/// buffers and their staging copies as well).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct MemoryPlan {
    /// The budget, bytes: Ridgeline's own heap and its GPU buffers.
    pub budget_bytes: u64,
    /// The most bytes the atlas's nodes may take (fewer nodes than the
    /// view wants: coarser data, never holes).
    pub atlas_bytes: u64,
    /// Requests the loader thread may queue (it keeps two buffers more).
    pub loader_queue: u32,
    /// Bytes a loader buffer is counted at: the largest node
    /// ([`crate::node::NodeSource::node_bytes`]).
    pub node_bytes: u64,
    /// The tile buffer (and each of its copies' unit), bytes.
    pub buffer_bytes: u32,
}

/// Copies of the tile buffer's size a display keeps: the GPU buffer and
/// its staging copy; with clusters, the tile staging copy, the cluster
/// vertex buffer and its staging copy, and the cluster index buffer and
/// its staging copy at half the size each (the tile buffer itself is then
/// never on the GPU).
pub fn buffer_copies(clusters: bool) -> f64 {
    if clusters {
        4.0
    } else {
        2.0
    }
}

/// Shares `budget_bytes` when the loader may queue up to `queue` requests
/// of nodes of at most `node_bytes`: `RESERVE_BYTES` kept for the rest of
/// the heap; the loader's buffers (an eighth of what `NODE_SHARE` of
/// the rest holds in largest nodes, at most `queue` and
/// [`MAX_LOADER_QUEUE`], two more); `NODE_SHARE` of
/// what is left for the atlas's nodes; the remainder shared among the
/// `copies` of the tile buffer (never more than `max_buffer_bytes` each).
/// A smaller buffer makes the scene coarsen its tiles, a smaller atlas
/// makes tiles fall back to coarser resident nodes: the display degrades,
/// never leaves holes, and says so. The tile buffer gets at least
/// [`MIN_BUFFER_BYTES`] before the atlas its share. `None` when the
/// budget is below [`MIN_BUDGET_BYTES`], or leaves the loader no buffer or
/// the tile buffer less than its floor.
pub fn plan_memory(
    budget_bytes: u64,
    node_bytes: u64,
    queue: u32,
    copies: f64,
    max_buffer_bytes: u32,
) -> Option<MemoryPlan> {
    if budget_bytes < MIN_BUDGET_BYTES {
        return None;
    }
    let usable = budget_bytes - RESERVE_BYTES;
    let node_bytes = node_bytes.max(1);
    let largest_nodes = (usable as f64 * NODE_SHARE) as u64 / node_bytes;
    // A loader buffer may hold the largest node; a few keep the thread busy.
    let loader_queue = ((largest_nodes / 8) as u32).min(queue.max(1)).min(MAX_LOADER_QUEUE);
    if loader_queue == 0 {
        return None;
    }
    let left = usable.checked_sub((loader_queue as u64 + 2) * node_bytes)?;
    // The buffer first gets its floor: without it no selection fits.
    let floor = (MIN_BUFFER_BYTES.min(max_buffer_bytes as u64) as f64 * copies) as u64;
    let atlas_bytes = ((left as f64 * NODE_SHARE) as u64).min(left.checked_sub(floor)?);
    let buffers = ((left - atlas_bytes) as f64 / copies) as u64;
    let buffer_bytes = buffers.min(max_buffer_bytes as u64) as u32 & !3;
    Some(MemoryPlan { budget_bytes, atlas_bytes, loader_queue, node_bytes, buffer_bytes })
}

/// The least budget [`plan_memory`] has a plan for with these settings,
/// bytes, so that a refused budget says what would do: bisected between a
/// budget without a plan and one with (a byte less has none).
pub fn least_budget(node_bytes: u64, queue: u32, copies: f64, max_buffer_bytes: u32) -> u64 {
    let fits = |budget: u64| plan_memory(budget, node_bytes, queue, copies, max_buffer_bytes);
    let (mut low, mut high) = (MIN_BUDGET_BYTES, MIN_BUDGET_BYTES.max(1 << 20));
    while fits(high).is_none() {
        if high >= 1 << 50 {
            return high;
        }
        (low, high) = (high, high * 2);
    }
    while high - low > 1 {
        let mid = low + (high - low) / 2;
        if fits(mid).is_some() {
            high = mid;
        } else {
            low = mid;
        }
    }
    if fits(low).is_some() {
        low
    } else {
        high
    }
}

impl MemoryPlan {
    /// What the plan gives out, bytes: it never exceeds the budget.
    pub fn planned_bytes(&self, copies: f64) -> u64 {
        let loader = (self.loader_queue as u64 + 2) * self.node_bytes;
        let buffers = (copies * self.buffer_bytes as f64).ceil() as u64;
        RESERVE_BYTES + loader + self.atlas_bytes + buffers
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The reserve, the loader's buffers, the atlas and the tile
        /// buffer's copies fit the budget; too small a budget has no plan.
        #[test]
        fn plans_fit_their_budget(
            budget in 0u64..(1 << 32),
            node_bytes in 1u64..(1 << 21),
            queue in 0u32..512,
            clusters: bool,
        ) {
            let copies = buffer_copies(clusters);
            match plan_memory(budget, node_bytes, queue, copies, 84 << 20) {
                None => {
                    let usable = budget.saturating_sub(RESERVE_BYTES) as f64;
                    let floor = MIN_BUFFER_BYTES as f64 * copies;
                    prop_assert!(
                        budget < MIN_BUDGET_BYTES
                            || usable * NODE_SHARE < (8 * node_bytes) as f64
                            || usable < floor + (10 * node_bytes) as f64
                    );
                }
                Some(plan) => {
                    prop_assert!(plan.planned_bytes(copies) <= budget);
                    prop_assert!(plan.loader_queue >= 1 && plan.loader_queue <= queue.max(1));
                    prop_assert!(plan.buffer_bytes <= 84 << 20);
                    prop_assert!(plan.buffer_bytes as u64 >= MIN_BUFFER_BYTES - 4);
                }
            }
        }

        /// The least budget a refusal names has a plan, and a byte less
        /// (above the floor) has none.
        #[test]
        fn the_least_budget_is_the_first_with_a_plan(
            node_bytes in 1u64..(1 << 22),
            queue in 0u32..512,
            clusters: bool,
        ) {
            let copies = buffer_copies(clusters);
            let least = least_budget(node_bytes, queue, copies, 84 << 20);
            prop_assert!(plan_memory(least, node_bytes, queue, copies, 84 << 20).is_some());
            if least > MIN_BUDGET_BYTES {
                prop_assert!(plan_memory(least - 1, node_bytes, queue, copies, 84 << 20).is_none());
            }
        }
    }
}
