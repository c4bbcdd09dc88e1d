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
