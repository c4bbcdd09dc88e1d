//! [`EarthGround`]: the best data placed on the WGS 84 ellipsoid, as the
//! geodetic truth follows rays against it: at every place the finest
//! present node's posts joined as triangles split from south-west to
//! north-east in the grid's own coordinates (`NodeSource::exact_height`'s
//! surface), each point at its geodetic latitude, longitude and height
//! ([`GridPlacement`]). Nothing of the display's geometry is used.
//!
//! For the rays it also keeps bounds: the highest height over blocks of
//! [`EarthGround::block_posts`] level-0 posts, a max pyramid over them, and
//! at each level the highest over each block's 3 x 3 neighbourhood (a ray
//! whose height is above that bound may move a block's width without
//! meeting the ground, wherever in the block it is).
//!
//! And *strip bounds*: the highest height over each strip between two level-0 rows,
//! all columns, and over strips within `2^k` rows of each. Near a pole, where
//! a ray crosses thousands of converging meridians in a few hundred metres,
//! a strip is a small ring around the pole and its highest height is close
//! to the ground's: a ray clear of it needs no lattice crossings checked.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use crate::earth::GridPlacement;
use crate::node::{cell_surface, NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// No node index: a footprint outside the reach of the views.
const NONE: u32 = u32::MAX;

/// One best-data node's centre posts.
struct GroundNode {
    id: NodeId,
    /// `(node_size + 1)^2` heights, row 0 south, NaN without data.
    heights: Vec<f32>,
}

/// The highest height over blocks of posts, per pyramid level of blocks.
struct BlockLevel {
    /// Blocks east and north.
    size: [usize; 2],
    /// Highest height of the 3 x 3 blocks around each block (row-major),
    /// `-inf` where none has data.
    around: Vec<f32>,
    /// Highest height of each row of blocks and the rows beside it, all
    /// columns: near a pole, where blocks are slivers east-west, a ray
    /// skips by latitude bands instead.
    bands: Vec<f32>,
}

/// The best data on the ellipsoid, loaded for the places a set of views can see.
pub struct EarthGround {
    placement: GridPlacement,
    layout: NodeLayout,
    /// Per level-0 node footprint (row-major over `nodes_at(0)`): its best
    /// present node's index in `nodes`, or [`NONE`].
    best: Vec<u32>,
    nodes: Vec<GroundNode>,
    /// Level-0 posts per block side (a power of two dividing `node_size`).
    block_posts: u32,
    levels: Vec<BlockLevel>,
    /// Per row of level-0 blocks: the least distance on the ellipsoid
    /// between neighbouring posts over that row and the rows beside it,
    /// east or north, metres; and north only.
    row_spacing_m: Vec<f64>,
    row_north_m: Vec<f64>,
    /// `strip_levels[k][r]`: the highest height over the strips between level-0
    /// rows `r - 2^k` and `r + 2^k + 1` (all columns), `-inf` without data.
    strip_levels: Vec<Vec<f32>>,
    /// The least north-south distance between neighbouring rows anywhere on
    /// the grid, metres (less 1 %).
    least_north_m: f64,
    top_m: f64,
    bottom_m: f64,
}

impl EarthGround {
    /// Loads the best data of `source` (placed by `placement`) wherever a
    /// footprint of a level-0 node lies within `reach_m` metres of one of
    /// `eyes` (ECEF). Reads each needed node once, in parallel.
    pub fn load(
        source: &dyn NodeSource,
        placement: GridPlacement,
        eyes: &[DVec3],
        reach_m: f64,
    ) -> Result<EarthGround, NodeError> {
        let layout = *source.layout();
        let [nx, ny] = layout.nodes_at(0);
        let span = layout.span(0) as f64;
        let mut ids: HashMap<NodeId, u32> = HashMap::new();
        let mut order: Vec<NodeId> = Vec::new();
        let mut best = vec![NONE; nx as usize * ny as usize];
        // Footprints that may lie within reach of some eye.
        let mut candidates = vec![false; best.len()];
        for eye in eyes {
            let (post, _) = placement.post_of_ecef(*eye);
            let (lo, hi) = placement.post_window(post, reach_m);
            let range = |lo: f64, hi: f64, n: u32| {
                let first = (lo / span).floor().clamp(0.0, n as f64) as u32;
                let last = (hi / span).floor().clamp(0.0, (n - 1) as f64) as u32;
                first..=last
            };
            let wraps = placement.period_posts().is_some();
            let xs = if wraps { 0..=nx - 1 } else { range(lo[0], hi[0], nx) };
            for fy in range(lo[1], hi[1], ny) {
                for fx in xs.clone() {
                    candidates[(fy * nx + fx) as usize] = true;
                }
            }
        }
        for fy in 0..ny {
            for fx in 0..nx {
                if !candidates[(fy * nx + fx) as usize] {
                    continue;
                }
                let centre = [(fx as f64 + 0.5) * span, (fy as f64 + 0.5) * span];
                let corner = placement.ecef(fx as f64 * span, fy as f64 * span, 0.0);
                let middle = placement.ecef(centre[0], centre[1], 0.0);
                let radius = 1.5 * middle.distance(corner) + 10_000.0;
                if !eyes.iter().any(|e| e.distance(middle) - radius < reach_m) {
                    continue;
                }
                let Some(id) = best_present(source, &layout, NodeId::new(0, fx, fy)) else {
                    continue;
                };
                let next = order.len() as u32;
                let index = *ids.entry(id).or_insert_with(|| {
                    order.push(id);
                    next
                });
                best[(fy * nx + fx) as usize] = index;
            }
        }
        let nodes = order
            .par_iter()
            .map(|&id| read_centre(source, &layout, id))
            .collect::<Result<Vec<_>, _>>()?;
        let mut ground = EarthGround {
            placement,
            layout,
            best,
            nodes,
            block_posts: block_posts(&layout),
            levels: Vec::new(),
            row_spacing_m: Vec::new(),
            row_north_m: Vec::new(),
            strip_levels: Vec::new(),
            least_north_m: 0.0,
            top_m: f64::NEG_INFINITY,
            bottom_m: f64::INFINITY,
        };
        ground.build_bounds();
        Ok(ground)
    }

    /// The placement the ground was loaded with.
    pub fn placement(&self) -> &GridPlacement {
        &self.placement
    }

    /// Level-0 posts per side of the finest blocks.
    pub fn block_posts(&self) -> u32 {
        self.block_posts
    }

    /// Highest and lowest height of the loaded data, metres
    /// (`-inf, inf` when none was loaded).
    pub fn height_range(&self) -> (f64, f64) {
        (self.bottom_m, self.top_m)
    }

    /// Level-0 post `(u, v)` brought onto the grid (wrapped for a grid that
    /// wraps); `None` off the data.
    pub fn on_grid(&self, u: f64, v: f64) -> Option<[f64; 2]> {
        let u = self.placement.wrap_u(u);
        let last = self.layout.posts.map(|p| p.saturating_sub(1) as f64);
        (u >= 0.0 && v >= 0.0 && u <= last[0] && v <= last[1]).then_some([u, v])
    }

    /// The best data's height at level-0 post `(u, v)`: `None` off the data,
    /// outside the loaded reach, or where the triangle there touches a post
    /// without data.
    pub fn height(&self, u: f64, v: f64) -> Option<f64> {
        let [u, v] = self.on_grid(u, v)?;
        let (node, [a, b]) = self.node_at(u, v)?;
        let n = self.layout.node_size;
        let cell = |p: f64| (p.max(0.0).floor() as u32).min(n - 1);
        let (i, j) = (cell(a), cell(b));
        let side = n + 1;
        let h = |di: u32, dj: u32| node.heights[((j + dj) * side + i + di) as usize] as f64;
        let z = cell_surface(h(0, 0), h(1, 0), h(0, 1), h(1, 1), a - i as f64, b - j as f64);
        z.is_finite().then_some(z)
    }

    /// The cell size, level-0 posts, of the best data at `(u, v)` (on the grid).
    pub fn cell_posts(&self, u: f64, v: f64) -> Option<f64> {
        let [u, v] = self.on_grid(u, v)?;
        self.node_at(u, v).map(|(node, _)| (1u64 << node.id.level) as f64)
    }

    /// The best node at grid post `(u, v)` and the point in its posts.
    fn node_at(&self, u: f64, v: f64) -> Option<(&GroundNode, [f64; 2])> {
        let [nx, ny] = self.layout.nodes_at(0);
        let span = self.layout.span(0) as f64;
        let fx = ((u / span).floor() as u32).min(nx - 1);
        let fy = ((v / span).floor() as u32).min(ny - 1);
        let index = self.best[(fy * nx + fx) as usize];
        let node = self.nodes.get(index as usize)?;
        let stride = (1u64 << node.id.level) as f64;
        let node_span = self.layout.span(node.id.level) as f64;
        let a = (u - node.id.x as f64 * node_span) / stride;
        let b = (v - node.id.y as f64 * node_span) / stride;
        Some((node, [a, b]))
    }

    /// The largest block, level `k` of the block pyramid, whose 3 x 3
    /// neighbourhood's highest height is below `height_m`, at grid post
    /// `(u, v)`: its level, and that highest height. `None`: the ray is at
    /// or below the highest ground around even at the finest blocks.
    pub fn clear_block(&self, u: f64, v: f64, height_m: f64) -> Option<(usize, f64)> {
        let b = self.block_posts as f64;
        let mut found = None;
        for (k, level) in self.levels.iter().enumerate() {
            let scale = b * (1u64 << k) as f64;
            let (i, j) = ((u / scale).floor() as usize, (v / scale).floor() as usize);
            let [w, h] = level.size;
            let top = level.around[j.min(h - 1) * w + i.min(w - 1)];
            if (top as f64) < height_m {
                found = Some((k, top as f64));
            } else {
                break;
            }
        }
        found
    }

    /// The least distance on the ellipsoid between neighbouring posts
    /// around grid row `v`, metres.
    pub fn post_spacing_near(&self, v: f64) -> f64 {
        let row = (v / self.block_posts as f64).floor().max(0.0) as usize;
        self.row_spacing_m[row.min(self.row_spacing_m.len() - 1)]
    }

    /// The least distance between neighbouring posts north-south around
    /// grid row `v`, metres.
    pub fn north_spacing_near(&self, v: f64) -> f64 {
        let row = (v / self.block_posts as f64).floor().max(0.0) as usize;
        self.row_north_m[row.min(self.row_north_m.len() - 1)]
    }

    /// The largest latitude band (a row of blocks of level `k` and the rows
    /// beside it, every column) whose highest height is below `height_m`
    /// at grid row `v`: its level and that height.
    pub fn clear_band(&self, v: f64, height_m: f64) -> Option<(usize, f64)> {
        let mut found = None;
        for (k, level) in self.levels.iter().enumerate() {
            let row = (v / self.block_side_posts(k)).floor().max(0.0) as usize;
            let top = level.bands[row.min(level.size[1] - 1)];
            if (top as f64) < height_m {
                found = Some((k, top as f64));
            } else {
                break;
            }
        }
        found
    }

    /// Level-0 posts per side of a block at level `k`.
    pub fn block_side_posts(&self, k: usize) -> f64 {
        self.block_posts as f64 * (1u64 << k) as f64
    }

    fn build_bounds(&mut self) {
        let [nx, ny] = self.layout.nodes_at(0);
        let per = (self.layout.node_size / self.block_posts) as usize;
        let size = [nx as usize * per, ny as usize * per];
        let mut blocks = vec![f32::NEG_INFINITY; size[0] * size[1]];
        for (row, out) in blocks.chunks_mut(size[0]).enumerate() {
            for (col, top) in out.iter_mut().enumerate() {
                *top = self.block_top(col, row);
            }
        }
        for &top in blocks.iter().filter(|t| t.is_finite()) {
            self.top_m = self.top_m.max(top as f64);
        }
        self.bottom_m = self
            .nodes
            .iter()
            .flat_map(|n| n.heights.iter())
            .fold(f64::INFINITY, |lo, &h| if h.is_nan() { lo } else { lo.min(h as f64) });
        let wraps = self.placement.period_posts().is_some();
        let mut level = blocks;
        let mut level_size = size;
        loop {
            let around = dilate(&level, level_size, wraps);
            let bands = around
                .chunks(level_size[0])
                .map(|row| row.iter().copied().fold(f32::NEG_INFINITY, f32::max))
                .collect();
            self.levels.push(BlockLevel { size: level_size, around, bands });
            if level_size[0] <= 1 && level_size[1] <= 1 {
                break;
            }
            (level, level_size) = halve(&level, level_size);
        }
        (self.row_spacing_m, self.row_north_m) = self.row_spacings(size[1]);
        self.least_north_m = self.row_north_m.iter().copied().fold(f64::INFINITY, f64::min);
        self.strip_levels = strip_levels(self.strip_tops());
    }

    /// The highest height over every strip between two neighbouring level-0
    /// rows, all columns: over the posts of every loaded node's cells there
    /// (a superset of each footprint's best node, so never too low).
    fn strip_tops(&self) -> Vec<f32> {
        let strips = self.layout.posts[1].saturating_sub(1).max(1) as usize;
        let mut tops = vec![f32::NEG_INFINITY; strips];
        let side = self.layout.node_size as usize + 1;
        for node in &self.nodes {
            let stride = 1usize << node.id.level;
            let y0 = node.id.y as usize * self.layout.span(node.id.level) as usize;
            let rows: Vec<f32> = node
                .heights
                .chunks(side)
                .map(|row| row.iter().copied().fold(f32::NEG_INFINITY, f32::max))
                .collect();
            for (j, pair) in rows.windows(2).enumerate() {
                let first = (y0 + j * stride).min(strips);
                let last = (y0 + (j + 1) * stride).min(strips);
                for top in &mut tops[first..last] {
                    *top = top.max(pair[0].max(pair[1]));
                }
            }
        }
        tops
    }

    /// The highest height of the ground between level-0 rows `v_lo` and
    /// `v_hi` (any column); `-inf` where no data is loaded there.
    pub fn rows_top(&self, v_lo: f64, v_hi: f64) -> f64 {
        let Some(strips) = self.strip_levels.first().map(Vec::len) else {
            return f64::NEG_INFINITY;
        };
        let last = strips as f64 - 1.0;
        let lo = v_lo.floor().clamp(0.0, last) as usize;
        let hi = v_hi.floor().clamp(0.0, last) as usize;
        let centre = lo + (hi - lo) / 2;
        let reach = (hi - centre).max(1);
        let k = (usize::BITS - (reach - 1).leading_zeros()) as usize;
        match self.strip_levels.get(k) {
            Some(level) => level[centre] as f64,
            None => self.top_m,
        }
    }

    /// How far a ray at grid row `v` and `height_m` may move without meeting
    /// the ground by the strips around it (the largest clear band of rows, its
    /// width or the ray's height over it, whichever is less); `None` when
    /// even the nearest strips reach the ray.
    pub fn clear_strips(&self, v: f64, height_m: f64) -> Option<f64> {
        let strips = self.strip_levels.first().map_or(0, Vec::len);
        if strips == 0 || !v.is_finite() {
            return None;
        }
        let row = v.floor().clamp(0.0, strips as f64 - 1.0) as usize;
        let mut found = None;
        for (k, level) in self.strip_levels.iter().enumerate() {
            let top = level[row] as f64;
            if top >= height_m {
                break;
            }
            // Within `2^k` rows' least distance the ray stays in the strips
            // `row - 2^k ..= row + 2^k`.
            let reach_m = (1u64 << k) as f64 * self.least_north_m;
            found = Some((height_m - top).min(reach_m));
        }
        found
    }

    /// The least north-south distance between neighbouring rows, metres.
    pub fn least_north_m(&self) -> f64 {
        self.least_north_m
    }

    /// The highest post of the best data over level-0 block `(col, row)`:
    /// over the cells of the best node that the block overlaps.
    fn block_top(&self, col: usize, row: usize) -> f32 {
        let b = self.block_posts as f64;
        let (u0, v0) = (col as f64 * b, row as f64 * b);
        let Some((node, [a0, b0])) = self.node_at(u0 + 0.5, v0 + 0.5) else {
            return f32::NEG_INFINITY;
        };
        let stride = (1u64 << node.id.level) as f64;
        let n = self.layout.node_size as i64;
        // Node posts around the block (coarse cells: the one cell it is in).
        let lo = |a: f64| ((a - 0.5 / stride).floor() as i64).clamp(0, n);
        let hi = |a: f64| ((a - 0.5 / stride + b / stride).ceil() as i64).clamp(0, n);
        let (i0, i1, j0, j1) = (lo(a0), hi(a0), lo(b0), hi(b0));
        let side = (n + 1) as usize;
        let mut top = f32::NEG_INFINITY;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let h = node.heights[j as usize * side + i as usize];
                if !h.is_nan() {
                    top = top.max(h);
                }
            }
        }
        top
    }

    /// Per row of level-0 blocks, the least post spacing (east or north,
    /// and north alone) over it and the rows beside it (sampled at 9
    /// columns, every row edge), less 1 %.
    fn row_spacings(&self, rows: usize) -> (Vec<f64>, Vec<f64>) {
        let b = self.block_posts as f64;
        let last = self.layout.posts.map(|p| p.saturating_sub(1).max(1) as f64);
        let edge: Vec<[f64; 2]> = (0..=rows)
            .map(|r| {
                let v = (r as f64 * b).min(last[1]);
                (0..=8)
                    .map(|c| {
                        let u = last[0] * c as f64 / 8.0;
                        let du = if u + 1.0 > last[0] { -1.0 } else { 1.0 };
                        let dv = if v + 1.0 > last[1] { -1.0 } else { 1.0 };
                        let here = self.placement.ecef(u, v, 0.0);
                        let east = here.distance(self.placement.ecef(u + du, v, 0.0));
                        let north = here.distance(self.placement.ecef(u, v + dv, 0.0));
                        [east.min(north), north]
                    })
                    .fold([f64::INFINITY; 2], |a, b| [a[0].min(b[0]), a[1].min(b[1])])
            })
            .collect();
        let least = |axis: usize| -> Vec<f64> {
            (0..rows)
                .map(|r| {
                    let (lo, hi) = (r.saturating_sub(1), (r + 2).min(rows));
                    edge[lo..=hi].iter().map(|e| e[axis]).fold(f64::INFINITY, f64::min) * 0.99
                })
                .collect()
        };
        (least(0), least(1))
    }
}

