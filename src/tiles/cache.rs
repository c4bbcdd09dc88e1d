//! Which tiles have their mesh in the GPU buffer, where, and from which
//! level of data it was made.
//!
//! Each tile in use owns one block of the [`ContiguousAllocator`]: its
//! vertices, then its indices ([`super::block`]); its generator id is the
//! tile's slot in a fixed table. Per frame:
//! 1. tiles the selection no longer uses give their blocks back;
//! 2. tiles that are new, or whose best resident data is now finer than what
//!    they were made from, announce their size, each its own (pass 1);
//! 3. the run is placed and each such tile fills its block (pass 2);
//! 4. the dirty ranges, one per run piece, are what the GPU must receive.
//!
//! A still camera with settled data announces nothing and uploads nothing.
//! The root level's tiles are made once and never released, so whatever
//! happens to the buffer there is always a coarse tile to draw.

use super::block::TileVertex;
use super::block::{write_block, MeshCounts, BLOCK_ALIGNMENT};
use super::by_distance::DistanceRule;
use super::errors::{ErrorStep, MeshErrors, TileErrors};
use super::extract::{forced_step, Extraction, Extractor, PlacedMap, TargetMesh};
use super::grid::{self, TileGrid};
use super::mesh_tile::{CutInputs, MeshCutter, TileSquare};
use super::seams::{seams_of, Seams};
use super::vertex::{fill_tile, tile_node, PostReader, TileCoverage};
use super::{best_resident, ResidentNodes};
use crate::allocator::{
    AllocError, AllocatorConfig, ConfigError, ContiguousAllocator, GeneratorId, Request,
    VertexFormat,
};
use crate::lod::select::{children_node_stored, tiles_at};
use crate::lod::{SelectedTile, TileKey};
use crate::node::{ErrorMap, NodeData, NodeId, NodeLayout};
use arrayvec::ArrayVec;
use std::collections::HashMap;
use std::ops::Range;

/// Sizes fixed when the cache is built.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TileCacheConfig {
    /// Cells per tile side; divides the node size.
    pub grid_size: u32,
    /// Bytes of the GPU vertex buffer (and its staging copy).
    pub capacity_bytes: u32,
    /// Tiles that may be resident at once, root tiles included.
    pub max_tiles: u32,
    /// Longest single transfer in bytes; `None` for one transfer per frame.
    pub transfer_cap: Option<u32>,
    /// Frames a released tile's bytes stay out of reuse (0: reusable at once).
    pub frames_in_flight: u32,
}

/// A tile to draw: where its block's vertices and indices are and what
/// data made it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileDraw {
    /// The tile: its level and position.
    pub key: TileKey,
    /// Where its block (its vertices) starts in the GPU buffer and the
    /// staging copy, bytes.
    pub byte_offset: u32,
    /// Where its indices start in the same buffer, bytes (right after its
    /// vertices).
    pub index_byte_offset: u32,
    /// Its indices: three per triangle, skirts included.
    pub index_count: u32,
    /// Level-0 posts between its vertices' posts (`u_tile.z`): `2^level`
    /// for a regular grid, half the node mesh's post step for a mesh tile.
    pub vertex_step: f32,
    /// Made from a node's mesh (its edges are shared only with tiles cut
    /// from the same node mesh), not as a regular grid of posts.
    pub node_mesh: bool,
    /// Level of the node the heights came from (above `key.level` when only
    /// coarser data was resident: best available).
    pub source_level: u8,
    /// Whether some of its posts have no data (never [`TileCoverage::Empty`]:
    /// tiles without data are not drawn).
    pub coverage: TileCoverage,
    /// Its sub-level (a leaf tile nearer than its level's ring; see
    /// [`super::errors`]).
    pub sub_level: u8,
    /// How far the surface it shows may lie from the data along each edge.
    pub errors: EdgeErrors,
    /// Which of its edges meet the neighbouring node's tile alike.
    pub seams: Seams,
}

/// How far a tile's surface may lie from the data along each of its edges
/// (south, east, north, west), metres: its mesh's error and its reference
/// lattice's; NaN where unknown (a grid: its level's tables apply).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeErrors {
    /// Where it has not morphed: its own mesh's.
    pub own_m: [f32; 4],
    /// Fully morphed: the larger of its own mesh's and the mesh it morphs
    /// toward's.
    pub morphed_m: [f32; 4],
}

impl EdgeErrors {
    /// Unknown errors (a grid).
    pub const UNKNOWN: EdgeErrors = EdgeErrors { own_m: [f32::NAN; 4], morphed_m: [f32::NAN; 4] };

    /// The largest fully morphed error along any edge: the tile's (its
    /// square's farthest points are corners).
    pub fn largest_m(&self) -> f32 {
        self.morphed_m.iter().copied().fold(f32::NAN, f32::max)
    }
}

