//! The ground truth's geometry, GL-free: every level-0 post of a region read
//! from a node source, with the normal a level-0 tile would give it, cut into
//! chunks of [`CHUNK_CELLS`] cells a side that share their edge posts.
//!
//! A chunk is laid out as a regular tile of that grid size
//! ([`crate::tiles::TileGrid`]'s vertices and 16-bit indices, one block per
//! chunk), with the morph target equal to the height, the parent
//! normal equal to its own, and skirt vertices that copy the edge posts (drawn
//! with depth 0 they have no area), so the terrain pass draws it as a big
//! unmorphed level-0 tile. The region is widened to whole chunks; posts
//! outside the data have no data. Where a layered pyramid has no level-0
//! node (no data that fine there), the posts are the best data: the
//! deepest present ancestor's surface sampled at the level-0 posts.
//!
//! Where the data end the truth hangs curtains as the tiles do
//! ([`crate::tiles::curtain`]), from its own exact edges: a skirt vertex
//! facing a post without data is a curtain's foot, and each chunk appends
//! feet and curtain triangles where its drawn triangles meet dropped ones.

use crate::lod::select::tiles_at;
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::tiles::curtain::{self, CurtainFinder};
use crate::tiles::grid::{index_count, positions, vertex_count, TileGrid};
use crate::tiles::vertex::slope;
use crate::tiles::{self, TileVertex, NO_DATA};

/// Most posts a truth mesh may hold (4096^2; 961 chunks at most, whose
/// blocks take 525 MB on the GPU).
pub const MAX_TRUTH_POSTS: u64 = 1 << 24;
/// Cells per chunk side: the largest power of two whose tile grid,
/// skirts included, numbers its vertices in `u16`.
pub const CHUNK_CELLS: u32 = 128;
/// Posts per side of the largest square of whole chunks within
/// [`MAX_TRUTH_POSTS`].
pub const MAX_TRUTH_SIDE: u32 = 31 * CHUNK_CELLS + 1;

/// A rectangle of level-0 posts: `posts` of them east and north from `first`.
/// It may reach past the data, where heights extend the edge (or, loaded
/// by [`TruthMesh::load_wrapped`], where they are read a turn back).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TruthRegion {
    /// The south-west post, in level-0 posts east and north of the data's south-west post.
    pub first: [i64; 2],
    /// Posts east and north; at least 2 each for a mesh.
    pub posts: [u32; 2],
}

impl TruthRegion {
    /// Every sample of the data.
    pub fn whole(layout: &NodeLayout) -> Self {
        TruthRegion { first: [0, 0], posts: layout.posts }
    }

    /// What the level-0 tiles of `grid_size` cover: the data, extended to a
    /// whole number of tiles as the LOD display draws it.
    pub fn covering_tiles(layout: &NodeLayout, grid_size: u32) -> Self {
        let tiles = tiles_at(layout.posts, grid_size, 0);
        TruthRegion {
            first: [0, 0],
            posts: tiles.map(|t| t.saturating_mul(grid_size).saturating_add(1)),
        }
    }

    /// What the level-0 tiles cover ([`TruthRegion::covering_tiles`]),
    /// within a window of [`MAX_TRUTH_SIDE`] posts a side centred on the
    /// middle of `positions` (local metres): all of a single tile, the part
    /// of a layered pyramid's level 0 (which spans its whole base) around a
    /// flight.
    pub fn around_positions(
        layout: &NodeLayout,
        grid_size: u32,
        positions: impl IntoIterator<Item = [f64; 2]>,
    ) -> Self {
        let (mut low, mut high) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in positions {
            for a in 0..2 {
                low[a] = low[a].min(p[a]);
                high[a] = high[a].max(p[a]);
            }
        }
        let centre = [0, 1].map(|a| {
            let middle = if low[a] <= high[a] { 0.5 * (low[a] + high[a]) } else { 0.0 };
            (middle / layout.spacing_m[a]).round() as i64
        });
        Self::covering_tiles(layout, grid_size).around(centre, MAX_TRUTH_SIDE)
    }

