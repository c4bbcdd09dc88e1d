//! The reference grid of one node: the best data under it on the lattice of
//! a finer level, the grid its adaptive mesh is simplified from.
//!
//! The node's square is cut into the squares of its descendants at the
//! reference level. Each is read from that descendant where the source
//! stores it, else from its deepest stored ancestor (best available, as the
//! tiles do), with [`PostReader`]: so posts past the data's last post carry
//! the extrapolation the terrain program clips at, and posts without data
//! are NaN, exactly as a tile of the reference level would have them.

use crate::lod::TileKey;
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::tiles::vertex::{slope, PostReader};

/// A node's reference grid and what it was read from.
pub struct ReferenceGrid {
    /// Posts a side: `node_size << (level - post_level) + 1`.
    pub side: u32,
    /// The heights, row-major, row 0 south; NaN where the data have none.
    pub heights: Vec<f32>,
    /// The same with one more post on every side (`side + 2` a side), for
    /// slopes at the node's edges that agree with the neighbour's.
    pub bordered: Vec<f32>,
    /// The level whose lattice the posts are on.
    pub post_level: u8,
    /// The largest delta of the reference-level nodes read: how far the
    /// reference surface may be from the best data (0 at level 0, and
    /// where a block came from an ancestor, which is the best data there).
    pub delta: f32,
    /// Each block's delta (the reference-level nodes the node is cut
    /// into, row-major; 0 where read from an ancestor): what a member's
    /// grid cut from this one takes its delta from.
    pub block_deltas: Vec<f32>,
}

/// Reads the reference grid of node `id` on the lattice of `post_level`
/// (at most `id.level`).
pub fn reference_grid(
    source: &dyn NodeSource,
    id: NodeId,
    post_level: u8,
) -> Result<ReferenceGrid, NodeError> {
    debug_assert!(post_level <= id.level);
    let mut grid = ReferenceGrid::unread(source.layout(), id, post_level);
    grid.read_blocks(source, id, false)?;
    grid.heights = grid.centre();
    Ok(grid)
}

impl ReferenceGrid {
    /// A grid of NaN for node `id` on the lattice of `post_level`.
    fn unread(layout: &NodeLayout, id: NodeId, post_level: u8) -> ReferenceGrid {
        let blocks = 1u32 << (id.level - post_level);
        let side = layout.node_size * blocks + 1;
        let wide = side as usize + 2;
        ReferenceGrid {
            side,
            heights: Vec::new(),
            bordered: vec![f32::NAN; wide * wide],
            post_level,
            delta: 0.0,
            block_deltas: vec![0.0; blocks as usize * blocks as usize],
        }
    }

    /// The grid without its border, row-major.
    fn centre(&self) -> Vec<f32> {
        let wide = self.side as usize + 2;
        self.bordered
            .chunks_exact(wide)
            .skip(1)
            .take(self.side as usize)
            .flat_map(|row| &row[1..wide - 1])
            .copied()
            .collect()
    }

    /// Reads node `id`'s blocks (the reference-level nodes it is cut into)
    /// into `bordered`, each from itself or its deepest stored ancestor;
    /// later blocks win on shared edges. `frame_only`: only the blocks on
    /// the node's edge, and only the outer two posts of the bordered grid
    /// (what the node's own read puts there, where a larger grid cut down
    /// holds its neighbours' posts instead).
    fn read_blocks(
        &mut self,
        source: &dyn NodeSource,
        id: NodeId,
        frame_only: bool,
    ) -> Result<(), NodeError> {
        let layout = *source.layout();
        let post_level = self.post_level;
        let blocks = 1u32 << (id.level - post_level);
        let n = layout.node_size;
        let mut data = NodeData::with_capacity(&layout);
        let mut loaded: Option<NodeId> = None;
        // Blocks read from an ancestor first, the stored ones after: on an
        // edge shared with a stored block the stored (finer) posts win,
        // whatever the order, as best available asks. So a node's own read
        // and its cut from a larger grid put the same posts there (its
        // neighbour may be stored in one and not in the other: a shard's
        // part lacks the nodes of the other shards).
        for stored_pass in [false, true] {
            for (bx, by) in (0..blocks).flat_map(|y| (0..blocks).map(move |x| (x, y))) {
                if bx == 0 && by > 0 && blocks >= RELEASE_FROM_BLOCKS {
                    source.release_pages();
                }
                let edge = bx == 0 || by == 0 || bx + 1 == blocks || by + 1 == blocks;
                if frame_only && !edge {
                    continue;
                }
                let block = NodeId::new(post_level, id.x * blocks + bx, id.y * blocks + by);
                let from = stored_ancestor(source, &layout, block, id);
                if (from == block) != stored_pass {
                    continue;
                }
                if loaded != Some(from) {
                    source.read_node(from, &mut data)?;
                    loaded = Some(from);
                }
                // A block read from an ancestor has no finer data (presence
                // is hierarchical): the ancestor's surface is the best data
                // there, so it adds no error; its own delta covers other places.
                if from == block {
                    self.block_deltas[(by * blocks + bx) as usize] = data.delta;
                    self.delta = self.delta.max(data.delta);
                }
                let reader = PostReader::new(
                    &layout,
                    TileKey::new(post_level, block.x, block.y),
                    n,
                    from,
                    &data,
                );
                self.put_block(&reader, [bx, by], [n, blocks], frame_only);
            }
        }
        Ok(())
    }