/// How a resident tile was made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MadeFrom {
    /// The level of the node its heights came from.
    pub source_level: u8,
    /// Extracted from the node's error map (else a grid of its posts).
    pub node_mesh: bool,
    /// How far its surface may lie from the data, metres (NaN for a grid:
    /// its level's grid delta).
    pub error_m: f32,
}

/// What one frame of the cache did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TileFrameStats {
    /// Tiles selected this frame.
    pub tiles: usize,
    /// Tiles whose block was made this frame: new ones and ones remade from finer data.
    pub generated: usize,
    /// Tiles released this frame because the selection no longer uses them.
    pub released: usize,
    /// Bytes of the staging copy uploaded this frame.
    pub bytes_uploaded: u64,
    /// Transfers this frame: one per run piece (dirty range).
    pub transfers: usize,
    /// Bytes held by resident tiles after the frame.
    pub allocator_used_bytes: u64,
    /// End of the highest block not free after the frame: the buffer size this state needs, bytes.
    pub allocator_workspace_bytes: u32,
}

/// Why the tile cache cannot be built or cannot make a frame's tiles.
#[derive(Debug, thiserror::Error)]
pub enum TileError {
    /// The allocator refused the configuration.
    #[error("tile cache configuration: {0}")]
    Config(#[from] ConfigError),
    /// The tile grid size does not divide the node size.
    #[error("grid size {grid} does not divide the node size {node}")]
    Grid {
        /// Cells per tile side.
        grid: u32,
        /// Cells per node side.
        node: u32,
    },
    /// The root level alone has more tiles than the cache may hold.
    #[error("the root level needs {needed} tiles but the cache holds {max}")]
    RootTooLarge {
        /// Tiles of the root level.
        needed: usize,
        /// Tiles the cache holds (`max_tiles`).
        max: u32,
    },
    /// No node covering the tile, nor any of its ancestors, is resident.
    #[error("no resident node covers tile {0:?}: the root level must stay resident")]
    NoData(TileKey),
    /// More tiles are selected (or would be resident) than the cache holds.
    #[error("{selected} tiles selected, the cache holds {max}")]
    TooManyTiles {
        /// Tiles selected, or resident with the one that found no slot.
        selected: usize,
        /// Tiles the cache holds (`max_tiles`).
        max: u32,
    },
    /// The GPU buffer cannot take this frame's new tiles; select coarser tiles
    /// and call again (the tiles already resident are untouched).
    #[error("GPU buffer full: {0}")]
    BufferFull(AllocError),
}

/// Which mesh a tile is made as: what decides its block's size (asked per
/// tile before placement) and what fills it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TileMeshKind {
    /// The regular grid of `grid_size` cells with skirts ([`TileGrid`]), of
    /// the source node's posts.
    #[default]
    Grid,
    /// The triangles of the source node's mesh inside the tile's square
    /// ([`super::mesh_tile`]).
    NodeMesh(TileSquare),
}

impl TileMeshKind {
    /// Level-0 posts between the tile's vertex posts (`u_tile.z`): a
    /// node mesh counts half steps of its lattice (cell centres are vertices).
    pub fn vertex_step(self, key: TileKey) -> f32 {
        match self {
            TileMeshKind::Grid => (1u32 << key.level) as f32,
            TileMeshKind::NodeMesh(square) => square.step as f32 / 2.0,
        }
    }
}

/// Whether tile `key` has finer data: its child node is stored.
fn has_finer_data(nodes: &dyn ResidentNodes, key: TileKey, grid_size: u32) -> bool {
    let layout = nodes.layout();
    children_node_stored(key, grid_size, layout, |id| nodes.is_stored(id))
}

/// What tiles are made with: the regular grid (its vertices the scratch a
/// grid tile is made in), the extractor of meshes from error maps, the
/// cutter that adds their skirts, and their scratch.
struct TileMaker {
    grid: TileGrid,
    extractor: Extractor,
    cutter: MeshCutter,
    vertices: Vec<TileVertex>,
    indices: Vec<u16>,
}

/// One tile to make: which node it is made from and with what errors.
#[derive(Clone, Copy)]
struct MakeSpec<'a> {
    key: TileKey,
    source: NodeId,
    data: &'a NodeData,
    errors: TileErrors,
}

impl TileMaker {
    /// How tile `key` is made from `spec.source`'s data, and its size:
    /// extracted from the node's error map where it has one whose lattice
    /// the tile's square covers, else as the regular grid of the node's
    /// posts.
    fn plan(
        &mut self,
        nodes: &dyn ResidentNodes,
        spec: MakeSpec<'_>,
        mesh_errors: &MeshErrors,
    ) -> (TileMeshKind, MeshCounts) {
        let layout = *nodes.layout();
        if let Some(square) = map_square(&layout, spec.key, self.grid.grid_size, spec) {
            if self.extract(nodes, spec, square, mesh_errors).is_ok() {
                if let Some(size) = self.cutter.cut(&self.extractor.mesh, square) {
                    let counts = MeshCounts {
                        vertices: size.vertices as u32,
                        indices: size.indices as u32,
                        skirt_indices: size.skirt_indices as u32,
                    };
                    if counts.vertices <= 1 << 16 {
                        return (TileMeshKind::NodeMesh(square), counts);
                    }
                }
            }
        }
        (TileMeshKind::Grid, grid::counts(self.grid.grid_size))
    }