    /// [`Self::around_positions`] over a grid whose columns wrap every
    /// `period` posts (drawn on the ellipsoid): its columns are a window
    /// centred on the positions' and not cut at the grid's seam (a turn
    /// at most; load it with [`TruthMesh::load_wrapped`], which reads
    /// posts past either edge a turn back), so a flight across the seam
    /// sees data on both sides.
    pub fn around_positions_wrapping(
        layout: &NodeLayout,
        grid_size: u32,
        positions: impl IntoIterator<Item = [f64; 2]>,
        period: u32,
    ) -> Self {
        let positions: Vec<[f64; 2]> = positions.into_iter().collect();
        let region = Self::around_positions(layout, grid_size, positions.iter().copied());
        let (low, high) = positions
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
        let middle = if low <= high { 0.5 * (low + high) } else { 0.0 };
        let centre = (middle / layout.spacing_m[0]).round() as i64;
        let east = MAX_TRUTH_SIDE.min(period.saturating_add(1));
        TruthRegion {
            first: [centre - east as i64 / 2, region.first[1]],
            posts: [east, region.posts[1]],
        }
    }

    /// The part of this region inside a square of `side` posts centred on
    /// level-0 post `centre`: for data too large to hold whole at full
    /// resolution (a layered pyramid's level 0 spans its coarse base).
    pub fn around(self, centre: [i64; 2], side: u32) -> Self {
        let window = |a: usize| {
            let end = self.first[a] + self.posts[a] as i64;
            let first = (centre[a] - side as i64 / 2).max(self.first[a]);
            let last = (first + side as i64).min(end);
            let first = (last - side as i64).max(self.first[a]);
            (first, (last - first) as u32)
        };
        let [(x, east), (y, north)] = [window(0), window(1)];
        TruthRegion { first: [x, y], posts: [east, north] }
    }

    /// The region widened east and north to whole chunks, as posts per side
    /// (u64: the widening may not fit `u32`).
    fn chunked_posts(&self) -> [u64; 2] {
        let chunk = CHUNK_CELLS as u64;
        self.posts.map(|p| (p as u64).saturating_sub(1).div_ceil(chunk) * chunk + 1)
    }
}

/// Why a truth mesh cannot be loaded.
#[derive(Debug, thiserror::Error)]
pub enum TruthError {
    /// The region has fewer than 2 posts on a side.
    #[error("truth mesh: a region of {0:?} posts needs at least 2 posts a side")]
    Degenerate([u32; 2]),
    /// The region, widened to whole chunks, holds more than [`MAX_TRUTH_POSTS`] posts.
    #[error("truth mesh: {posts} posts exceed the limit of {max}")]
    TooLarge {
        /// Posts of the widened region.
        posts: u64,
        /// The limit, [`MAX_TRUTH_POSTS`].
        max: u64,
    },
    /// The node source could not read a level-0 node.
    #[error("truth mesh: reading level-0 node {id:?}: {source}")]
    Node {
        /// The node that failed.
        id: NodeId,
        /// Why it failed.
        source: NodeError,
    },
    /// A level-0 node holds an infinite height (NaN is a void, and allowed).
    #[error("truth mesh: level-0 node {id:?} has a non-finite height at post ({i}, {j})")]
    NotFinite {
        /// The node holding it.
        id: NodeId,
        /// Post column inside the node (0..=node_size, border excluded).
        i: u32,
        /// Post row inside the node (0..=node_size, border excluded).
        j: u32,
    },
}

/// One chunk of [`CHUNK_CELLS`] cells a side, its vertices in
/// [`crate::tiles::TileGrid`] order.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthChunk {
    /// The south-west post, counted from the region's first post.
    pub first_post: [u32; 2],
    /// `vertex_count(CHUNK_CELLS)` vertices, their positions in the chunk
    /// set: posts row by row from the south-west, then the skirt's copies
    /// of the edge posts (curtain feet where they face no data), then the
    /// feet of the curtains inside the chunk.
    pub vertices: Vec<TileVertex>,
    /// The curtains' triangles inside the chunk, drawn after the grid's.
    pub curtains: Vec<u16>,
    /// Some posts have no data ([`crate::tiles::NO_DATA`]).
    pub no_data: bool,
}

