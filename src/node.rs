//! The node pyramid's vocabulary, shared by the pyramid on disk, the procedural
//! source and the chunked clipmap: which node is which, how big nodes are, and
//! what a loaded node holds (Kühnert 4.5.3 and 4.5.6, Ulrich section 10).
//!
//! Level 0 is the finest; a node of level `lod` spans `node_size << lod`
//! level-0 sample spacings per side (Kühnert eq. 4.8). Node `(x, y)` of level
//! `lod` covers level-0 posts `[x * span, (x + 1) * span]` east and
//! `[y * span, (y + 1) * span]` north, `span = node_size << lod`, sampled every
//! `1 << lod` samples: `node_size + 1` posts per side, so neighbours share their
//! edge posts. A border of `border` posts on every side repeats the
//! neighbours' posts (extended at the edge of the data) for normals and
//! seamless sampling.

/// Names one node of the pyramid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct NodeId {
    /// Level in the pyramid: 0 is the finest, each level above halves the posts.
    pub level: u8,
    /// Column of the node at its level, from the west.
    pub x: u32,
    /// Row of the node at its level, from the south.
    pub y: u32,
}

impl NodeId {
    /// The node at column `x`, row `y` of `level`.
    pub fn new(level: u8, x: u32, y: u32) -> Self {
        NodeId { level, x, y }
    }

    /// The node one level coarser that contains this one.
    pub fn parent(self) -> Option<NodeId> {
        (self.level < u8::MAX).then(|| NodeId::new(self.level + 1, self.x / 2, self.y / 2))
    }
}

/// Sizes shared by every node of one pyramid.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct NodeLayout {
    /// Number of levels (`lod_count`); level `levels - 1` is the root level.
    pub levels: u8,
    /// Cells per node side at every level (posts per side: `node_size + 1`).
    pub node_size: u32,
    /// Extra posts stored on each side of a node.
    pub border: u32,
    /// Level-0 posts of the data, east and north.
    pub posts: [u32; 2],
    /// Metres between level-0 posts, east and north, in the local frame.
    pub spacing_m: [f64; 2],
}

/// The level of the squares inside which node edges are shared
/// ([`ErrorMap::shared_edges`]): every map of a node finer than its square
/// codes the posts of the edges inside it from the square's own hierarchy.
/// A fixed level (not the build's blocks), so that every build, whole or
/// in shards, shares the same edges; shards split no finer
/// (`pyramid::shard`).
///
/// The squares' own edges are not shared: the maps on either side code
/// their posts apart, and tiles of levels below the square meet there at
/// cracks their skirts fill and a viewer sees. Level 3 left one level-0
/// node edge in eight such an edge, and the SRTM tile flown at tau 4
/// (`tests/render_data_edges.rs`) 0.070 % of its terrain pixels on skirts
/// along them, over issue 25's 0.05 %. Level 5 is the blocks' depth
/// (`MeshOptions::depth`: their blocks already hold a square this size, so
/// the build reads and scans no more), leaves one edge in 32, and took
/// that flight to 0 %. A coarser square would be built on a coarser
/// lattice than level 0's maps, which could then share none of its edges;
/// and shards split no finer than it (`docs/edges.md`, "Share squares of
/// level 5").
pub const SHARE_LEVEL: u8 = 5;

impl NodeLayout {
    /// The level of the squares node edges are shared inside: [`SHARE_LEVEL`],
    /// or the root's in a smaller pyramid.
    pub fn share_level(&self) -> u8 {
        SHARE_LEVEL.min(self.levels.saturating_sub(1))
    }

    /// The square node `id`'s shared edges lie inside: its ancestor of
    /// [`Self::share_level`], or `None` at or above that level.
    pub fn share_square(&self, id: NodeId) -> Option<NodeId> {
        let level = self.share_level();
        let up = level.checked_sub(id.level).filter(|&up| up > 0)?;
        Some(NodeId::new(level, id.x >> up, id.y >> up))
    }

    /// Posts per stored node side, border included.
    pub fn stored_side(&self) -> u32 {
        self.node_size + 1 + 2 * self.border
    }