    /// Extracts the tile's mesh from the source's map and its resident
    /// ancestors' into the extractor.
    fn extract(
        &mut self,
        nodes: &dyn ResidentNodes,
        spec: MakeSpec<'_>,
        square: TileSquare,
        mesh_errors: &MeshErrors,
    ) -> Result<(), super::extract::ExtractError> {
        let layout = nodes.layout();
        let grid_size = self.grid.grid_size;
        let place = |id, data, error_m, view| place_map(layout, grid_size, id, data, error_m, view);
        let own_level = spec.source.level == spec.key.level;
        // On the stack: tiles are made in frames, which allocate nothing
        // once their scratch has grown.
        let mut chain: ArrayVec<PlacedMap<'_>, { crate::pyramid::MAX_LEVELS as usize }> =
            ArrayVec::new();
        let mut id = spec.source;
        while let Some(parent) = id.parent().filter(|p| p.level < layout.levels) {
            if let Some(data) = nodes.resident(parent).filter(|d| !d.map.is_empty()) {
                // As the ancestor's own tiles are made (`band_rule`).
                let above = parent.parent().is_some_and(|p| nodes.resident(p).is_some());
                let view = band_rule(mesh_errors, parent.level, 0, above);
                chain.push(place(parent, data, level_error(mesh_errors, parent.level), view));
            }
            id = parent;
        }
        let parent_resident = chain.first().is_some_and(|p| Some(p.node()) == spec.source.parent());
        let sub_level = spec.errors.sub_level;
        // Split at the tile's square like the neighbour of the coarser
        // sub-level is: the shared edge then morphs onto that neighbour's.
        let coarser = (own_level && sub_level > 0).then(|| {
            let view = mesh_errors.target_rule(spec.key.level, sub_level, parent_resident);
            let mut coarser = place(spec.source, spec.data, spec.errors.target.metres(), view);
            coarser.set_forced(square.width.min(coarser.forced()));
            coarser.as_target();
            coarser
        });
        let target = match &coarser {
            Some(c) => TargetMesh::Coarser(c),
            None if own_level && parent_resident => TargetMesh::Parent,
            None => TargetMesh::None,
        };
        let own_view = own_level
            .then(|| band_rule(mesh_errors, spec.key.level, sub_level, parent_resident))
            .flatten();
        let mut own = place(spec.source, spec.data, spec.errors.own.metres(), own_view);
        own.set_forced(square.width.min(own.forced()));
        let job = Extraction {
            own: &own,
            ancestors: &chain,
            target,
            origin: square.origin,
            width: square.width,
            place_parent: coarser.is_some() && parent_resident,
        };
        self.extractor.extract(&job)
    }

    /// Makes the tile's mesh into `block` (its planned size): vertices,
    /// then indices.
    fn fill(
        &mut self,
        nodes: &dyn ResidentNodes,
        job: &Job,
        key: TileKey,
        mesh_errors: &MeshErrors,
        block: &mut [u8],
    ) -> TileCoverage {
        let layout = *nodes.layout();
        let data = nodes.resident(job.source).expect("resident since mark_selected");
        let grid_size = self.grid.grid_size;
        let reader = PostReader::new(&layout, key, grid_size, job.source, data);
        match job.kind {
            TileMeshKind::Grid => {
                let scale = 2f64.powi(key.level as i32);
                let spacing = [layout.spacing_m[0] * scale, layout.spacing_m[1] * scale];
                let grid = &mut self.grid;
                let coverage = fill_tile(&reader, grid.grid_size, spacing, &mut grid.vertices);
                write_block(block, &grid.vertices, &grid.indices);
                coverage
            }
            TileMeshKind::NodeMesh(square) => {
                let spec = MakeSpec { key, source: job.source, data, errors: job.errors };
                self.extract(nodes, spec, square, mesh_errors).expect("planned from the same maps");
                let mesh = &self.extractor.mesh;
                let size = self.cutter.cut(mesh, square).expect("planned from the same mesh");
                self.vertices.resize(size.vertices, TileVertex::default());
                self.indices.resize(size.indices, 0);
                let span = (layout.node_size as u64) << job.source.level;
                let inputs = CutInputs {
                    mesh,
                    square,
                    reader: &reader,
                    tile_step: 1 << key.level,
                    node_origin: [job.source.x as u64 * span, job.source.y as u64 * span],
                    last_post: layout.posts.map(|p| p as u64 - 1),
                    own_level: job.source.level == key.level,
                };
                let coverage = self.cutter.fill(&inputs, &mut self.vertices, &mut self.indices);
                write_block(block, &self.vertices, &self.indices);
                coverage
            }
        }
    }
}