/// Surface triangles of one chunk (its skirts have no area).
pub const CHUNK_TRIANGLES: u64 = 2 * CHUNK_CELLS as u64 * CHUNK_CELLS as u64;

/// The whole region at full resolution, chunked.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthMesh {
    /// The region drawn: the one asked for, widened to whole chunks.
    pub region: TruthRegion,
    /// The chunks, row by row from the south-west.
    pub chunks: Vec<TruthChunk>,
}

impl TruthMesh {
    /// Reads the level-0 nodes under `region` (and one post around it, for
    /// the normals) from `source`. Refuses a region larger than
    /// [`MAX_TRUTH_POSTS`] before allocating.
    pub fn load(source: &dyn NodeSource, region: TruthRegion) -> Result<TruthMesh, TruthError> {
        Self::load_wrapped(source, region, None)
    }

    /// [`Self::load`] over a grid whose columns wrap every `period` posts
    /// (`Some`: drawn on the ellipsoid, where post `u` and `u + period` are
    /// one place): posts past its east or west edge are read a turn back.
    pub fn load_wrapped(
        source: &dyn NodeSource,
        region: TruthRegion,
        period: Option<u32>,
    ) -> Result<TruthMesh, TruthError> {
        if region.posts[0] < 2 || region.posts[1] < 2 {
            return Err(TruthError::Degenerate(region.posts));
        }
        let [east, north] = region.chunked_posts();
        let posts = east.saturating_mul(north);
        if posts > MAX_TRUTH_POSTS {
            return Err(TruthError::TooLarge { posts, max: MAX_TRUTH_POSTS });
        }
        // Both sides fit u32 now: their product is at most 2^24.
        let region = TruthRegion { first: region.first, posts: [east as u32, north as u32] };
        let layout = *source.layout();
        let heights = MarginGrid::load(source, &layout, region, period)?;
        let starts = |posts: u32| (0..posts / CHUNK_CELLS).map(|k| k * CHUNK_CELLS);
        let grid = TileGrid::new(CHUNK_CELLS);
        let mut finder = CurtainFinder::default();
        let chunks = starts(region.posts[1])
            .flat_map(|y| starts(region.posts[0]).map(move |x| [x, y]))
            .map(|first_post| heights.chunk(first_post, layout.spacing_m, &grid, &mut finder))
            .collect();
        Ok(TruthMesh { region, chunks })
    }

    /// Surface triangles of the whole mesh.
    pub fn triangles(&self) -> u64 {
        self.chunks.len() as u64 * CHUNK_TRIANGLES
    }

    /// The chunk's south-west post, in level-0 posts of the data.
    pub fn chunk_first_post(&self, chunk: &TruthChunk) -> [i64; 2] {
        [0, 1].map(|axis| self.region.first[axis] + chunk.first_post[axis] as i64)
    }
}

/// The region's heights with one post of margin on every side.
struct MarginGrid {
    /// Posts per row, margin included.
    width: usize,
    /// Row 0 is the margin south of the region.
    heights: Vec<f32>,
}

/// Where each post along one axis of the margin grid comes from: the node
/// index and the post inside it, after clamping to the data, and whether
/// the post lies inside the data at all (past its edge there is no data).
struct AxisMap {
    nodes: Vec<u32>,
    local: Vec<u32>,
    inside: Vec<bool>,
}

impl AxisMap {
    /// The posts `first - 1 ..= first + posts` of an axis of `samples`
    /// posts (read a turn back past its ends when it wraps every `period`).
    fn new(
        first: i64,
        posts: u32,
        samples: u32,
        layout: &NodeLayout,
        node_count: u32,
        period: Option<u32>,
    ) -> Self {
        let node_size = layout.node_size;
        let last = samples.saturating_sub(1) as i64;
        let (mut nodes, mut local, mut inside) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..posts as i64 + 2 {
            let mut wanted = first.saturating_sub(1).saturating_add(k);
            if let Some(period) = period.filter(|&p| p > 0) {
                wanted = wanted.rem_euclid(period as i64);
            }
            let sample = wanted.clamp(0, last) as u32;
            let node = (sample / node_size).min(node_count - 1);
            nodes.push(node);
            local.push(sample - node * node_size);
            inside.push((0..=last).contains(&wanted));
        }
        AxisMap { nodes, local, inside }
    }