    /// Nodes per side at `lod`, east and north (covering every sample).
    pub fn nodes_at(&self, lod: u8) -> [u32; 2] {
        let span = self.span(lod);
        let count = |samples: u32| (samples.saturating_sub(1) as u64).div_ceil(span).max(1) as u32;
        [count(self.posts[0]), count(self.posts[1])]
    }

    /// Level-0 sample spacings spanned by one node of `lod` (Kühnert eq. 4.8).
    pub fn span(&self, lod: u8) -> u64 {
        (self.node_size as u64) << lod
    }

    /// Levels needed so that the root level is a single node covering every
    /// sample: level `l` exists while level `l - 1` still needs more than one
    /// node per side.
    pub fn levels_for(samples: [u32; 2], node_size: u32) -> u8 {
        debug_assert!(node_size > 0, "a node has at least one cell per side");
        let node_size = node_size.max(1) as u64;
        let cells = samples[0].max(samples[1]).saturating_sub(1) as u64;
        let mut levels = 1u8;
        while (node_size << (levels - 1)) < cells {
            levels += 1;
        }
        levels
    }

    /// Nodes in the whole pyramid.
    pub fn node_count(&self) -> u64 {
        (0..self.levels).map(|lod| self.nodes_at_count(lod)).sum()
    }

    /// Nodes at one level.
    pub fn nodes_at_count(&self, lod: u8) -> u64 {
        let [x, y] = self.nodes_at(lod);
        x as u64 * y as u64
    }

    /// Side of a node of `lod` in metres, east and north.
    pub fn node_size_m(&self, lod: u8) -> [f64; 2] {
        let span = self.span(lod) as f64;
        [span * self.spacing_m[0], span * self.spacing_m[1]]
    }

    /// Distance in metres from the south-west sample to the north-east one.
    pub fn extent_m(&self) -> [f64; 2] {
        let last = |axis: usize| self.posts[axis].saturating_sub(1) as f64 * self.spacing_m[axis];
        [last(0), last(1)]
    }

    /// Whether `id` names a node of this pyramid.
    pub fn contains(&self, id: NodeId) -> bool {
        if id.level >= self.levels {
            return false;
        }
        let [x, y] = self.nodes_at(id.level);
        id.x < x && id.y < y
    }

    /// The position of `id` when nodes are listed level by level (finest
    /// first), row by row (south first) within a level.
    pub fn node_index(&self, id: NodeId) -> Option<u64> {
        if !self.contains(id) {
            return None;
        }
        let before: u64 = (0..id.level).map(|lod| self.nodes_at_count(lod)).sum();
        let [x_count, _] = self.nodes_at(id.level);
        Some(before + id.y as u64 * x_count as u64 + id.x as u64)
    }

    /// The node of `lod` covering the point `(x_m, y_m)` of the local frame and
    /// the point's post coordinates inside it, or `None` when the point is not
    /// finite or lies outside the data. A point on a shared edge belongs to
    /// the node east or north of it, except on the data's far edges.
    pub fn locate(&self, lod: u8, x_m: f64, y_m: f64) -> Option<NodePoint> {
        if lod >= self.levels {
            return None;
        }
        let span = self.span(lod);
        let stride = (1u64 << lod) as f64;
        let extent = self.extent_m();
        let nodes = self.nodes_at(lod);
        let axis = |axis: usize, m: f64| -> Option<(u32, f64)> {
            if !(m >= 0.0 && m <= extent[axis]) {
                return None; // also refuses NaN
            }
            let sample = m / self.spacing_m[axis];
            let node = ((sample / span as f64).floor() as u64).min(nodes[axis] as u64 - 1);
            Some((node as u32, (sample - (node * span) as f64) / stride))
        };
        let (x, u) = axis(0, x_m)?;
        let (y, v) = axis(1, y_m)?;
        Some(NodePoint { id: NodeId::new(lod, x, y), posts: [u, v] })
    }
}

/// A point located inside a node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodePoint {
    /// The node containing the point.
    pub id: NodeId,
    /// Post coordinates east and north from the node's south-west centre
    /// post, each in `0..=node_size`.
    pub posts: [f64; 2],
}