/// The finest stored node holding footprint `id` (a level-0 node).
fn best_present(source: &dyn NodeSource, layout: &NodeLayout, id: NodeId) -> Option<NodeId> {
    let mut id = id;
    loop {
        if source.has_node(id) {
            return Some(id);
        }
        id = id.parent().filter(|p| p.level < layout.levels)?;
    }
}

/// Node `id`'s centre posts.
fn read_centre(
    source: &dyn NodeSource,
    layout: &NodeLayout,
    id: NodeId,
) -> Result<GroundNode, NodeError> {
    let mut data = NodeData::with_capacity(layout);
    source.read_node(id, &mut data)?;
    let n = layout.node_size;
    let heights = (0..=n).flat_map(|j| (0..=n).map(move |i| (i, j)));
    Ok(GroundNode { id, heights: heights.map(|(i, j)| data.post(layout, i, j)).collect() })
}

/// Level-0 posts per finest block: 16, or more for grids of many posts
/// (at most about 2^21 blocks), never more than a node.
fn block_posts(layout: &NodeLayout) -> u32 {
    let posts = layout.posts[0] as u64 * layout.posts[1] as u64;
    let mut b = 16u32.min(layout.node_size);
    while b < layout.node_size && posts / (b as u64 * b as u64) > 1 << 21 {
        b *= 2;
    }
    b
}

