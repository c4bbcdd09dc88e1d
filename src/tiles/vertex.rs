//! Per-tile vertex data, made on the CPU from the best resident node: each
//! vertex's height, its morph target (the parent level's surface at the same
//! place) and both normals. This is what replaces vertex texturing (Polok):
//! heights reach the shader as attributes.

use super::block::TileVertex;
use super::grid::{edge_posts, vertex_count};
use crate::lod::TileKey;
use crate::node::{cell_surface, NodeData, NodeId, NodeLayout};

/// The height a vertex carries where the data has none (a void, or more
/// than one post beyond the data's edge): far below any terrain, so that no consumer mistakes it
/// for one. Its morph target then holds a nearby real height, for the
/// rasteriser's sake only; every triangle touching such a vertex is dropped
/// (see [`TileCoverage`] and the terrain shaders' `NO_DATA` variant).
pub const NO_DATA: f32 = -1.0e9;

/// Whether a vertex's height is [`NO_DATA`].
pub fn is_no_data(height: f32) -> bool {
    height <= NO_DATA * 0.5
}

/// How much of a tile has data.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum TileCoverage {
    /// Every post has data.
    #[default]
    Full,
    /// Some posts have none, or a skirt faces no data, or posts lie past
    /// the data's last post: the tile is drawn with the program that drops
    /// the triangles touching posts without data and clips at the last post.
    Partial,
    /// No post has data: nothing to draw.
    Empty,
}

/// The node of the tile's own level that contains it, and the tile's first
/// post inside that node's centre.
pub fn tile_node(key: TileKey, grid_size: u32, node_size: u32) -> (NodeId, [u32; 2]) {
    let per_node = node_size / grid_size;
    let node = NodeId::new(key.level, key.x / per_node, key.y / per_node);
    (node, [(key.x % per_node) * grid_size, (key.y % per_node) * grid_size])
}

/// Reads level-`level` posts around a tile from a node of that level or a
/// coarser one (then the coarser surface is sampled: best available data).
pub struct PostReader<'a> {
    layout: &'a NodeLayout,
    node: NodeId,
    data: &'a NodeData,
    /// The tile's south-west post in level-0 samples.
    origin: [i64; 2],
    /// Level-0 samples between the tile's posts.
    stride: i64,
}

impl<'a> PostReader<'a> {
    /// A reader for tile `key` from `node` (the tile's own node or an ancestor) and its
    /// `data`.
    pub fn new(
        layout: &'a NodeLayout,
        key: TileKey,
        grid_size: u32,
        node: NodeId,
        data: &'a NodeData,
    ) -> Self {
        let span = (grid_size as i64) << key.level;
        let origin = [key.x as i64 * span, key.y as i64 * span];
        PostReader { layout, node, data, origin, stride: 1 << key.level }
    }

    /// Height of the tile's post `(i, j)`; `i` and `j` may reach two posts
    /// outside the tile (into the node's border). NaN where the data has no
    /// post: a void in the node, or more than one post beyond the data's
    /// last post (never an edge-copied height). The first post beyond it
    /// carries the height on the line through the data's last post, to be
    /// clipped there (see `value`).
    pub fn post(&self, i: i64, j: i64) -> f32 {
        let [x, y] = self.position(i, j);
        self.value(x, y, self.stride)
    }

    /// Height of the parent level's post `(i, j)` (both even): the tile's
    /// own where the data reach, the parent lattice's extrapolation (see
    /// `value`) on the first parent post beyond the data.
    pub fn parent_post(&self, i: i64, j: i64) -> f32 {
        let [x, y] = self.position(i, j);
        self.value(x, y, 2 * self.stride)
    }

    /// Whether post `(i, j)` lies beyond the data's last post east or
    /// north: drawn only by the program that clips at that post.
    pub fn is_beyond(&self, i: i64, j: i64) -> bool {
        let [x, y] = self.position(i, j);
        let [last_x, last_y] = self.last();
        x > last_x || y > last_y
    }

    fn position(&self, i: i64, j: i64) -> [i64; 2] {
        [self.origin[0] + i * self.stride, self.origin[1] + j * self.stride]
    }