    /// Runs of consecutive posts read from the same node (the map is monotone).
    fn runs(&self) -> Vec<(u32, std::ops::Range<usize>)> {
        let mut runs: Vec<(u32, std::ops::Range<usize>)> = Vec::new();
        for (k, &node) in self.nodes.iter().enumerate() {
            match runs.last_mut() {
                Some((last, range)) if *last == node => range.end = k + 1,
                _ => runs.push((node, k..k + 1)),
            }
        }
        runs
    }
}

impl MarginGrid {
    fn load(
        source: &dyn NodeSource,
        layout: &NodeLayout,
        region: TruthRegion,
        period: Option<u32>,
    ) -> Result<MarginGrid, TruthError> {
        let [nx, ny] = layout.nodes_at(0);
        let x = AxisMap::new(region.first[0], region.posts[0], layout.posts[0], layout, nx, period);
        let y = AxisMap::new(region.first[1], region.posts[1], layout.posts[1], layout, ny, None);
        let width = x.nodes.len();
        let mut heights = vec![0.0f32; width * y.nodes.len()];
        let mut node = NodeData::with_capacity(layout);
        let x_runs = x.runs();
        for (node_y, rows) in y.runs() {
            for (node_x, columns) in &x_runs {
                let id = NodeId::new(0, *node_x, node_y);
                // The deepest present node: the level-0 one or an ancestor.
                let mut best = id;
                while !source.has_node(best) && best.level + 1 < layout.levels {
                    best = NodeId::new(best.level + 1, best.x / 2, best.y / 2);
                }
                source
                    .read_node(best, &mut node)
                    .map_err(|source| TruthError::Node { id: best, source })?;
                let stride = (1u64 << best.level) as f64;
                let offset = [0, 1].map(|a| {
                    let (level0, ancestor) = if a == 0 { (id.x, best.x) } else { (id.y, best.y) };
                    (level0 as u64 * layout.node_size as u64
                        - ancestor as u64 * layout.span(best.level)) as f64
                });
                for row in rows.clone() {
                    for column in columns.clone() {
                        let (i, j) = (x.local[column], y.local[row]);
                        let height = if best.level == 0 {
                            node.post(layout, i, j)
                        } else {
                            let fx = (offset[0] + i as f64) / stride;
                            let fy = (offset[1] + j as f64) / stride;
                            crate::tiles::vertex::sample_node(layout, &node, fx, fy)
                        };
                        if height.is_infinite() {
                            return Err(TruthError::NotFinite { id, i, j });
                        }
                        // NaN: a void of the data. Past the data: none either.
                        let inside = x.inside[column] && y.inside[row];
                        heights[row * width + column] = if inside { height } else { f32::NAN };
                    }
                }
            }
        }
        Ok(MarginGrid { width, heights })
    }

    /// Height of region post `(i, j)`; -1 and `posts` reach into the margin.
    fn at(&self, i: i64, j: i64) -> f64 {
        self.heights[(j + 1) as usize * self.width + (i + 1) as usize] as f64
    }

    /// The unit normal's x and y at region post `(i, j)`, by differences as
    /// level-0 tiles compute them (`tiles::vertex::fill_tile`).
    fn normal(&self, i: i64, j: i64, spacing_m: [f64; 2]) -> [i8; 2] {
        let here = self.at(i, j);
        let dx = slope(self.at(i - 1, j), here, self.at(i + 1, j), spacing_m[0]);
        let dy = slope(self.at(i, j - 1), here, self.at(i, j + 1), spacing_m[1]);
        let inv = 1.0 / (dx * dx + dy * dy + 1.0).sqrt();
        [quantize(-dx * inv), quantize(-dy * inv)]
    }