/// Each block's highest over its 3 x 3 neighbourhood; for a grid that
/// wraps, the first and last columns are neighbours.
fn dilate(tops: &[f32], [w, h]: [usize; 2], wraps: bool) -> Vec<f32> {
    let mut out = vec![f32::NEG_INFINITY; tops.len()];
    for j in 0..h {
        for i in 0..w {
            let mut top = f32::NEG_INFINITY;
            for dj in -1i64..=1 {
                let y = j as i64 + dj;
                if y < 0 || y >= h as i64 {
                    continue;
                }
                for di in -1i64..=1 {
                    let mut x = i as i64 + di;
                    if wraps {
                        x = x.rem_euclid(w as i64);
                    } else if x < 0 || x >= w as i64 {
                        continue;
                    }
                    top = top.max(tops[y as usize * w + x as usize]);
                }
            }
            out[j * w + i] = top;
        }
    }
    out
}

/// `out[k][r]`: the highest of `tops` over `r - 2^k ..= r + 2^k` (clamped
/// to the strips), for every `k` until one level spans them all.
fn strip_levels(tops: Vec<f32>) -> Vec<Vec<f32>> {
    let n = tops.len();
    let at = |level: &[f32], r: i64| level[r.clamp(0, n as i64 - 1) as usize];
    let first: Vec<f32> =
        (0..n as i64).map(|r| at(&tops, r - 1).max(at(&tops, r)).max(at(&tops, r + 1))).collect();
    let mut levels = vec![first];
    while (1usize << (levels.len() - 1)) < n {
        let k = levels.len() - 1;
        let below = &levels[k];
        let step = 1i64 << k;
        let next = (0..n as i64).map(|r| at(below, r - step).max(at(below, r + step))).collect();
        levels.push(next);
    }
    levels
}

/// The next level of a max pyramid: each block the highest of its 2 x 2.
fn halve(tops: &[f32], [w, h]: [usize; 2]) -> (Vec<f32>, [usize; 2]) {
    let size = [w.div_ceil(2), h.div_ceil(2)];
    let mut out = vec![f32::NEG_INFINITY; size[0] * size[1]];
    for j in 0..h {
        for i in 0..w {
            let at = (j / 2) * size[0] + i / 2;
            out[at] = out[at].max(tops[j * w + i]);
        }
    }
    (out, size)
}