/// The height at fractions `(fu, fv)` of a cell whose corners are `h00`
/// (south-west), `h10` (south-east), `h01` (north-west) and `h11` (north-east),
/// the cell split along its south-west to north-east diagonal: the one
/// triangulation the pyramid's delta, the tiles, the exact heights and the
/// shaders' meshes share.
///
/// A corner without data (NaN) counts only where it weighs: on a corner,
/// along an edge or the diagonal, the posts at its ends decide alone. So a
/// post with data next to one without reads as itself: read through the
/// full formula (`0 * NaN` is NaN), every post with no data to its east or
/// north-east read as none, and a ragged no-data outline lost a row of
/// posts at every level (issue 25).
#[inline]
pub fn cell_surface(h00: f64, h10: f64, h01: f64, h11: f64, fu: f64, fv: f64) -> f64 {
    let height = cell_surface_full(h00, h10, h01, h11, fu, fv);
    if height.is_nan() {
        cell_surface_weighed(h00, h10, h01, h11, fu, fv)
    } else {
        height
    }
}

/// [`cell_surface`] through the full formula (its bits where all four
/// corners have data).
#[inline]
fn cell_surface_full(h00: f64, h10: f64, h01: f64, h11: f64, fu: f64, fv: f64) -> f64 {
    if fu >= fv {
        // South-east triangle (SW, SE, NE).
        h00 + fu * (h10 - h00) + fv * (h11 - h10)
    } else {
        // North-west triangle (SW, NE, NW).
        h00 + fv * (h01 - h00) + fu * (h11 - h01)
    }
}

/// [`cell_surface`] as the sum of the corners that weigh, each times its
/// barycentric weight: NaN only where a corner without data weighs.
fn cell_surface_weighed(h00: f64, h10: f64, h01: f64, h11: f64, fu: f64, fv: f64) -> f64 {
    let terms = if fu >= fv {
        [(h00, 1.0 - fu), (h10, fu - fv), (h11, fv)]
    } else {
        [(h00, 1.0 - fv), (h01, fv - fu), (h11, fu)]
    };
    terms.iter().filter(|(_, w)| *w != 0.0).map(|(h, w)| h * w).sum()
}

/// One vertex of a node's adaptive mesh: 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MeshVertex {
    /// Mesh post `(i, j)` from the node's south-west post, in half steps
    /// of `2^NodeMesh::post_level` level-0 posts: even pairs are posts of
    /// the reference lattice, odd pairs the centres of cells drawn as a
    /// fan of four (see `meshes::fan`).
    pub post: [u16; 2],
    /// Height of the data there, metres; NaN where there is none.
    pub height: f32,
    /// Ulrich's morph target: the parent node's mesh height at the same
    /// place (the vertex's own height for a root node, or where the parent
    /// has no data there).
    pub target: f32,
    /// Unit normals, x and y scaled to -127..127 (z positive): of this
    /// level's surface, then of the parent level's.
    pub normal: [i8; 4],
}

/// A node's adaptive mesh (Ulrich's chunk): a right-triangulated irregular
/// network of the best data under the node, simplified to its level's error
/// (see [`crate::mesh`] and the chunk builder). Empty when the source keeps
/// none: tiles then draw the node's posts as a regular grid.
///
/// Invariant: every index is below `vertices.len()`, `indices.len()` is a
/// multiple of 3, triangles are counter-clockwise seen from above, and each
/// triangle lies inside one square of `tile_cells` node posts; `bands`
/// is empty or has one entry per vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeMesh {
    /// The level whose post spacing the vertices' posts count in (the
    /// reference level, at most a few levels below the node's own).
    pub post_level: u8,
    /// The vertices.
    pub vertices: Vec<MeshVertex>,
    /// Three indices a triangle.
    pub indices: Vec<u16>,
    /// Per vertex, the morph band it follows (`tiles::by_distance`'s
    /// `DistanceRule::band_at`): 0, the level's own morph, for all where
    /// empty.
    pub bands: Vec<u8>,
}