    fn chunk(
        &self,
        first_post: [u32; 2],
        spacing_m: [f64; 2],
        grid: &TileGrid,
        finder: &mut CurtainFinder,
    ) -> TruthChunk {
        let g = CHUNK_CELLS;
        let mut vertices: Vec<TileVertex> = positions(g)
            .map(|(post, skirt)| TileVertex { post, skirt, ..TileVertex::default() })
            .collect();
        let posts = ((g + 1) * (g + 1)) as usize;
        let mut nearest = f32::NAN;
        for vertex in &mut vertices[..posts] {
            let [i, j] = vertex.post.map(i64::from);
            let (i, j) = (first_post[0] as i64 + i, first_post[1] as i64 + j);
            let height = self.at(i, j) as f32;
            *vertex = if height.is_nan() {
                // As tiles mark a post without data (`tiles::NO_DATA`).
                vertex.with_surface(NO_DATA, f32::NAN, [0; 4])
            } else {
                nearest = height;
                let [nx, ny] = self.normal(i, j, spacing_m);
                vertex.with_surface(height, height, [nx, ny, nx, ny])
            };
        }
        let no_data = vertices.iter().any(|v| v.target.is_nan());
        for vertex in &mut vertices[..posts] {
            if vertex.target.is_nan() {
                vertex.target = if nearest.is_nan() { 0.0 } else { nearest };
            }
        }
        for k in posts..vertices.len() {
            let [i, j] = vertices[k].post.map(usize::from);
            let top = vertices[i + j * (g as usize + 1)];
            let skirt = vertices[k].with_surface_of(top);
            // A chunk edge facing no data is the data's cut face.
            let [di, dj] = OUTWARD[vertices[k].edge() as usize - 1];
            let (x, y) = (first_post[0] as i64 + i as i64, first_post[1] as i64 + j as i64);
            let faces_void =
                self.at(x + di, y + dj).is_nan() && !tiles::vertex::is_no_data(top.height);
            vertices[k] = if faces_void { curtain::foot(skirt) } else { skirt };
        }
        debug_assert_eq!(vertices.len(), vertex_count(g));
        let mut curtains = Vec::new();
        if no_data {
            let surface = &grid.indices[..index_count(g) - 24 * g as usize];
            finder.find(surface, |v| tiles::vertex::is_no_data(vertices[v as usize].height));
            let first = vertices.len();
            vertices.resize(first + finder.feet(), TileVertex::default());
            curtains.resize(finder.index_count(), 0);
            let (tops, feet) = vertices.split_at_mut(first);
            finder.write(|v| tops[v as usize], first, feet, &mut curtains);
        }
        TruthChunk { first_post, vertices, curtains, no_data }
    }
}

/// The step across each skirt edge (south, east, north, west).
const OUTWARD: [[i64; 2]; 4] = [[0, -1], [1, 0], [0, 1], [-1, 0]];

