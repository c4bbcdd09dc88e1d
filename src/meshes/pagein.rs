//! Page-in of a map that stores no heights (format 2's
//! [`super::record::FROM_PYRAMID`]: sparse maps at most
//! [`super::build::HEIGHTS_FROM_PYRAMID_SHIFT`] levels above their
//! reference lattice): the heights and normals at its keys, read on the
//! loader thread straight from the stored heights of the pyramid's nodes
//! under the map's node.
//!
//! The result is bit for bit what [`super::build::fill_posts`] takes from
//! the node's [`super::reference::reference_grid`] (the build's path, and
//! this one's oracle in the tests), without making that grid: the grid
//! reads every post of its 4 or 16 reference nodes through [`PostReader`]
//! (0.7 and 4.3 ms a node on the built-in terrain), where a key needs its
//! post and its four neighbours. Most of those are a stored reference
//! node's own height, one load; the rest (a post two of them share, one
//! read from an ancestor, past the data's last post, without data or at
//! zero height) take the reader's path, so every post has the grid's
//! value.

use crate::lod::TileKey;
use crate::node::{ErrorMap, NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::tiles::vertex::{slope_parts, PostReader};

use super::reference::{inverse_length, quantise_normal, stored_ancestor};

/// Fills `map`'s heights and normals (a sparse map of node `id`, its keys
/// and lattice decoded) from `source`, the pyramid the map was built on:
/// the values `fill_posts` takes from `reference_grid(source, id,
/// map.post_level)`.
pub fn fill_from_pyramid(
    source: &dyn NodeSource,
    id: NodeId,
    map: &mut ErrorMap,
) -> Result<(), NodeError> {
    let nodes = RefNodes::read(source, id, map.post_level)?;
    debug_assert_eq!(nodes.side(), map.side() as i64);
    let scale = (1u64 << map.post_level) as f64;
    let spacing = source.layout().spacing_m.map(|s| s * scale);
    map.heights.clear();
    map.normals.clear();
    map.heights.reserve_exact(map.keys.len());
    map.normals.reserve_exact(map.keys.len());
    let side = map.side();
    // Keys ascend: the row advances without a division per key.
    let (mut row, mut row_start) = (0u32, 0u32);
    // A chunk's posts first, then its divisions and square roots, each in
    // a loop of its own: they are independent from key to key, so they
    // overlap, two to a vector instruction (a key's normal alone is a
    // chain of four of them, most of a key's time).
    let mut parts = [[0.0f64; 4]; CHUNK];
    let mut slopes_of = [[0.0f64; 2]; CHUNK];
    let mut inverse = [0.0f64; CHUNK];
    for keys in map.keys.chunks(CHUNK) {
        let count = keys.len();
        for (&key, out) in keys.iter().zip(&mut parts) {
            while key >= row_start + side {
                row += 1;
                row_start += side;
            }
            let [w, c, e, s, n] = nodes.cross(i64::from(key - row_start), i64::from(row));
            map.heights.push(c as f32);
            let [rise_x, run_x] = slope_parts(w, c, e, spacing[0]);
            let [rise_y, run_y] = slope_parts(s, c, n, spacing[1]);
            *out = [rise_x, rise_y, run_x, run_y];
        }
        for (p, d) in parts[..count].iter().zip(&mut slopes_of) {
            *d = [p[0] / p[2], p[1] / p[3]];
        }
        for (d, inv) in slopes_of[..count].iter().zip(&mut inverse) {
            *inv = inverse_length(*d);
        }
        let normals = slopes_of[..count].iter().zip(&inverse);
        map.normals.extend(normals.map(|(&d, &inv)| quantise_normal(d, inv)));
    }
    Ok(())
}

/// Keys held at a time (14 KiB on the stack).
const CHUNK: usize = 256;

/// One reference node of the map's node and where its posts come from.
struct RefNode {
    /// Index of the node it is read from in [`RefNodes::data`].
    data: usize,
    /// The node it is read from: itself, or its deepest stored ancestor.
    from: NodeId,
    /// The reference node as a tile of its level (what its reader takes).
    key: TileKey,
    /// Read from itself: it wins a shared post over one read from an
    /// ancestor (see `ReferenceGrid::read_blocks`).
    stored: bool,
    /// Stored, and its posts 0..n-1 both ways lie within the data (none
    /// past its last post): a key whose cross lies there, and whose
    /// posts no other reference node wins, reads it straight from the
    /// node's heights.
    inner: bool,
}

/// The reference nodes of one node and the nodes they are read from.
struct RefNodes<'a> {
    layout: &'a NodeLayout,
    /// Reference nodes a side (a power of two).
    count: i64,
    /// Cells of a node a side (a power of two).
    n: i64,
    shift: u32,
    /// Row-major.
    list: Vec<RefNode>,
    data: Vec<NodeData>,
    all_stored: bool,
    /// The node's first reference-lattice post, east and north.
    origin: [i64; 2],
    post_level: u8,
    /// Posts a stored node's row holds, border included.
    stored_side: i64,
}