/// How far a tile's surface may lie from the data along each edge (south,
/// east, north, west), metres, unmorphed and fully morphed: the error it
/// was extracted at (or the mesh it morphs toward's), plus its reference
/// lattice's; NaN for a grid (its level's grid delta applies). Where its
/// errors grow with the distance, the largest they reach along the edge:
/// its skirt fills a crack no deeper.
fn tile_error(
    kind: TileMeshKind,
    spec: MakeSpec<'_>,
    layout: &NodeLayout,
    grid_size: u32,
    errors: &MeshErrors,
) -> EdgeErrors {
    let own_level = spec.source.level == spec.key.level;
    if kind == TileMeshKind::Grid {
        return EdgeErrors::UNKNOWN;
    }
    let (level, sub) = (spec.key.level, spec.errors.sub_level);
    let map = &spec.data.map;
    let reference = map.reference_delta as f64;
    // Along a level-0 node's own (not shared) edges the meshes keep their
    // vertices' rings' near-end errors (`super::extract`).
    let per_node = (layout.node_size / grid_size).max(1);
    let on_boundary = |edge: usize| {
        spec.source.level == 0
            && map.shared_edges & ErrorMap::BY_TILE_EDGE[edge] == 0
            && match edge {
                0 => spec.key.y % per_node == 0,
                1 => (spec.key.x + 1) % per_node == 0,
                2 => (spec.key.y + 1) % per_node == 0,
                _ => spec.key.x % per_node == 0,
            }
    };
    let edge = |edge: usize| {
        let largest = |level: u8, sub: u8, step: ErrorStep| {
            let rule = errors.rule(level, sub, true).filter(|_| own_level);
            let far = |rule: &DistanceRule| {
                let anchors = rule.rings.iter().map(|b| b.anchor_m);
                let far = anchors.map(|a| edge_far_m(spec.key, grid_size, layout, a, edge));
                far.fold(0.0, f64::max)
            };
            // Along a boundary each vertex keeps its ring's near-end error
            // (`super::extract`).
            let largest = |r: &DistanceRule| match on_boundary(edge) {
                true => r.near_end_within(far(r)),
                false => r.largest_within(far(r)),
            };
            rule.map_or(step.metres(), |r| largest(&r).max(step.metres()))
        };
        let own = largest(level, sub, spec.errors.own).max(map.floor_m as f64);
        let morph = match (own_level, sub) {
            (false, _) => 0.0,
            (true, 0) => largest(level + 1, 0, spec.errors.target),
            (true, k) => largest(level, k - 1, spec.errors.target),
        };
        ((own + reference) as f32, (own.max(morph) + reference) as f32)
    };
    let edges: [(f32, f32); 4] = std::array::from_fn(edge);
    EdgeErrors { own_m: edges.map(|e| e.0), morphed_m: edges.map(|e| e.1) }
}

/// The distance from `anchor_m` (chart metres) to the farther end of edge
/// `edge` (south, east, north, west) of tile `key`'s square, metres.
fn edge_far_m(
    key: TileKey,
    grid_size: u32,
    layout: &NodeLayout,
    anchor_m: [f64; 2],
    edge: usize,
) -> f64 {
    let span = ((grid_size as u64) << key.level) as f64;
    let sw = [key.x as f64 * span, key.y as f64 * span];
    let ends = match edge {
        0 => [[0.0, 0.0], [1.0, 0.0]],
        1 => [[1.0, 0.0], [1.0, 1.0]],
        2 => [[0.0, 1.0], [1.0, 1.0]],
        _ => [[0.0, 0.0], [0.0, 1.0]],
    };
    let distance = |end: [f64; 2]| {
        let at = [0, 1].map(|k| (sw[k] + end[k] * span) * layout.spacing_m[k] - anchor_m[k]);
        at[0].hypot(at[1])
    };
    distance(ends[0]).max(distance(ends[1]))
}

/// Node `id`'s map placed for meshes of `error_m`, or of errors growing
/// with the distance as `view` says, split at least to the squares of its
/// own level's tiles (`grid_size` cells).
fn place_map<'a>(
    layout: &'a NodeLayout,
    grid_size: u32,
    id: NodeId,
    data: &'a NodeData,
    error_m: f64,
    view: Option<DistanceRule>,
) -> PlacedMap<'a> {
    let map = &data.map;
    let tile_posts = grid_size << (id.level - map.post_level.min(id.level));
    // The curvature caps the widest triangle by the band's least error:
    // a wider one would sag more than the tile's nearest part allows. With
    // a view each split checks its own error (`PlacedMap::is_vertex`).
    let sag_error_m = if view.is_some() { f64::INFINITY } else { error_m };
    let forced = forced_step(layout, map.post_level, map.cells, tile_posts, sag_error_m);
    let placed = PlacedMap::new(layout, id, data, error_m, forced);
    match view {
        Some(view) => placed.with_view(view),
        None => placed,
    }
}