    /// Writes block `[bx, by]`'s posts 0..=n (and -1, n+1 on the node's
    /// edge) from `reader`, `blocks` a side; `frame_only`: only the outer
    /// two posts.
    fn put_block(
        &mut self,
        reader: &PostReader,
        [bx, by]: [u32; 2],
        [n, blocks]: [u32; 2],
        frame_only: bool,
    ) {
        let n = n as i64;
        let wide = self.side as usize + 2;
        let in_frame = |k: usize| k < 2 || k + 2 >= wide;
        let first = |b: u32| if b == 0 { -1 } else { 0 };
        let end = |b: u32| if b + 1 == blocks { n + 1 } else { n };
        let (x0, y0) = (bx as i64 * n + 1, by as i64 * n + 1);
        for j in first(by)..=end(by) {
            let y = (y0 + j) as usize;
            for i in first(bx)..=end(bx) {
                let x = (x0 + i) as usize;
                if !frame_only || in_frame(x) || in_frame(y) {
                    self.bordered[y * wide + x] = reader.post(i, j);
                }
            }
        }
    }

    /// The reference grid of `member`, a node under `top` (this grid's node)
    /// on the same lattice, cut from this one: exactly what
    /// [`reference_grid`] reads for it, with only its frame read again.
    pub fn cut(
        &self,
        source: &dyn NodeSource,
        top: NodeId,
        member: NodeId,
    ) -> Result<ReferenceGrid, NodeError> {
        debug_assert!(member.level <= top.level && member.level >= self.post_level);
        let layout = source.layout();
        let mut grid = ReferenceGrid::unread(layout, member, self.post_level);
        let up = top.level - member.level;
        let posts = (layout.node_size << (member.level - self.post_level)) as usize;
        let off = [member.x - (top.x << up), member.y - (top.y << up)].map(|v| v as usize * posts);
        let (wide, big) = (grid.side as usize + 2, self.side as usize + 2);
        for j in 0..wide {
            let from = (off[1] + j) * big + off[0];
            grid.bordered[j * wide..(j + 1) * wide]
                .copy_from_slice(&self.bordered[from..from + wide]);
        }
        grid.read_blocks(source, member, true)?;
        let blocks = 1usize << (member.level - self.post_level);
        let (big_blocks, b0) =
            (1usize << (top.level - self.post_level), off.map(|o| o / layout.node_size as usize));
        grid.delta = 0.0;
        for by in 0..blocks {
            for bx in 0..blocks {
                let d = self.block_deltas[(b0[1] + by) * big_blocks + b0[0] + bx];
                grid.block_deltas[by * blocks + bx] = d;
                grid.delta = grid.delta.max(d);
            }
        }
        grid.heights = grid.centre();
        Ok(grid)
    }
}

/// Grids of at least this many blocks a side release the source's pages
/// after each row of blocks. A row's nodes lie a level's width of nodes
/// from the next row's in the file, and the kernel maps whole page-cache
/// folios (up to 2 MB, even with MADV_RANDOM) around each read: a 32 x 32
/// block held 60 to 90 MB of the 16-tile pyramid mapped (against 20 MB of
/// its nodes), so the import's peak grew with the data's width.
const RELEASE_FROM_BLOCKS: u32 = 8;