    fn last(&self) -> [i64; 2] {
        self.layout.posts.map(|p| p as i64 - 1)
    }

    /// The surface at level-0 post `(x, y)` on a lattice of `stride`. Where
    /// the data's last post east (or north) falls inside a cell of the
    /// lattice, the cell's post beyond it gets the height on the line from
    /// the post before through the data's last post: the cell then passes
    /// through the data at its edge, and the terrain program clips it
    /// there (`u_frame.zw`), so the surface ends where the data end, at
    /// every level, instead of at the level's last post before them. A
    /// lattice post more than one cell beyond has no data (NaN).
    fn value(&self, x: i64, y: i64, stride: i64) -> f32 {
        let last_y = self.last()[1];
        if y <= last_y {
            return self.value_x(x, y as f64, stride);
        }
        let before = y - stride;
        if before >= last_y {
            return f32::NAN;
        }
        let a = self.value_x(x, before as f64, stride);
        let edge = self.value_x(x, self.edge(last_y), stride);
        extrapolate(a, edge, (y - before) as f32 / (last_y - before) as f32)
    }

    /// `value` along a row at `y` (level-0 posts, perhaps the edge
    /// position of [`Self::edge`]).
    fn value_x(&self, x: i64, y: f64, stride: i64) -> f32 {
        let last_x = self.last()[0];
        if x < 0 || y < 0.0 {
            return f32::NAN;
        }
        if x <= last_x {
            return self.sample(x as f64, y);
        }
        let before = x - stride;
        if before >= last_x {
            return f32::NAN;
        }
        let a = self.sample(before as f64, y);
        let edge = self.sample(self.edge(last_x), y);
        extrapolate(a, edge, (x - before) as f32 / (last_x - before) as f32)
    }

    /// Where the node holds the data's last post `last`: its first lattice
    /// post at or beyond it, which the builder fills with the last post's
    /// height (positions beyond the data take the edge post's place).
    fn edge(&self, last: i64) -> f64 {
        let node_stride = 1i64 << self.node.level;
        ((last + node_stride - 1) / node_stride * node_stride) as f64
    }

    /// The node's surface at level-0 post `(x, y)`.
    fn sample(&self, x: f64, y: f64) -> f32 {
        let node_stride = (1i64 << self.node.level) as f64;
        let span = ((self.layout.node_size as i64) << self.node.level) as f64;
        let fx = (x - self.node.x as f64 * span) / node_stride;
        let fy = (y - self.node.y as f64 * span) / node_stride;
        sample_node(self.layout, self.data, fx, fy)
    }
}

/// The height `t` times the way from `a` toward `edge` (`t` above 1: past
/// the edge, on the same line). NaN when either is.
fn extrapolate(a: f32, edge: f32, t: f32) -> f32 {
    a + (edge - a) * t
}

/// The node's surface at post coordinates `(fx, fy)` (0 = the first centre
/// post), interpolated on the triangles split from south-west to north-east.
/// Coordinates beyond the stored border are clamped to it.
pub fn sample_node(layout: &NodeLayout, data: &NodeData, fx: f64, fy: f64) -> f32 {
    let side = layout.stored_side() as i64;
    let border = layout.border as f64;
    let max = (side - 1) as f64;
    let gx = (fx + border).clamp(0.0, max);
    let gy = (fy + border).clamp(0.0, max);
    let (x0, y0) = ((gx.floor() as i64).min(side - 2), (gy.floor() as i64).min(side - 2));
    let (tx, ty) = (gx - x0 as f64, gy - y0 as f64);
    let h = |x: i64, y: i64| data.heights[(y * side + x) as usize] as f64;
    cell_surface(h(x0, y0), h(x0 + 1, y0), h(x0, y0 + 1), h(x0 + 1, y0 + 1), tx, ty) as f32
}