/// Tile `key`'s square (`grid_size` cells a side) in chart metres: its
/// south-west and north-east corners.
fn tile_rectangle_m(layout: &NodeLayout, grid_size: u32, key: TileKey) -> ([f64; 2], [f64; 2]) {
    let span = ((grid_size as u64) << key.level.min(63)) as f64;
    let corner = |k: usize, t: u32| t as f64 * span * layout.spacing_m[k];
    ([corner(0, key.x), corner(1, key.y)], [corner(0, key.x + 1), corner(1, key.y + 1)])
}

/// The errors by distance a tile of `level`'s sub-level `sub` is made with
/// (`None` before the frame set them: one error); `above`: its level's
/// parent is resident, so past its level's band it keeps only the parent's
/// vertices.
fn band_rule(errors: &MeshErrors, level: u8, sub: u8, above: bool) -> Option<DistanceRule> {
    errors.rule(level, sub, above)
}

/// The error a level's tiles are extracted at this frame, metres.
fn level_error(errors: &MeshErrors, level: u8) -> f64 {
    errors.level.get(level as usize).map_or(0.0, |s| s.metres())
}

/// The tile's square in its source's map, when the source has a map and
/// the tile covers whole posts of its lattice.
fn map_square(
    layout: &NodeLayout,
    key: TileKey,
    grid_size: u32,
    spec: MakeSpec<'_>,
) -> Option<TileSquare> {
    let map = &spec.data.map;
    if map.is_empty() {
        return None;
    }
    TileSquare::of(layout, key, grid_size, spec.source, map.post_level)
}

#[derive(Clone, Copy, Debug)]
struct Resident {
    key: TileKey,
    source_level: u8,
    /// The errors it was made with.
    errors: TileErrors,
    /// Whether its parent node was resident when it was made (its mesh
    /// then refines the parent's; made again once it is).
    parent_resident: bool,
    /// How far its surface may lie from the data along each edge.
    errors_m: EdgeErrors,
    /// Which of its edges meet the neighbouring node's tile alike.
    seams: Seams,
    /// The error its ring allowed when made, not quantised.
    allowed_m: f64,
    coverage: TileCoverage,
    /// What its block holds.
    mesh: MeshCounts,
    /// How it was made.
    kind: TileMeshKind,
    last_frame: u64,
    pinned: bool,
}

/// Pending generation of one tile this frame.
#[derive(Clone, Copy)]
struct Job {
    slot: u32,
    new: bool,
    /// The resident node the tile's heights come from.
    source: NodeId,
    /// The errors it is made with.
    errors: TileErrors,
    /// Whether the source's parent is resident.
    parent_resident: bool,
    /// How far its surface may lie from the data along each edge.
    errors_m: EdgeErrors,
    /// Which of its edges meet the neighbouring node's tile alike.
    seams: Seams,
    /// The error its ring allowed, not quantised ([`MeshErrors::allowed_m`]).
    allowed_m: f64,
    /// The mesh it is made as, and its size.
    kind: TileMeshKind,
    mesh: MeshCounts,
}

/// The tiles resident in the GPU buffer: one allocator block each, keyed by [`TileKey`],
/// with the level of data each was made from.
pub struct TileCache {
    config: TileCacheConfig,
    allocator: ContiguousAllocator,
    slots: Vec<Option<Resident>>,
    spare: Vec<u32>,
    by_key: HashMap<TileKey, u32>,
    frame: u64,
    requests: Vec<Request>,
    jobs: Vec<Job>,
    draws: Vec<TileDraw>,
    dirty: Vec<Range<u32>>,
    /// The regular grid; its vertices are the scratch a tile is made in.
    maker: TileMaker,
    stats: TileFrameStats,
}

impl TileCache {
    /// Builds the cache and makes the root level's tiles from `nodes`.
    pub fn new(config: TileCacheConfig, nodes: &dyn ResidentNodes) -> Result<Self, TileError> {
        let layout = *nodes.layout();
        if layout.node_size % config.grid_size != 0 {
            return Err(TileError::Grid { grid: config.grid_size, node: layout.node_size });
        }
        let alloc_config = AllocatorConfig {
            capacity: config.capacity_bytes,
            max_generators: config.max_tiles,
            alignment: BLOCK_ALIGNMENT,
            transfer_cap: config.transfer_cap,
            frames_in_flight: config.frames_in_flight,
        };
        let max = config.max_tiles as usize;
        let mut cache = TileCache {
            config,
            allocator: ContiguousAllocator::new(alloc_config)?,
            slots: vec![None; max],
            spare: (0..config.max_tiles).rev().collect(),
            by_key: HashMap::with_capacity(max),
            frame: 0,
            requests: Vec::with_capacity(max),
            jobs: Vec::with_capacity(max),
            draws: Vec::with_capacity(max),
            dirty: Vec::with_capacity(max),
            maker: TileMaker {
                grid: TileGrid::new(config.grid_size),
                extractor: Extractor::default(),
                cutter: MeshCutter::default(),
                vertices: Vec::new(),
                indices: Vec::new(),
            },
            stats: TileFrameStats::default(),
        };
        cache.make_root_tiles(nodes)?;
        Ok(cache)
    }

