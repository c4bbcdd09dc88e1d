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
/// the atlas and the staging copy (tile cache tables, draw list, loader
/// queue, meshes of loaded nodes), as a share of the budget.
pub const RESERVE_SHARE: f64 = 0.125;
/// Most of what is left after the reserve that the node atlas may take.
pub const ATLAS_SHARE: f64 = 0.25;
/// Bytes an atlas slot is counted at, per height it holds: the heights
/// themselves and room for a node mesh's vertices and indices.
pub const SLOT_BYTES_PER_HEIGHT: u64 = 12;

/// How a memory budget is shared: the node atlas, and the GPU tile buffer
/// with its staging copy (the same size, one on each side of the bus).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct MemoryPlan {
    /// The budget, bytes: Ridgeline's own heap and its GPU buffer.
    pub budget_bytes: u64,
    /// Atlas slots (fewer than the view wants: coarser data, never holes).
    pub atlas_slots: u32,
    /// Bytes an atlas slot is counted at.
    pub slot_bytes: u64,
    /// The GPU tile buffer and its staging copy, bytes each.
    pub buffer_bytes: u32,
}

/// Shares `budget_bytes` for `layout`'s nodes when the view wants
/// `wanted_slots` atlas slots: [`RESERVE_SHARE`] kept for the rest of the
/// heap, the atlas up to [`ATLAS_SHARE`] of what is left (never more slots
/// than wanted), and half of the remainder each to the GPU buffer and its
/// staging copy (never more than `max_buffer_bytes`). A smaller buffer
/// makes the scene coarsen its tiles, a smaller atlas makes tiles fall
/// back to coarser resident nodes: the display degrades, never leaves holes.
pub fn plan_memory(
    budget_bytes: u64,
    layout: &NodeLayout,
    wanted_slots: u32,
    max_buffer_bytes: u32,
) -> MemoryPlan {
    let side = layout.stored_side() as u64;
    let slot_bytes = side * side * SLOT_BYTES_PER_HEIGHT;
    let usable = budget_bytes as f64 * (1.0 - RESERVE_SHARE);
    let atlas_cap = (usable * ATLAS_SHARE) as u64 / slot_bytes.max(1);
    let atlas_slots = (wanted_slots as u64).min(atlas_cap) as u32;
    let left = usable as u64 - atlas_slots as u64 * slot_bytes;
    let buffer_bytes = (left / 2).min(max_buffer_bytes as u64) as u32 & !3;
    debug_assert!(
        atlas_slots as u64 * slot_bytes + 2 * buffer_bytes as u64 <= budget_bytes,
        "the plan fits its budget"
    );
    MemoryPlan { budget_bytes, atlas_slots, slot_bytes, buffer_bytes }
}