impl<'a> RefNodes<'a> {
    /// Reads node `id`'s reference nodes on the lattice of `post_level`:
    /// each from itself where stored, else from its deepest stored
    /// ancestor, each node read once.
    fn read(
        source: &'a dyn NodeSource,
        id: NodeId,
        post_level: u8,
    ) -> Result<RefNodes<'a>, NodeError> {
        let layout = source.layout();
        debug_assert!(post_level <= id.level && layout.node_size.is_power_of_two());
        let count = 1u32 << (id.level - post_level);
        let n = i64::from(layout.node_size);
        let mut nodes = RefNodes {
            layout,
            count: i64::from(count),
            n,
            shift: layout.node_size.trailing_zeros(),
            list: Vec::with_capacity((count * count) as usize),
            data: Vec::new(),
            all_stored: true,
            origin: [id.x, id.y].map(|v| i64::from(v) * i64::from(count) * n),
            post_level,
            stored_side: i64::from(layout.stored_side()),
        };
        let mut read: Vec<NodeId> = Vec::new();
        for (bx, by) in (0..count).flat_map(|y| (0..count).map(move |x| (x, y))) {
            let own = NodeId::new(post_level, id.x * count + bx, id.y * count + by);
            let from = stored_ancestor(source, layout, own, id);
            let data = match read.iter().position(|&r| r == from) {
                Some(k) => k,
                None => {
                    let mut data = NodeData::with_capacity(layout);
                    source.read_node(from, &mut data)?;
                    nodes.data.push(data);
                    read.push(from);
                    read.len() - 1
                }
            };
            let stored = from == own;
            nodes.all_stored &= stored;
            let inner = stored
                && [bx, by].into_iter().zip(nodes.origin).enumerate().all(|(k, (b, o))| {
                    nodes.in_data(k, o + i64::from(b) * n)
                        && nodes.in_data(k, o + i64::from(b) * n + n - 1)
                });
            let key = TileKey::new(post_level, own.x, own.y);
            nodes.list.push(RefNode { data, from, key, stored, inner });
        }
        Ok(nodes)
    }

    /// Posts a side of the node's reference grid.
    fn side(&self) -> i64 {
        self.count * self.n + 1
    }

    /// Whether reference-lattice post `p` (from the lattice's origin) of
    /// axis `k` has a position of the data: not west or south of it, not
    /// past its last post.
    fn in_data(&self, k: usize, p: i64) -> bool {
        let last = i64::from(self.layout.posts[k]) - 1;
        (0..=last).contains(&(p << self.post_level))
    }

    /// The heights west of grid post `(ci, cj)`, at it, east, south and
    /// north (a neighbour may lie in the node's border: -1 or `side`).
    fn cross(&self, ci: i64, cj: i64) -> [f64; 5] {
        let mask = self.n - 1;
        let (i, j) = (ci & mask, cj & mask);
        let (bx, by) = (ci >> self.shift, cj >> self.shift);
        // A post on the edge two reference nodes share is the later one's
        // (its own post 0) where both are stored: then a key at post 1
        // reads its own node only, else only from post 2 on.
        let first = if self.all_stored { 1 } else { 2 };
        let inside = (first..=self.n - 2).contains(&i) && (first..=self.n - 2).contains(&j);
        if inside && bx < self.count && by < self.count {
            let node = &self.list[(by * self.count + bx) as usize];
            if node.inner {
                let heights = &self.data[node.data].heights;
                let border = i64::from(self.layout.border);
                let at = ((j + border) * self.stored_side + i + border) as usize;
                let side = self.stored_side as usize;
                // The rows south and north of the key, and its own.
                let cross = &heights[at - side..=at + side];
                let (c, last) = (side, 2 * side);
                let posts = [cross[c - 1], cross[c], cross[c + 1], cross[0], cross[last]];
                // A height of zero or without data reads through the
                // surface's formula, which may change its sign or bits.
                if posts.iter().all(|h| h.is_finite() && *h != 0.0) {
                    let f = |k: usize| f64::from(posts[k]);
                    return [f(0), f(1), f(2), f(3), f(4)];
                }
            }
        }
        let h = |di: i64, dj: i64| f64::from(self.post(ci + di, cj + dj));
        [h(-1, 0), h(0, 0), h(1, 0), h(0, -1), h(0, 1)]
    }

    /// The height of grid post `(ci, cj)` (-1 to `side` both ways): the
    /// one the reference grid holds there.
    fn post(&self, ci: i64, cj: i64) -> f32 {
        let [bx, by] = self.winner(ci, cj);
        let node = &self.list[(by * self.count + bx) as usize];
        let data = &self.data[node.data];
        let (i, j) = (ci - bx * self.n, cj - by * self.n);
        let in_data = self.in_data(0, self.origin[0] + ci) && self.in_data(1, self.origin[1] + cj);
        if node.stored && in_data {
            if let Some(h) = self.own_height(data, i, j) {
                return h;
            }
        }
        let n = self.layout.node_size;
        PostReader::new(self.layout, node.key, n, node.from, data).post(i, j)
    }

    /// A stored reference node's post `(i, j)` as its own stored height, where that
    /// is the reader's value: a post of the stored grid before its last
    /// row and column (the reader's cell then has it as its south-west
    /// corner), finite and not zero (the cell formula keeps those bits).
    fn own_height(&self, data: &NodeData, i: i64, j: i64) -> Option<f32> {
        let border = i64::from(self.layout.border);
        let (x, y) = (i + border, j + border);
        let fits = |v: i64| (0..=self.stored_side - 2).contains(&v);
        if !(fits(x) && fits(y)) {
            return None;
        }
        let h = data.heights[(y * self.stored_side + x) as usize];
        (h.is_finite() && h != 0.0).then_some(h)
    }

    /// The reference node whose value the reference grid holds at grid
    /// post `(ci, cj)`: of those that write it, the last one
    /// `ReferenceGrid::read_blocks` writes (those read from an ancestor
    /// first, then the stored ones, each pass row by row).
    fn winner(&self, ci: i64, cj: i64) -> [i64; 2] {
        let last = self.count - 1;
        let own = |c: i64| (c >> self.shift).clamp(0, last);
        let (hx, hy) = (own(ci), own(cj));
        if self.all_stored {
            return [hx, hy];
        }
        // A post on an edge two reference nodes share is also the previous one's.
        let shared = |c: i64| c > 0 && c < self.count * self.n && c & (self.n - 1) == 0;
        let lo = |c: i64, h: i64| if shared(c) { h - 1 } else { h };
        let (lx, ly) = (lo(ci, hx), lo(cj, hy));
        let mut best = [hx, hy];
        let mut best_rank = (false, -1, -1);
        for by in ly..=hy {
            for bx in lx..=hx {
                let rank = (self.list[(by * self.count + bx) as usize].stored, by, bx);
                if rank > best_rank {
                    (best, best_rank) = ([bx, by], rank);
                }
            }
        }
        best
    }
}