impl NodeMesh {
    /// Whether the source keeps no mesh for the node.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Checks the invariant (debug builds).
    pub fn debug_check(&self) {
        debug_assert_eq!(self.indices.len() % 3, 0);
        debug_assert!(self.indices.iter().all(|&i| (i as usize) < self.vertices.len()));
        debug_assert!(self.bands.is_empty() || self.bands.len() == self.vertices.len());
    }
}

/// A node's error map (issues 21 and 22): the right-triangulated
/// irregular network of the best data under the node, each split's error
/// as a code (see [`crate::mesh::code`]), from which a mesh of any error at
/// or above `floor_m` is extracted when a tile is made. One map serves
/// every tau and every viewport.
///
/// *Dense* maps keep a code for every post of the node's own lattice (the
/// best data there: level 0, or a node no finer node lies under), whose
/// heights are [`NodeData::heights`]. *Sparse* maps are on a finer
/// reference lattice and keep only the posts whose code is above the
/// floor's, or that every mesh has (the corners of the squares tiles may
/// cut), with their heights and normals.
///
/// Invariant: `keys` ascend and are below `(cells + 1)^2`; `codes`,
/// `heights` and `normals` have one entry per key (dense: `codes` one per
/// post, the rest empty); `above` has 4 x 256 entries, each quadrant's
/// non-increasing; `shared_edges` holds the four edge bits alone.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErrorMap {
    /// The level whose lattice the map's posts are on.
    pub post_level: u8,
    /// Reference-lattice cells per node side, a power of two.
    pub cells: u32,
    /// The smallest error a mesh may be extracted at, metres (0: any).
    pub floor_m: f32,
    /// How far the reference lattice's surface may lie from the best data,
    /// metres (0 on the data's own lattice): added to any mesh's error.
    pub reference_delta: f32,
    /// Half cells are drawn as the hierarchy makes them (a reference
    /// lattice coarser than the data), never along the data's diagonal.
    pub hierarchy_leaves: bool,
    /// The edges (bits [`ErrorMap::WEST`] to [`ErrorMap::NORTH`]) whose
    /// posts' codes take the neighbouring node's triangles too: there the
    /// two maps code every shared post alike, so meshes of one error meet
    /// without a crack. Other edges' posts see their own node's triangles
    /// alone (the edges on its share square's boundary, or every edge of
    /// a node whose square is not stored on its lattice).
    pub shared_edges: u8,
    /// Dense: a code per post, row-major. Sparse: a code per key.
    pub codes: Vec<u8>,
    /// Sparse: the posts kept, `j * (cells + 1) + i`, ascending.
    pub keys: Vec<u32>,
    /// Sparse: each kept post's height, metres (NaN: no data).
    pub heights: Vec<f32>,
    /// Sparse: each kept post's data normal, x and y scaled to -127..127.
    pub normals: Vec<[i8; 2]>,
    /// Sparse: the spacing of the heights' quantisation steps, metres (the
    /// map file stores them so; half of it is in `reference_delta`), or 0:
    /// the heights are the pyramid's own, read again at page-in.
    pub height_step: f32,
    /// `above[256 q + c]`: posts of quadrant `q` (`x + 2 y`, south-west
    /// first; posts on a quadrant's north or east edge belong to the next)
    /// whose code is above `c`: what a frame budget estimates a tile's
    /// triangles at another error from.
    pub above: Vec<u32>,
    /// Sparse: where each row's keys start (`side + 1` entries), so a
    /// lookup searches one row.
    pub rows: Vec<u32>,
}

impl ErrorMap {
    /// The west edge's bit in [`Self::shared_edges`] (posts `(0, j)`).
    pub const WEST: u8 = 1;
    /// The east edge's (posts `(cells, j)`).
    pub const EAST: u8 = 2;
    /// The south edge's (posts `(i, 0)`).
    pub const SOUTH: u8 = 4;
    /// The north edge's (posts `(i, cells)`).
    pub const NORTH: u8 = 8;
    /// The bits in the order tiles number their edges: south, east, north,
    /// west.
    pub const BY_TILE_EDGE: [u8; 4] = [Self::SOUTH, Self::EAST, Self::NORTH, Self::WEST];