    /// The sizes the cache was built with.
    pub fn config(&self) -> &TileCacheConfig {
        &self.config
    }

    /// Makes the tile list for `selected`: releases unused tiles, generates
    /// new or improved ones, and lists the draws. On `BufferFull` nothing that
    /// was resident before has changed except that unused tiles were released.
    pub fn update(
        &mut self,
        selected: &[SelectedTile],
        nodes: &dyn ResidentNodes,
        errors: &MeshErrors,
    ) -> Result<&[TileDraw], TileError> {
        self.frame += 1;
        self.allocator.begin_frame();
        self.stats = TileFrameStats::default();
        self.dirty.clear();
        self.retake(selected, nodes, errors)
    }

    /// [`Self::update`] again within the same frame, for another selection
    /// (a frame budget's correction once the tiles' real counts are
    /// known): what the first made stays resident this frame and its dirty
    /// ranges are kept, so the GPU still receives every block made.
    pub fn retake(
        &mut self,
        selected: &[SelectedTile],
        nodes: &dyn ResidentNodes,
        errors: &MeshErrors,
    ) -> Result<&[TileDraw], TileError> {
        self.stats.tiles = selected.len();
        // Unused tiles go first so that their slots and bytes can serve new ones.
        for tile in selected {
            if let Some(&slot) = self.by_key.get(&tile.key) {
                self.slots[slot as usize].as_mut().expect("mapped slots are full").last_frame =
                    self.frame;
            }
        }
        self.release_unused();
        self.mark_selected(selected, nodes, errors)?;
        if !self.requests.is_empty() {
            self.generate(nodes, errors)?;
        }
        self.list_draws(selected);
        let stats = self.allocator.stats();
        self.stats.allocator_used_bytes = stats.live_bytes;
        self.stats.allocator_workspace_bytes = stats.workspace_end;
        Ok(&self.draws)
    }

    /// Triangles of the last update's draws, skirts included.
    pub fn drawn_triangles(&self) -> u64 {
        self.draws.iter().map(|d| d.index_count as u64 / 3).sum()
    }

    /// The draws of the last successful update, in memory order.
    pub fn draws(&self) -> &[TileDraw] {
        &self.draws
    }

    /// The ranges of the staging copy the GPU must receive this frame.
    pub fn dirty_ranges(&self) -> &[Range<u32>] {
        &self.dirty
    }

    /// The staging copy (the GPU buffer mirrors it at the same offsets).
    pub fn staging(&self) -> &[u8] {
        self.allocator.staging()
    }

    /// What the last update did.
    pub fn stats(&self) -> TileFrameStats {
        self.stats
    }

    /// Triangles of `key`'s block, skirts included, and the error it was
    /// extracted at (NaN for a grid), when it is resident (a frame
    /// budget's estimate before the tiles are made).
    pub fn resident_triangles(&self, key: TileKey) -> Option<(u64, f64)> {
        self.resident_parts(key).map(|(surface, skirts, error)| (surface + skirts, error))
    }

    /// [`Self::resident_triangles`] parted: the surface's, the skirts'
    /// (0 for a grid, whose skirts are not counted apart), and the error.
    pub fn resident_parts(&self, key: TileKey) -> Option<(u64, u64, f64)> {
        let slot = *self.by_key.get(&key)?;
        let resident = self.slots.get(slot as usize)?.as_ref()?;
        let error = match resident.kind {
            TileMeshKind::Grid => f64::NAN,
            // Errors grow with the distance in steps: the ring's allowed
            // error at its near end moves with tau smoothly.
            TileMeshKind::NodeMesh(_) => resident.allowed_m,
        };
        let skirts = resident.mesh.skirt_indices as u64 / 3;
        Some((resident.mesh.indices as u64 / 3 - skirts, skirts, error))
    }

    /// How `key`'s resident tile was made: the level of the node it came
    /// from (above `key.level` when only coarser data was resident: best
    /// available), and whether it was cut from that node's mesh (else made
    /// as a grid of its posts).
    pub fn made_from(&self, key: TileKey) -> Option<MadeFrom> {
        let slot = *self.by_key.get(&key)?;
        let resident = self.slots.get(slot as usize)?.as_ref()?;
        Some(MadeFrom {
            source_level: resident.source_level,
            node_mesh: resident.kind != TileMeshKind::Grid,
            error_m: resident.errors_m.largest_m(),
        })
    }

    /// Resident tiles (for statistics and tests).
    pub fn resident_count(&self) -> usize {
        self.by_key.len()
    }