/// Fills the surface of `out` (one regular tile's vertices, skirt included,
/// in [`super::grid`] numbering, their positions already set) from
/// `reader`, and says how much of the tile has data. `spacing_m` is the distance between
/// the tile's posts, east and north. A post without data gets [`NO_DATA`];
/// a morph target or normal that would need a missing neighbour falls back
/// to what the post's own data gives (no morph, one-sided slopes).
pub fn fill_tile(
    reader: &PostReader<'_>,
    grid_size: u32,
    spacing_m: [f64; 2],
    out: &mut [TileVertex],
) -> TileCoverage {
    let g = grid_size as i64;
    debug_assert_eq!(out.len(), vertex_count(grid_size));
    let h = |i: i64, j: i64| reader.post(i, j) as f64;
    // The parent level's posts: the same where the data reach, its own
    // lattice's extrapolation past them.
    let hp = |i: i64, j: i64| reader.parent_post(i, j) as f64;
    let normal = |h: &dyn Fn(i64, i64) -> f64, i: i64, j: i64, step: i64| {
        let dx = slope(h(i - step, j), h(i, j), h(i + step, j), step as f64 * spacing_m[0]);
        let dy = slope(h(i, j - step), h(i, j), h(i, j + step), step as f64 * spacing_m[1]);
        let inv = 1.0 / (dx * dx + dy * dy + 1.0).sqrt();
        [-dx * inv, -dy * inv]
    };
    let (mut with_data, mut without, mut beyond) = (0usize, 0usize, 0usize);
    let mut nearest = f64::NAN;
    for j in 0..=g {
        for i in 0..=g {
            let own = h(i, j);
            let index = (i + j * (g + 1)) as usize;
            if own.is_nan() {
                without += 1;
                out[index] = out[index].with_surface(NO_DATA, f32::NAN, [0; 4]);
                continue;
            }
            if reader.is_beyond(i, j) {
                beyond += 1;
            } else {
                with_data += 1;
            }
            nearest = own;
            let slope_here = normal(&h, i, j, 1);
            let (target, parent) = parent_surface(i, j, &hp, &|i, j| normal(&hp, i, j, 2));
            let (target, parent) =
                if target.is_nan() { (own, slope_here) } else { (target, parent) };
            let normal = [slope_here[0], slope_here[1], parent[0], parent[1]].map(quantize);
            out[index] = out[index].with_surface(own as f32, target as f32, normal);
        }
    }
    // Vertices without data still need a place for the rasteriser: a real
    // height of the tile, so their (dropped) triangles stay small.
    for vertex in out.iter_mut().take(((g + 1) * (g + 1)) as usize) {
        if vertex.target.is_nan() {
            vertex.target = nearest as f32;
        }
    }
    let skirts_dropped = fill_skirts(reader, grid_size, out);
    // Posts beyond the data's last post are drawn only to be clipped there.
    match (with_data, without + skirts_dropped + beyond) {
        (0, _) => TileCoverage::Empty,
        (_, 0) => TileCoverage::Full,
        _ => TileCoverage::Partial,
    }
}

/// Copies the edge posts into the skirt vertices. A skirt hides cracks
/// between two tiles of data; where the post across the edge has no data
/// (the data end there, or a void begins) there is nothing to meet, and the
/// vertex is a curtain's foot instead ([`super::curtain`]: the cut face
/// drawn as no data). Returns how many were.
fn fill_skirts(reader: &PostReader<'_>, grid_size: u32, out: &mut [TileVertex]) -> usize {
    let g = grid_size as i64;
    let posts = ((g + 1) * (g + 1)) as usize;
    let mut dropped = 0;
    for (k, (i, j)) in edge_posts(grid_size).enumerate() {
        let edge_post = out[(i + j * grid_size + j) as usize];
        let [di, dj] = OUTWARD[k / (grid_size as usize + 1)];
        let across = reader.post(i as i64 + di, j as i64 + dj);
        let skirt = out[posts + k].with_surface_of(edge_post);
        out[posts + k] = if across.is_nan() && !is_no_data(edge_post.height) {
            dropped += 1;
            super::curtain::foot(skirt)
        } else {
            skirt
        };
    }
    dropped
}

/// The step across each edge, in [`edge_posts`] order (south, east, north, west).
const OUTWARD: [[i64; 2]; 4] = [[0, -1], [1, 0], [0, 1], [-1, 0]];