    /// Whether the map keeps every post of its lattice.
    pub fn is_dense(&self) -> bool {
        self.keys.is_empty() && !self.codes.is_empty()
    }

    /// Whether the node has no map (a source without meshes).
    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    /// Posts a side of the reference lattice.
    pub fn side(&self) -> u32 {
        self.cells + 1
    }

    /// Where post `(i, j)` is kept in a sparse map.
    pub fn find(&self, i: u32, j: u32) -> Option<usize> {
        let key = j * self.side() + i;
        let (start, end) = match (self.rows.get(j as usize), self.rows.get(j as usize + 1)) {
            (Some(&a), Some(&b)) => (a as usize, b as usize),
            _ => (0, self.keys.len()),
        };
        self.keys[start..end].binary_search(&key).ok().map(|k| start + k)
    }

    /// The code of the split at post `(i, j)`: 0 where a sparse map keeps
    /// none (its split is never needed above the floor).
    pub fn code(&self, i: u32, j: u32) -> u8 {
        debug_assert!(i <= self.cells && j <= self.cells);
        if self.is_dense() {
            return self.codes[(j * self.side() + i) as usize];
        }
        self.find(i, j).map_or(0, |k| self.codes[k])
    }

    /// Fills `rows` from `keys` (sparse maps; dense ones need none).
    pub fn index_rows(&mut self) {
        self.rows.clear();
        if self.keys.is_empty() {
            return;
        }
        let side = self.side();
        self.rows.reserve_exact(side as usize + 1);
        let mut k = 0;
        for j in 0..=side {
            while k < self.keys.len() && self.keys[k] < j * side {
                k += 1;
            }
            self.rows.push(k as u32);
        }
    }

    /// Fills `above` from `codes`.
    pub fn count_codes(&mut self) {
        let mut counts = [[0u32; 256]; 4];
        let (side, half) = (self.side(), self.cells / 2);
        let quadrant = |key: u32| {
            let (i, j) = (key % side, key / side);
            (i >= half) as usize + 2 * (j >= half) as usize
        };
        for (k, &c) in self.codes.iter().enumerate() {
            let key = if self.keys.is_empty() { k as u32 } else { self.keys[k] };
            counts[quadrant(key)][c as usize] += 1;
        }
        self.above.clear();
        self.above.resize(4 * 256, 0);
        for (q, counts) in counts.iter().enumerate() {
            let mut running = 0;
            for c in (0..256).rev() {
                self.above[256 * q + c] = running;
                running += counts[c];
            }
        }
    }

    /// Posts of quadrants `quadrants` (a bit each) whose code is above `code`.
    pub fn above_in(&self, quadrants: u8, code: u8) -> u32 {
        (0..4)
            .filter(|q| quadrants & (1 << q) != 0)
            .map(|q| self.above.get(256 * q + code as usize).copied().unwrap_or(0))
            .sum()
    }

    /// Heap the map's buffers take, bytes (their capacities).
    pub fn heap_bytes(&self) -> u64 {
        (self.codes.capacity()
            + 4 * self.keys.capacity()
            + 4 * self.heights.capacity()
            + 2 * self.normals.capacity()
            + 4 * self.above.capacity()
            + 4 * self.rows.capacity()) as u64
    }

    /// Gives back the buffers' room beyond their lengths.
    pub fn fit(&mut self) {
        self.codes.shrink_to_fit();
        self.keys.shrink_to_fit();
        self.heights.shrink_to_fit();
        self.normals.shrink_to_fit();
        self.above.shrink_to_fit();
        self.rows.shrink_to_fit();
    }

    /// Checks the invariant (debug builds).
    pub fn debug_check(&self) {
        debug_assert!(self.keys.windows(2).all(|w| w[0] < w[1]), "keys ascend");
        debug_assert!(self.keys.last().is_none_or(|&k| k < self.side() * self.side()));
        debug_assert!(self.shared_edges <= 15, "four edge bits");
        if !self.keys.is_empty() {
            debug_assert_eq!(self.codes.len(), self.keys.len());
            debug_assert_eq!(self.heights.len(), self.keys.len());
            debug_assert_eq!(self.normals.len(), self.keys.len());
        }
    }
}