    fn make_root_tiles(&mut self, nodes: &dyn ResidentNodes) -> Result<(), TileError> {
        let layout = *nodes.layout();
        let root = layout.levels - 1;
        let [nx, ny] = tiles_at(layout.posts, self.config.grid_size, root);
        let needed = (nx * ny) as usize;
        if needed > self.config.max_tiles as usize {
            return Err(TileError::RootTooLarge { needed, max: self.config.max_tiles });
        }
        let roots: Vec<SelectedTile> = (0..ny)
            .flat_map(|y| {
                (0..nx).map(move |x| SelectedTile { key: TileKey::new(root, x, y), distance: 0.0 })
            })
            .collect();
        self.update(&roots, nodes, &MeshErrors::default())?;
        for slot in self.slots.iter_mut().flatten() {
            slot.pinned = true;
        }
        Ok(())
    }

    /// Finds or reserves each selected tile's slot and queues the ones that
    /// need their block made (new, or finer data is resident now), each
    /// with its own size.
    fn mark_selected(
        &mut self,
        selected: &[SelectedTile],
        nodes: &dyn ResidentNodes,
        mesh_errors: &MeshErrors,
    ) -> Result<(), TileError> {
        self.requests.clear();
        self.jobs.clear();
        if selected.len() > self.config.max_tiles as usize {
            return Err(TileError::TooManyTiles {
                selected: selected.len(),
                max: self.config.max_tiles,
            });
        }
        let layout = *nodes.layout();
        let grid_size = self.config.grid_size;
        for tile in selected {
            let (node, _) = tile_node(tile.key, grid_size, layout.node_size);
            let (source, data) = best_resident(nodes, node).ok_or(TileError::NoData(tile.key))?;
            let leaf = !has_finer_data(nodes, tile.key, grid_size);
            let (lo, hi) = tile_rectangle_m(&layout, grid_size, tile.key);
            let width_m = (hi[0] - lo[0]).max(hi[1] - lo[1]);
            let ground = mesh_errors.ground_distance(lo, hi);
            let distance = MeshErrors::leaf_distance(ground, width_m);
            let errors = mesh_errors.for_tile(tile.key.level, distance, leaf);
            let parent_resident = source.parent().is_some_and(|p| nodes.resident(p).is_some());
            let (slot, new) = match self.by_key.get(&tile.key) {
                Some(&slot) => (slot, false),
                None => (self.reserve(tile.key, source.level)?, true),
            };
            let resident = self.slots[slot as usize].as_mut().expect("reserved");
            resident.last_frame = self.frame;
            let stale = resident.kind != TileMeshKind::Grid
                && (resident.errors != errors || (parent_resident && !resident.parent_resident));
            if new || source.level < resident.source_level || stale {
                let spec = MakeSpec { key: tile.key, source, data, errors };
                let (kind, mesh) = self.maker.plan(nodes, spec, mesh_errors);
                // A grid of posts has no sub-levels: it morphs toward its
                // parent level's posts from its level's ring, as ever.
                let errors =
                    if kind == TileMeshKind::Grid { TileErrors::default() } else { errors };
                self.requests.push(Request {
                    generator: GeneratorId(slot),
                    format: VertexFormat(0),
                    size: mesh.block_bytes(),
                });
                let errors_m = tile_error(kind, spec, &layout, grid_size, mesh_errors);
                let seams = match kind {
                    TileMeshKind::Grid => Seams::default(),
                    _ if source.level != tile.key.level => Seams::default(),
                    _ => seams_of(nodes, tile.key, source, grid_size, errors),
                };
                // What the tile's triangles scale with: its own distance's
                // sub-level (its rule starts finer, for the vertices its
                // splits reach: see `MeshErrors::leaf_distance`).
                let physical = match errors.sub_level {
                    0 => 0,
                    _ => mesh_errors.sub_level(tile.key.level, tile.distance),
                };
                let allowed_m = mesh_errors.allowed_m(tile.key.level, physical);
                self.jobs.push(Job {
                    slot,
                    new,
                    source,
                    errors,
                    parent_resident,
                    errors_m,
                    seams,
                    allowed_m,
                    kind,
                    mesh,
                });
            }
        }
        Ok(())
    }

    fn reserve(&mut self, key: TileKey, source_level: u8) -> Result<u32, TileError> {
        let slot = self.spare.pop().ok_or(TileError::TooManyTiles {
            selected: self.by_key.len() + 1,
            max: self.config.max_tiles,
        })?;
        self.slots[slot as usize] = Some(Resident {
            key,
            source_level,
            errors: TileErrors::default(),
            parent_resident: false,
            errors_m: EdgeErrors::UNKNOWN,
            seams: Seams::default(),
            allowed_m: f64::NAN,
            coverage: TileCoverage::Full,
            mesh: MeshCounts::default(),
            kind: TileMeshKind::Grid,
            last_frame: 0,
            pinned: false,
        });
        self.by_key.insert(key, slot);
        Ok(slot)
    }