/// `block` itself if the source stores it, else its deepest stored
/// ancestor, which is at most `top` (stored by the caller's contract).
pub(super) fn stored_ancestor(
    source: &dyn NodeSource,
    layout: &NodeLayout,
    block: NodeId,
    top: NodeId,
) -> NodeId {
    let mut node = block;
    while node.level < top.level && !(layout.contains(node) && source.has_node(node)) {
        node = node.parent().expect("below the top node there is a parent");
    }
    node
}

impl ReferenceGrid {
    /// The unit normal of the reference surface at post `(i, j)`, x and y
    /// quantised as the tiles' are, from central differences one post apart
    /// (one-sided where a neighbour has no data), posts `spacing_m` apart.
    pub fn normal(&self, i: u32, j: u32, spacing_m: [f64; 2]) -> [i8; 2] {
        let wide = self.side as usize + 2;
        let h = |di: i64, dj: i64| {
            let (x, y) = ((i as i64 + 1 + di) as usize, (j as i64 + 1 + dj) as usize);
            self.bordered[y * wide + x] as f64
        };
        quantised_normal([h(-1, 0), h(0, 0), h(1, 0)], [h(0, -1), h(0, 0), h(0, 1)], spacing_m)
    }
}

/// The unit normal, x and y quantised as the tiles' are, at a post from
/// the heights west, here and east (`x`) and south, here and north (`y`),
/// posts `spacing_m` apart: central differences, one-sided where a
/// neighbour has no data. One formula for the build and the page-in
/// (`super::pagein`), so both give the same bits.
#[inline]
pub fn quantised_normal(x: [f64; 3], y: [f64; 3], spacing_m: [f64; 2]) -> [i8; 2] {
    let slopes = [slope(x[0], x[1], x[2], spacing_m[0]), slope(y[0], y[1], y[2], spacing_m[1])];
    quantise_normal(slopes, inverse_length(slopes))
}

/// The inverse length of the normal of `slopes` (east and north), before
/// it is made a unit vector: a caller may take many at once, their square
/// roots and divisions then overlap.
#[inline]
pub fn inverse_length([dx, dy]: [f64; 2]) -> f64 {
    1.0 / (dx * dx + dy * dy + 1.0).sqrt()
}

/// [`quantised_normal`] from its slopes and their [`inverse_length`].
#[inline]
pub fn quantise_normal([dx, dy]: [f64; 2], inv: f64) -> [i8; 2] {
    if dx.is_nan() || dy.is_nan() {
        return [0, 0];
    }
    let q = |x: f64| round_half_away(x * 127.0).clamp(-127, 127) as i8;
    [q(-dx * inv), q(-dy * inv)]
}

/// `x.round() as i64` for `|x| < 2^52` (and 0 for NaN, as the cast
/// gives), without a call: on the x86-64 baseline `f64::round` is a libm
/// call, a third of page-in's time per key. Truncation and the fraction
/// are exact there, so the result is the same integer.
#[inline]
fn round_half_away(x: f64) -> i64 {
    let t = x as i64;
    let fraction = x - t as f64;
    t + i64::from(fraction >= 0.5) - i64::from(fraction <= -0.5)
}

#[cfg(test)]
mod tests {
    use super::round_half_away;

    /// Every quarter step from -300 to 300, its neighbours a unit in the
    /// last place away, zeros and NaN: as `f64::round` and the cast.
    #[test]
    fn rounding_is_f64_rounds() {
        let mut values = vec![0.0, -0.0, f64::NAN, 0.49999999999999994, -0.49999999999999994];
        for k in (-1200..=1200).filter(|&k| k != 0) {
            let x = k as f64 / 4.0;
            values.extend([x, f64::from_bits(x.to_bits() + 1), f64::from_bits(x.to_bits() - 1)]);
        }
        // And spread over the range a normal's component takes.
        let spread = (0..20_000u64).map(|k| {
            let bits = k.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 11;
            bits as f64 / (1u64 << 53) as f64 * 300.0 - 150.0
        });
        for x in values.into_iter().chain(spread) {
            assert_eq!(round_half_away(x), x.round() as i64, "{x:e}");
        }
    }
}