/// A node's stored content.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeData {
    /// `stored_side^2` heights in metres, row 0 southern, border included.
    pub heights: Vec<f32>,
    /// Lowest height of the node's centre posts.
    pub min: f32,
    /// Highest height of the node's centre posts.
    pub max: f32,
    /// Ulrich's delta: the largest vertical distance, in metres, between the
    /// node's surface (posts joined as triangles, each cell split from its
    /// south-west to its north-east corner) and the level-0 posts it covers;
    /// with a mesh, the mesh's.
    pub delta: f32,
    /// The same for the node's posts as a regular grid, whether or not it
    /// has a mesh: what a tile made as a grid of its posts errs by.
    pub grid_delta: f32,
    /// The node's error map, if its source keeps one: tiles extract their
    /// meshes from it.
    pub map: ErrorMap,
}

impl NodeData {
    /// Empty node data whose buffer already holds a node of `layout`, so that
    /// reading into it does not allocate.
    pub fn with_capacity(layout: &NodeLayout) -> Self {
        let side = layout.stored_side() as usize;
        NodeData { heights: Vec::with_capacity(side * side), ..NodeData::default() }
    }

    /// Heap the buffers take, bytes: their capacities, not their lengths,
    /// because a buffer keeps what the largest node read into it needed.
    pub fn heap_bytes(&self) -> u64 {
        self.heights.capacity() as u64 * std::mem::size_of::<f32>() as u64 + self.map.heap_bytes()
    }

    /// Gives back the buffers' room beyond their lengths, so that a
    /// byte-accounted atlas counts a node at its own size (what
    /// [`NodeSource::node_bytes_of`] plans with) and not at the largest node
    /// its buffer once held: a planned load that then measured more would be
    /// refused and read again every frame. Reallocates: the loader thread
    /// calls it after a read, never a frame.
    pub fn fit(&mut self) {
        self.heights.shrink_to_fit();
        self.map.fit();
    }

    /// Height of centre post `(i, j)` (`0..=node_size` each, border excluded).
    pub fn post(&self, layout: &NodeLayout, i: u32, j: u32) -> f32 {
        let side = layout.stored_side();
        debug_assert!(i <= layout.node_size && j <= layout.node_size);
        debug_assert_eq!(self.heights.len(), (side * side) as usize);
        self.heights[((j + layout.border) * side + i + layout.border) as usize]
    }

    /// The node's surface at post coordinates `posts` (see [`NodePoint`]):
    /// each cell is split from its south-west to its north-east corner and
    /// the triangle holding the point is interpolated linearly, the surface
    /// `delta` is measured against.
    pub fn interpolate(&self, layout: &NodeLayout, posts: [f64; 2]) -> f32 {
        let last_cell = layout.node_size.saturating_sub(1);
        let cell = |p: f64| (p.max(0.0).floor() as u32).min(last_cell);
        let (i, j) = (cell(posts[0]), cell(posts[1]));
        let (fx, fy) = (posts[0] - i as f64, posts[1] - j as f64);
        let h = |di: u32, dj: u32| self.post(layout, i + di, j + dj) as f64;
        cell_surface(h(0, 0), h(1, 0), h(0, 1), h(1, 1), fx, fy) as f32
    }
}

/// Anything that can produce nodes: the memory-mapped pyramid, the procedural
/// earth. Called from the loader thread.
pub trait NodeSource: Send + Sync {
    /// The pyramid's geometry: levels, node size, border, post spacing.
    fn layout(&self) -> &NodeLayout;

    /// Whether node `id` is stored. An absent node (a layered pyramid
    /// stores fine levels only where fine data are) means "no finer data
    /// here": the clipmap never requests it and draws its deepest present
    /// ancestor. The default: every node of the layout is present.
    fn has_node(&self, id: NodeId) -> bool {
        self.layout().contains(id)
    }

    /// Writes node `id` into `out`, reusing its buffers.
    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError>;