/// The slope between posts `step_m` apart: central where both neighbours
/// have data, one-sided where one has, flat where neither has.
pub fn slope(before: f64, here: f64, after: f64, step_m: f64) -> f64 {
    let [rise, run] = slope_parts(before, here, after, step_m);
    rise / run
}

/// [`slope`]'s rise and run, divided apart by a caller that divides many
/// at once (flat: 0 over 1, exactly 0).
#[inline]
pub fn slope_parts(before: f64, here: f64, after: f64, step_m: f64) -> [f64; 2] {
    match (before.is_nan(), after.is_nan()) {
        (false, false) => [after - before, 2.0 * step_m],
        (true, false) => [after - here, step_m],
        (false, true) => [here - before, step_m],
        (true, true) => [0.0, 1.0],
    }
}

/// The parent level's height and normal at post `(i, j)`: its own post where
/// `i` and `j` are even, else interpolated along the parent cell's edge or
/// south-west to north-east diagonal, as the parent's triangles are.
fn parent_surface(
    i: i64,
    j: i64,
    h: &dyn Fn(i64, i64) -> f64,
    n: &dyn Fn(i64, i64) -> [f64; 2],
) -> (f64, [f64; 2]) {
    let (a, b) = match (i % 2 == 1, j % 2 == 1) {
        (false, false) => ((i, j), (i, j)),
        (true, false) => ((i - 1, j), (i + 1, j)),
        (false, true) => ((i, j - 1), (i, j + 1)),
        (true, true) => ((i - 1, j - 1), (i + 1, j + 1)),
    };
    let (na, nb) = (n(a.0, a.1), n(b.0, b.1));
    let height = (h(a.0, a.1) + h(b.0, b.1)) / 2.0;
    (height, [(na[0] + nb[0]) / 2.0, (na[1] + nb[1]) / 2.0])
}