/// Same rounding as the tiles' normals.
fn quantize(x: f64) -> i8 {
    (x * 127.0).round().clamp(-127.0, 127.0) as i8
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::{EarthParams, ProceduralEarth};
    use crate::tiles::grid::edge_posts;

    fn earth() -> ProceduralEarth {
        // 16 << 5 = 512 cells: 513 samples a side, four chunks a side.
        let params = EarthParams { node_size: 16, levels: 6, border: 1, spacing_m: 30.0, seed: 7 };
        ProceduralEarth::new(params).expect("small earth")
    }

    /// Region post `k` of a chunk's vertex list, in region posts.
    fn post_of(chunk: &TruthChunk, k: usize) -> (i64, i64) {
        let row = CHUNK_CELLS as usize + 1;
        (
            (chunk.first_post[0] as usize + k % row) as i64,
            (chunk.first_post[1] as usize + k / row) as i64,
        )
    }

    #[test]
    fn the_largest_chunk_numbers_its_vertices_in_16_bits() {
        assert!(vertex_count(CHUNK_CELLS) <= 1 << 16);
        assert!(vertex_count(2 * CHUNK_CELLS) > 1 << 16);
    }

    #[test]
    fn every_post_is_the_sample_and_normals_match_the_tiles() {
        let earth = earth();
        let mesh = TruthMesh::load(&earth, TruthRegion::whole(earth.layout())).expect("loads");
        assert_eq!(mesh.region.posts, [513, 513]);
        assert_eq!(mesh.chunks.len(), 16);
        assert_eq!(mesh.triangles(), 2 * 512 * 512);
        let spacing = 30.0;
        // Past the data's edge (post 512) there is no post: slopes go one-sided.
        let h = |i: i64, j: i64| {
            if (0..=512).contains(&i) && (0..=512).contains(&j) {
                earth.sample(i, j) as f64
            } else {
                f64::NAN
            }
        };
        let posts = (CHUNK_CELLS as usize + 1).pow(2);
        for chunk in &mesh.chunks {
            assert_eq!(chunk.vertices.len(), vertex_count(CHUNK_CELLS));
            for (k, vertex) in chunk.vertices[..posts].iter().enumerate().step_by(37) {
                let (i, j) = post_of(chunk, k);
                assert_eq!(vertex.height, earth.sample(i, j), "post ({i}, {j})");
                assert_eq!(vertex.target, vertex.height);
                let dx = slope(h(i - 1, j), h(i, j), h(i + 1, j), spacing);
                let dy = slope(h(i, j - 1), h(i, j), h(i, j + 1), spacing);
                let inv = 1.0 / (dx * dx + dy * dy + 1.0).sqrt();
                let expected = [quantize(-dx * inv), quantize(-dy * inv)];
                assert_eq!(vertex.normal, [expected[0], expected[1], expected[0], expected[1]]);
            }
            let skirts = chunk.vertices[posts..].iter().zip(edge_posts(CHUNK_CELLS));
            for (k, (skirt, (i, j))) in skirts.enumerate() {
                let edge = (k / (CHUNK_CELLS as usize + 1) + 1) as u16;
                let post = chunk.vertices[(i + j * (CHUNK_CELLS + 1)) as usize];
                let (x, y) = (chunk.first_post[0] + i, chunk.first_post[1] + j);
                // The data's own edge (posts 0 and 512) hangs a curtain; the
                // chunks' shared edges hang skirts of no depth.
                let cut_face = match edge {
                    1 => y == 0,
                    2 => x == 512,
                    3 => y == 512,
                    _ => x == 0,
                };
                let expected =
                    if cut_face { curtain::foot(post) } else { TileVertex { skirt: edge, ..post } };
                assert_eq!(*skirt, expected, "skirt at ({x}, {y}), edge {edge}");
            }
            assert!(chunk.curtains.is_empty(), "no void inside the data");
        }
        let last = mesh.chunks.last().unwrap();
        assert_eq!(mesh.chunk_first_post(last), [384, 384]);
    }

    #[test]
    fn regions_widen_to_whole_chunks_and_posts_past_the_data_have_none() {
        let earth = earth();
        let region = TruthRegion { first: [-3, 500], posts: [5, 20] };
        let mesh = TruthMesh::load(&earth, region).expect("loads");
        assert_eq!((mesh.region.first, mesh.region.posts), ([-3, 500], [129, 129]));
        let chunk = &mesh.chunks[0];
        for k in (0..129 * 129).step_by(11) {
            let (i, j) = post_of(chunk, k);
            let past = i < 3 || j + 500 > 512;
            let expected = if past { NO_DATA } else { earth.sample(i - 3, j + 500) };
            assert_eq!(chunk.vertices[k].height, expected, "post ({i}, {j})");
        }
        assert!(chunk.no_data, "the chunk reaches past the data");
        let tiled = TruthRegion::covering_tiles(earth.layout(), 32);
        assert_eq!(tiled.posts, [513, 513]);
        let wider = TruthRegion { first: [0, 0], posts: [514, 2] };
        assert_eq!(TruthMesh::load(&earth, wider).expect("loads").region.posts, [641, 129]);
    }

    #[test]
    fn refuses_degenerate_and_huge_regions_before_reading() {
        let earth = earth();
        let flat = TruthRegion { first: [0, 0], posts: [1, 9] };
        assert!(matches!(TruthMesh::load(&earth, flat), Err(TruthError::Degenerate(_))));
        let huge = TruthRegion { first: [i64::MAX - 5, i64::MIN], posts: [u32::MAX, u32::MAX] };
        assert!(matches!(TruthMesh::load(&earth, huge), Err(TruthError::TooLarge { .. })));
        let long = TruthRegion { first: [0, 0], posts: [1 << 24, 2] };
        assert!(matches!(TruthMesh::load(&earth, long), Err(TruthError::TooLarge { .. })));
    }
}