    /// The most heap, bytes, a [`NodeData`] holding any node of this source
    /// takes (its buffers grow to the largest node read into them): what a
    /// memory budget counts an atlas slot at. The default: the heights.
    fn node_bytes(&self) -> u64 {
        let side = self.layout().stored_side() as u64;
        side * side * std::mem::size_of::<f32>() as u64
    }

    /// The heap, bytes, node `id` takes once read and fitted
    /// ([`NodeData::fit`]): what a byte-accounted atlas plans its loads
    /// with before reading. The default: [`NodeSource::node_bytes`].
    fn node_bytes_of(&self, id: NodeId) -> u64 {
        let _ = id;
        self.node_bytes()
    }

    /// The height at `(x_m, y_m)` at full resolution: the level-0 posts
    /// joined as triangles (the surface every `delta` is measured against).
    /// The default reads the level-0 node holding the point, which allocates
    /// one node; sources with direct access to samples override it.
    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        let layout = *self.layout();
        let point = layout.locate(0, x_m, y_m).ok_or(NodeError::OutsideData { x_m, y_m })?;
        let mut node = NodeData::with_capacity(&layout);
        self.read_node(point.id, &mut node)?;
        Ok(node.interpolate(&layout, point.posts))
    }

    /// Drops the pages of a memory-mapped source that reads have made
    /// resident (a long pass over every node, such as building the map
    /// file, calls it between batches so its memory stays flat). The
    /// default, for sources that map nothing, does nothing.
    fn release_pages(&self) {}
}

/// Why a node could not be produced.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// The id names no node of the layout.
    #[error("node {id:?} is outside the pyramid")]
    OutOfRange {
        /// The node asked for.
        id: NodeId,
    },
    /// The file stores no such node: no data of its resolution there (its
    /// deepest present ancestor serves).
    #[error("node {id:?} is absent: no data of its resolution there")]
    Absent {
        /// The node asked for.
        id: NodeId,
    },
    /// The node's bytes failed their check (checksum or range).
    #[error("{path}: node {id:?}: {problem}")]
    Corrupt {
        /// The pyramid file.
        path: std::path::PathBuf,
        /// The node.
        id: NodeId,
        /// What the check found.
        problem: String,
    },
    /// Reading the pyramid file failed.
    #[error("{path}: {source}")]
    Io {
        /// The pyramid file.
        path: std::path::PathBuf,
        /// The I/O failure.
        source: std::io::Error,
    },
    /// An exact height was asked outside the data's extent.
    #[error("point ({x_m} m, {y_m} m) is outside the data")]
    OutsideData {
        /// Metres east of the pyramid's origin.
        x_m: f64,
        /// Metres north of the pyramid's origin.
        y_m: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::cell_surface;

    /// A post with data reads as itself whatever its neighbours, and an
    /// edge between two posts with data as their line; a point inside a
    /// triangle touching a post without data has none.
    #[test]
    fn corners_without_data_count_only_where_they_weigh() {
        let nan = f64::NAN;
        // North-east and north-west without data: the south edge stands.
        assert_eq!(cell_surface(10.0, 20.0, nan, nan, 0.0, 0.0), 10.0);
        assert_eq!(cell_surface(10.0, 20.0, nan, nan, 0.25, 0.0), 12.5);
        assert_eq!(cell_surface(10.0, 20.0, nan, nan, 1.0, 0.0), 20.0);
        assert!(cell_surface(10.0, 20.0, nan, nan, 0.5, 0.25).is_nan());
        // South-east without data: the diagonal and the north-west triangle stand.
        assert_eq!(cell_surface(10.0, nan, 30.0, 50.0, 0.5, 0.5), 30.0);
        assert_eq!(cell_surface(10.0, nan, 30.0, 50.0, 0.25, 0.5), 25.0);
        assert!(cell_surface(10.0, nan, 30.0, 50.0, 0.5, 0.25).is_nan());
        // With every corner, the full formula's bits.
        let full = 10.0 + 0.3 * (20.0 - 10.0) + 0.1 * (50.0 - 20.0);
        assert_eq!(cell_surface(10.0, 20.0, 30.0, 50.0, 0.3, 0.1), full);
    }
}