fn quantize(x: f64) -> i8 {
    (x * 127.0).round().clamp(-127.0, 127.0) as i8
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::TileKey;
    use crate::node::{NodeData, NodeId, NodeLayout};
    use crate::tiles::grid::{edge_posts, TileGrid};

    /// One node of 8 cells whose data end at post `last` east: the tile is
    /// the whole node at level 0.
    fn tile_ending_at(last: u32) -> (Vec<TileVertex>, TileCoverage) {
        let layout = NodeLayout {
            levels: 1,
            node_size: 8,
            border: 2,
            posts: [last + 1, 20],
            spacing_m: [90.0, 90.0],
        };
        let side = layout.stored_side() as usize;
        let data = NodeData {
            heights: (0..side * side).map(|k| (k % side) as f32 * 10.0).collect(),
            min: 0.0,
            max: 120.0,
            delta: 0.0,
            grid_delta: 0.0,
            map: Default::default(),
        };
        let reader =
            PostReader::new(&layout, TileKey::new(0, 0, 0), 8, NodeId::new(0, 0, 0), &data);
        let mut out = TileGrid::new(8).vertices;
        let coverage = fill_tile(&reader, 8, layout.spacing_m, &mut out);
        (out, coverage)
    }

    fn dropped_skirts(out: &[TileVertex]) -> Vec<(u32, u32)> {
        let posts = 9 * 9;
        edge_posts(8)
            .enumerate()
            .filter(|(k, _)| crate::tiles::curtain::is_foot(&out[posts + k]))
            .map(|(_, p)| p)
            .collect()
    }

    /// A level-1 node over data whose last post is 9 both ways (10 x 10
    /// posts), heights `x^2 + 3 y^2`, stored as the builder stores them
    /// (positions beyond the data take the edge post's place).
    fn reader_test(check: impl FnOnce(&PostReader<'_>)) {
        let layout = NodeLayout {
            levels: 2,
            node_size: 8,
            border: 2,
            posts: [10, 10],
            spacing_m: [90.0, 90.0],
        };
        let side = layout.stored_side() as i64;
        let at = |p: i64| ((p - 2) * 2).clamp(0, 9) as f32;
        let heights = (0..side * side).map(|k| at(k % side).powi(2) + 3.0 * at(k / side).powi(2));
        let data = NodeData {
            heights: heights.collect(),
            min: 0.0,
            max: 324.0,
            delta: 0.0,
            grid_delta: 0.0,
            map: Default::default(),
        };
        let reader =
            PostReader::new(&layout, TileKey::new(1, 0, 0), 8, NodeId::new(1, 0, 0), &data);
        check(&reader);
    }

    #[test]
    fn the_cell_the_data_end_in_passes_through_their_last_post() {
        let h = |x: f32, y: f32| x * x + 3.0 * y * y;
        reader_test(|reader| {
            // Post 5 of the level-1 tile is level-0 post 10, one past the
            // data's last (9): on the line from post 8 through post 9.
            let beyond = reader.post(5, 4);
            assert_eq!(beyond, h(8.0, 8.0) + 2.0 * (h(9.0, 8.0) - h(8.0, 8.0)));
            // So the drawn cell's midpoint, post 9, is the data there.
            assert_eq!((reader.post(4, 4) + beyond) / 2.0, h(9.0, 8.0));
            assert_eq!((reader.post(4, 4) + reader.post(4, 5)) / 2.0, h(8.0, 9.0));
            // The corner: the SW-NE diagonal passes through (9, 9).
            assert_eq!((reader.post(4, 4) + reader.post(5, 5)) / 2.0, h(9.0, 9.0));
            assert!(reader.is_beyond(5, 0) && reader.is_beyond(0, 5) && !reader.is_beyond(4, 4));
            // Two posts beyond: no data.
            assert!(reader.post(6, 0).is_nan() && reader.post(0, 6).is_nan());
            assert!(reader.post(-1, 0).is_nan());
            // The parent lattice (level-0 posts 0, 4, 8, 12) extrapolates
            // from its own post before the edge: 12 is on the line 8-9.
            let parent = reader.parent_post(6, 0);
            assert_eq!(parent, h(8.0, 0.0) + 4.0 * (h(9.0, 0.0) - h(8.0, 0.0)));
            assert_eq!(reader.parent_post(4, 0), reader.post(4, 0));
        });
    }

    /// A tile reaching past the data's last post is drawn by the clipping
    /// program, and its posts past the edge carry heights (not NO_DATA).
    #[test]
    fn a_tile_past_the_data_edge_is_partial_with_heights_to_clip() {
        reader_test(|reader| {
            let mut out = TileGrid::new(8).vertices;
            let coverage = fill_tile(reader, 8, [180.0, 180.0], &mut out);
            assert_eq!(coverage, TileCoverage::Partial);
            assert!(!is_no_data(out[5 + 9 * 4].height), "one post past the edge has a height");
            assert!(is_no_data(out[6 + 9 * 4].height), "two posts past it have none");
        });
    }

    #[test]
    fn skirts_facing_no_data_are_curtains_and_the_rest_skirts() {
        // Data on every side except past the south and west edges (the
        // data's own edge there): only those skirts are dropped.
        let (out, coverage) = tile_ending_at(20);
        assert_eq!(coverage, TileCoverage::Partial, "a skirt faces no data");
        let dropped = dropped_skirts(&out);
        assert!(dropped.iter().all(|&(i, j)| i == 0 || j == 0), "{dropped:?}");
        assert_eq!(dropped.len(), 2 * 9, "every south and west skirt vertex");
        // A curtain's foot hangs under its post, the curtain's depth down.
        let posts = 9 * 9;
        let depth = crate::tiles::curtain::CURTAIN_DEPTH_M;
        for (k, (i, j)) in edge_posts(8).enumerate().filter(|(k, _)| k / 9 == 0 || k / 9 == 3) {
            let own = out[(i + 9 * j) as usize];
            assert_eq!(out[posts + k].height, own.height - depth, "foot {k} under its post");
            assert_eq!(out[posts + k].post, own.post, "and keeps its position");
        }
    }

    #[test]
    fn the_east_skirt_is_dropped_where_the_data_end_at_the_tile_edge() {
        let (out, _) = tile_ending_at(8);
        let dropped = dropped_skirts(&out);
        assert!(dropped.contains(&(8, 4)), "east edge: {dropped:?}");
        let (out, _) = tile_ending_at(9);
        assert!(!dropped_skirts(&out).contains(&(8, 4)), "one more post east: the skirt stays");
    }
}
