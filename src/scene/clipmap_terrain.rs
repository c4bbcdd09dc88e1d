//! The clipmap as the scene's terrain: tiles read whatever nodes the node
//! atlas holds now, and fall back to the finest resident ancestor.

use super::terrain::{node_height_bounds, TerrainData};
use crate::clipmap::{Clipmap, SlotState};
use crate::lod::select::{children_node_stored, TileBounds};
use crate::lod::TileKey;
use crate::meshes::StoreInfo;
use crate::node::{NodeData, NodeId, NodeLayout, NodeSource};
use crate::procedural::ProceduralEarth;
use crate::pyramid::PyramidInfo;
use crate::tiles::errors::MapErrors;
use crate::tiles::ResidentNodes;

/// Per-level error and height range of the data behind a clipmap (from the
/// pyramid's header, or the procedural source's bounds).
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainSummary {
    /// Largest delta of each level, metres, finest level first: of the
    /// node meshes where the source keeps them.
    pub delta_per_level: Vec<f64>,
    /// Largest delta of each level's regular grid of posts, metres: what a
    /// tile made as a grid of a node's posts errs by (the pyramid's deltas;
    /// the same as `delta_per_level` where the source keeps no meshes).
    pub grid_delta_per_level: Vec<f64>,
    /// Lowest and highest height of the data, metres.
    pub height_range: (f32, f32),
    /// What each level's error maps can do (empty without maps).
    pub map_errors: MapErrors,
    /// Every post inside the data's rectangle has data (no void left, no
    /// no-data outline): only then may the horizon cull tiles, since the
    /// occluder is the drawn surface (see [`crate::lod::horizon`]).
    pub gapless: bool,
}

impl TerrainSummary {
    /// The summary a pyramid file's header records.
    pub fn from_pyramid(info: &PyramidInfo) -> Self {
        let deltas: Vec<f64> = info.levels.iter().map(|level| level.delta_max as f64).collect();
        TerrainSummary {
            grid_delta_per_level: deltas.clone(),
            delta_per_level: deltas,
            height_range: (info.stats.height_min, info.stats.height_max),
            map_errors: MapErrors::default(),
            gapless: info.stats.posts_no_data == 0,
        }
    }

    /// The summary of a pyramid drawn from its error maps: the rings' Ulrich
    /// rule takes each level's finest mesh error, the tiles their maps'
    /// floors and reference deltas.
    pub fn of_maps(pyramid: &PyramidInfo, maps: &StoreInfo) -> Self {
        TerrainSummary {
            delta_per_level: maps.finest_error_per_level(),
            map_errors: maps.map_errors(),
            ..TerrainSummary::from_pyramid(pyramid)
        }
    }

    /// The summary of the procedural earth: each level's delta bound and
    /// the heights its samples can reach.
    pub fn from_procedural(earth: &ProceduralEarth) -> Self {
        let levels = earth.layout().levels;
        let [low, high] = earth.height_bounds();
        let deltas: Vec<f64> = (0..levels).map(|l| earth.delta_bound(l) as f64).collect();
        TerrainSummary {
            grid_delta_per_level: deltas.clone(),
            delta_per_level: deltas,
            height_range: (low as f32, high as f32),
            map_errors: MapErrors::default(),
            gapless: true,
        }
    }
}

/// Borrows a clipmap for one frame.
pub struct ClipmapTerrain<'a> {
    /// The clipmap whose node atlas the tiles read.
    pub clipmap: &'a Clipmap,
    /// Deltas and height range of the data behind it.
    pub summary: &'a TerrainSummary,
}

impl ResidentNodes for ClipmapTerrain<'_> {
    fn layout(&self) -> &NodeLayout {
        self.clipmap.layout()
    }

    fn resident(&self, id: NodeId) -> Option<&NodeData> {
        let atlas = self.clipmap.atlas();
        let slot = atlas.slot_of(id)?;
        (atlas.state(slot) != SlotState::Empty).then(|| atlas.data(slot))
    }

    fn is_stored(&self, id: NodeId) -> bool {
        self.clipmap.has_node(id)
    }
}

impl TileBounds for ClipmapTerrain<'_> {
    fn posts(&self) -> [u32; 2] {
        self.clipmap.layout().posts
    }

    fn spacing_m(&self) -> [f64; 2] {
        self.clipmap.layout().spacing_m
    }

    fn height_bounds(&self, tile: TileKey, grid_size: u32) -> (f32, f32) {
        node_height_bounds(self, tile, grid_size, self.summary.height_range)
    }

    fn has_finer_data(&self, tile: TileKey, grid_size: u32) -> bool {
        children_node_stored(tile, grid_size, self.clipmap.layout(), |id| self.clipmap.has_node(id))
    }
}

impl TerrainData for ClipmapTerrain<'_> {
    fn delta_per_level(&self) -> Vec<f64> {
        self.summary.delta_per_level.clone()
    }

    fn grid_delta_per_level(&self) -> Vec<f64> {
        self.summary.grid_delta_per_level.clone()
    }

    fn height_range(&self) -> (f32, f32) {
        self.summary.height_range
    }

    fn map_errors(&self) -> MapErrors {
        self.summary.map_errors.clone()
    }

    fn gapless(&self) -> bool {
        self.summary.gapless
    }
}
