//! What the scene reads terrain through: resident nodes for the tiles, height
//! bounds for culling, and the pyramid's per-level error. The clipmap serves
//! it while flying; [`PreloadedTerrain`] holds every node of a small pyramid
//! (tests, ground truth).

use crate::lod::select::{children_node_stored, TileBounds};
use crate::lod::TileKey;
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::tiles::errors::MapErrors;
use crate::tiles::vertex::tile_node;
use crate::tiles::{best_resident, ResidentNodes};
use std::collections::HashMap;

/// Terrain as the scene sees it.
pub trait TerrainData: ResidentNodes + TileBounds {
    /// Largest geometric error of each level, metres (level 0 first).
    fn delta_per_level(&self) -> Vec<f64>;
    /// Largest error of each level's regular grid of posts, metres: what
    /// a tile made as a grid errs by where the source also keeps node
    /// meshes (whose errors `delta_per_level` gives). The same without them.
    fn grid_delta_per_level(&self) -> Vec<f64>;
    /// Lowest and highest height of the data, metres.
    fn height_range(&self) -> (f32, f32);
    /// What each level's error maps can do (empty without maps).
    fn map_errors(&self) -> MapErrors;
    /// Whether every post inside the data's rectangle has data: the horizon
    /// culls only then (its occluder is the drawn surface, and a no-data
    /// outline or void draws none).
    fn gapless(&self) -> bool;
}

/// Height bounds of a tile from the finest resident node that covers it:
/// every level-0 sample under a node lies within its posts' range widened by
/// its delta.
pub fn node_height_bounds(
    nodes: &dyn ResidentNodes,
    tile: TileKey,
    grid_size: u32,
    fallback: (f32, f32),
) -> (f32, f32) {
    let (node, _) = tile_node(tile, grid_size, nodes.layout().node_size);
    match best_resident(nodes, node) {
        Some((_, data)) => (data.min - data.delta, data.max + data.delta),
        None => fallback,
    }
}

/// Every node of a source, read once and kept.
pub struct PreloadedTerrain {
    layout: NodeLayout,
    nodes: HashMap<NodeId, NodeData>,
    deltas: Vec<f64>,
    grid_deltas: Vec<f64>,
    range: (f32, f32),
    maps: MapErrors,
    /// No node holds a post without data.
    gapless: bool,
}

impl PreloadedTerrain {
    /// Reads all present nodes of `source` (meant for pyramids of a few
    /// thousand nodes); absent ones are left out, as the clipmap leaves them.
    pub fn load(source: &dyn NodeSource) -> Result<Self, NodeError> {
        let layout = *source.layout();
        let mut nodes = HashMap::new();
        let mut deltas = vec![0.0f64; layout.levels as usize];
        let mut grid_deltas = deltas.clone();
        let mut maps =
            MapErrors { floor: deltas.clone(), reference: deltas.clone(), max: deltas.clone() };
        let mut range = (f32::INFINITY, f32::NEG_INFINITY);
        for lod in 0..layout.levels {
            let [nx, ny] = layout.nodes_at(lod);
            for y in 0..ny {
                for x in 0..nx {
                    let id = NodeId::new(lod, x, y);
                    if !source.has_node(id) {
                        continue;
                    }
                    let mut data = NodeData::default();
                    source.read_node(id, &mut data)?;
                    deltas[lod as usize] = deltas[lod as usize].max(data.delta as f64);
                    let grid = &mut grid_deltas[lod as usize];
                    *grid = grid.max(data.grid_delta as f64);
                    let l = lod as usize;
                    maps.floor[l] = maps.floor[l].max(data.map.floor_m as f64);
                    maps.reference[l] = maps.reference[l].max(data.map.reference_delta as f64);
                    let coarsest = data.map.codes.iter().filter(|&&c| c < 255).max();
                    let coarsest = coarsest.map_or(0.0, |&c| crate::mesh::code::code_error(c));
                    maps.max[l] = maps.max[l].max(coarsest);
                    // Every level: a layered pyramid's level 0 is sparse.
                    range = (range.0.min(data.min), range.1.max(data.max));
                    nodes.insert(id, data);
                }
            }
        }
        // A source without maps draws grids: its summary says so.
        let any_map = nodes.values().any(|d| !d.map.is_empty());
        let maps = if any_map { maps } else { MapErrors::default() };
        // Past the data's edge a node repeats the edge post: NaN is a post
        // without data (a void left, or a no-data outline).
        let gapless = nodes.values().all(|d| d.heights.iter().all(|h| !h.is_nan()));
        Ok(PreloadedTerrain { layout, nodes, deltas, grid_deltas, range, maps, gapless })
    }
}

impl ResidentNodes for PreloadedTerrain {
    fn layout(&self) -> &NodeLayout {
        &self.layout
    }

    fn resident(&self, id: NodeId) -> Option<&NodeData> {
        self.nodes.get(&id)
    }

    fn is_stored(&self, id: NodeId) -> bool {
        self.nodes.contains_key(&id)
    }
}

impl TileBounds for PreloadedTerrain {
    fn posts(&self) -> [u32; 2] {
        self.layout.posts
    }

    fn spacing_m(&self) -> [f64; 2] {
        self.layout.spacing_m
    }

    fn height_bounds(&self, tile: TileKey, grid_size: u32) -> (f32, f32) {
        node_height_bounds(self, tile, grid_size, self.range)
    }

    fn has_finer_data(&self, tile: TileKey, grid_size: u32) -> bool {
        children_node_stored(tile, grid_size, &self.layout, |id| self.nodes.contains_key(&id))
    }
}

impl TerrainData for PreloadedTerrain {
    fn delta_per_level(&self) -> Vec<f64> {
        self.deltas.clone()
    }

    fn grid_delta_per_level(&self) -> Vec<f64> {
        self.grid_deltas.clone()
    }

    fn height_range(&self) -> (f32, f32) {
        self.range
    }

    fn map_errors(&self) -> MapErrors {
        self.maps.clone()
    }

    fn gapless(&self) -> bool {
        self.gapless
    }
}