    fn release_slot(&mut self, slot: u32) {
        if let Some(resident) = self.slots[slot as usize].take() {
            self.by_key.remove(&resident.key);
            // A slot reserved this frame may not own a block yet.
            self.allocator
                .release(GeneratorId(slot))
                .expect("slot ids are in range and retire room is sized");
            self.spare.push(slot);
        }
    }

    /// Tiles no view uses this frame give their blocks back.
    fn release_unused(&mut self) {
        for slot in 0..self.slots.len() as u32 {
            let unused = matches!(self.slots[slot as usize], Some(r) if r.last_frame != self.frame && !r.pinned);
            if unused {
                self.release_slot(slot);
                self.stats.released += 1;
            }
        }
    }

    /// Places and makes the queued blocks. When the buffer cannot take them
    /// all, finer data for tiles that have data already waits: the
    /// improvements are dropped and the new tiles placed alone, so a small
    /// buffer still takes a coarser selection whose tiles are resident.
    fn generate(
        &mut self,
        nodes: &dyn ResidentNodes,
        errors: &MeshErrors,
    ) -> Result<(), TileError> {
        let mut outcome = self.place(nodes, errors);
        if outcome.is_err() && self.drop_improvements() {
            outcome = self.place(nodes, errors);
        }
        match outcome {
            Ok(bytes_uploaded) => {
                self.stats.generated += self.requests.len();
                self.stats.transfers = self.dirty.len();
                self.stats.bytes_uploaded += bytes_uploaded;
                Ok(())
            }
            Err(error) => {
                self.forget_new_jobs();
                Err(TileError::BufferFull(error))
            }
        }
    }

    /// One placement of the queued requests as a run, making each block;
    /// the bytes made.
    fn place(&mut self, nodes: &dyn ResidentNodes, errors: &MeshErrors) -> Result<u64, AllocError> {
        if self.requests.is_empty() {
            return Ok(0);
        }
        let (slots, maker, dirty, jobs) =
            (&mut self.slots, &mut self.maker, &mut self.dirty, &self.jobs);
        self.allocator.allocate(&self.requests).map(|mut plan| {
            let mut bytes_uploaded = 0u64;
            plan.fill(|index, request, block| {
                let resident = slots[request.generator.0 as usize]
                    .as_mut()
                    .expect("queued tiles are reserved");
                let job = jobs[index];
                debug_assert_eq!(block.len(), job.mesh.block_bytes() as usize);
                resident.coverage = maker.fill(nodes, &job, resident.key, errors, block);
                resident.mesh = job.mesh;
                resident.kind = job.kind;
                resident.source_level = job.source.level;
                resident.errors = job.errors;
                resident.parent_resident = job.parent_resident;
                resident.errors_m = job.errors_m;
                resident.seams = job.seams;
                resident.allowed_m = job.allowed_m;
                bytes_uploaded += block.len() as u64;
            });
            dirty.extend(plan.dirty_ranges().iter().cloned());
            bytes_uploaded
        })
    }

    /// Keeps only the jobs of new tiles and their requests (the two lists
    /// run in step); whether an improvement was dropped.
    fn drop_improvements(&mut self) -> bool {
        let before = self.jobs.len();
        let mut kept = 0;
        for k in 0..before {
            if self.jobs[k].new {
                self.jobs[kept] = self.jobs[k];
                self.requests[kept] = self.requests[k];
                kept += 1;
            }
        }
        self.jobs.truncate(kept);
        self.requests.truncate(kept);
        kept < before
    }

    /// After a failed placement: tiles reserved this frame have no data, so
    /// they are dropped; tiles that were only to be improved keep their data.
    fn forget_new_jobs(&mut self) {
        for k in 0..self.jobs.len() {
            let job = self.jobs[k];
            if job.new {
                self.release_slot(job.slot);
            }
        }
    }

    fn list_draws(&mut self, selected: &[SelectedTile]) {
        self.draws.clear();
        for tile in selected {
            let slot = self.by_key[&tile.key];
            let resident = self.slots[slot as usize].expect("selected tiles are resident");
            if resident.coverage == TileCoverage::Empty {
                // Nothing to draw: no post of it has data.
                continue;
            }
            let range =
                self.allocator.block_range(GeneratorId(slot)).expect("resident tiles own a block");
            self.draws.push(TileDraw {
                key: tile.key,
                byte_offset: range.start,
                index_byte_offset: range.start + resident.mesh.vertex_bytes(),
                index_count: resident.mesh.indices,
                vertex_step: resident.kind.vertex_step(tile.key),
                node_mesh: resident.kind != TileMeshKind::Grid,
                source_level: resident.source_level,
                coverage: resident.coverage,
                sub_level: resident.errors.sub_level,
                errors: resident.errors_m,
                seams: resident.seams,
            });
        }
        // Memory order keeps the attribute pointer moving forward.
        self.draws.sort_unstable_by_key(|d| d.byte_offset);
    }
}
