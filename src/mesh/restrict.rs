//! The restricted RTIN: one block's error hierarchy computed once, and the
//! error map of every aligned power-of-two square inside it read from it
//! (issue 21: the maps of a node and of its descendants on the same
//! reference lattice are all squares of one grid).
//!
//! A square of the block split along [`Diagonal::of_node`] is the root of
//! a subtree of the block's hierarchy, so its triangles are the block's.
//! A triangle's own error (`own_error`) depends on the posts under it
//! alone, so it is computed once per triangle of the block and kept as a
//! code ([`error_code`] keeps order, so the code of a maximum is the
//! maximum of the codes). What differs between the square's own map and
//! the block's is the propagation: at a post on the square's edge, the
//! square's map takes only the triangles inside the square (the block's
//! also takes those outside), and through the children-first maximum that
//! difference reaches the posts inside too. So the propagation is redone
//! per square, from the kept own codes: O(posts) per square, against
//! O(posts x depth) for the scans. [`OwnCodes::restrict`] gives exactly
//! the codes [`Rtin::new`] gives on the square's own grid.
//!
//! [`Rtin::new`]: super::Rtin::new

use rayon::prelude::*;

use super::code::error_code;
use super::rtin::{own_error, Triangle};
use super::{Diagonal, HeightGrid, Metric};

/// Every triangle's own error code of one block's hierarchy. A post is the
/// midpoint of at most two triangles (one each side of their shared
/// hypotenuse): `slots[s]` holds the code of the one on side `s`
/// (`slot`), 0 where none.
#[derive(Clone, Debug)]
pub struct OwnCodes {
    side: u32,
    slots: [Vec<u8>; 2],
}

/// The side of its hypotenuse a triangle's right angle lies on: 0 south
/// (or west, on a north-south hypotenuse), 1 north (or east).
fn slot(t: &Triangle, m: [u32; 2]) -> usize {
    usize::from((t.c[1], t.c[0]) > (m[1], m[0]))
}

/// Squares of the block a part of its scans covers: 4^k parts, at most 16,
/// for the cores.
fn part_cells(cells: u32) -> u32 {
    cells >> cells.trailing_zeros().min(2)
}

/// Calls `f(triangle, slot, children's midpoints)` for every non-leaf
/// triangle of the hierarchy of a square of `cells` cells (roots split
/// along `diagonal`) that halves a square of `lo..=hi` cells (powers of two,
/// `lo >= 2`) or has one's edge as its hypotenuse, finest first: per size
/// `s`, the triangles on the edges of the squares of side `s` (their right
/// angle at the square's centre), then the squares' halves. Plain loops
/// over the squares, where a walk from the roots per depth recursed.
fn for_each_split(
    cells: u32,
    diagonal: Diagonal,
    [lo, hi]: [u32; 2],
    f: &mut impl FnMut(Triangle, usize, &[[u32; 2]]),
) {
    let mut s = lo.max(2);
    while s <= hi.min(cells) {
        let h = s / 2;
        let per_side = cells / s;
        // Every edge first: an edge's midpoint takes the triangles of both
        // squares beside it before either square's halves read it.
        for qy in 0..per_side {
            for qx in 0..per_side {
                let [sw, se, nw, ne] = square_corners(qx, qy, s);
                let c = [sw[0] + h, sw[1] + h];
                // Counter-clockwise as [a, c, b]: right angle at the centre.
                for (a, b) in [(se, sw), (ne, se), (nw, ne), (sw, nw)] {
                    let t = Triangle { a, b, c };
                    let mids = [half_way(c, a), half_way(c, b)];
                    f(t, slot(&t, t.midpoint()), if s >= 4 { &mids } else { &[] });
                }
            }
        }
        for qy in 0..per_side {
            for qx in 0..per_side {
                let [sw, se, nw, ne] = square_corners(qx, qy, s);
                let along = if s == cells { diagonal } else { Diagonal::of_node(qx, qy) };
                let halves = match along {
                    Diagonal::SouthWest => {
                        [Triangle { a: sw, b: ne, c: se }, Triangle { a: ne, b: sw, c: nw }]
                    }
                    Diagonal::SouthEast => {
                        [Triangle { a: se, b: nw, c: ne }, Triangle { a: nw, b: se, c: sw }]
                    }
                };
                for t in halves {
                    let mids = [half_way(t.c, t.a), half_way(t.c, t.b)];
                    f(t, slot(&t, t.midpoint()), &mids);
                }
            }
        }
        s *= 2;
    }
}

/// The south-west, south-east, north-west and north-east corners of
/// square `(qx, qy)` of side `s`.
fn square_corners(qx: u32, qy: u32, s: u32) -> [[u32; 2]; 4] {
    let (x0, y0) = (qx * s, qy * s);
    [[x0, y0], [x0 + s, y0], [x0, y0 + s], [x0 + s, y0 + s]]
}

fn half_way(p: [u32; 2], q: [u32; 2]) -> [u32; 2] {
    [(p[0] + q[0]) / 2, (p[1] + q[1]) / 2]
}

impl OwnCodes {
    /// Scans every non-leaf triangle of the hierarchy of `grid` whose roots
    /// split it along `diagonal`, in parallel over the squares of
    /// `part_cells`, the few triangles above them after.
    pub fn new(grid: &HeightGrid, diagonal: Diagonal, metric: Metric) -> OwnCodes {
        let (side, cells) = (grid.side(), grid.cells());
        let posts = side as usize * side as usize;
        let mut codes = OwnCodes { side, slots: [vec![0; posts], vec![0; posts]] };
        let part = part_cells(cells);
        let per_side = cells / part;
        let scanned: Vec<([u32; 2], OwnCodes)> = (0..per_side * per_side)
            .into_par_iter()
            .map(|k| {
                let (px, py) = (k % per_side, k / per_side);
                let origin = [px * part, py * part];
                let along = if part == cells { diagonal } else { Diagonal::of_node(px, py) };
                let n = (part as usize + 1) * (part as usize + 1);
                let mut local = OwnCodes { side: part + 1, slots: [vec![0; n], vec![0; n]] };
                for_each_split(part, along, [2, part], &mut |t, slot, _| {
                    let k = (t.midpoint()[1] * local.side + t.midpoint()[0]) as usize;
                    let at = |v: [u32; 2]| [v[0] + origin[0], v[1] + origin[1]];
                    let placed = Triangle { a: at(t.a), b: at(t.b), c: at(t.c) };
                    local.slots[slot][k] = own_code(grid, placed, metric);
                });
                (origin, local)
            })
            .collect();
        for (origin, local) in &scanned {
            codes.merge(local, *origin);
        }
        for_each_split(cells, diagonal, [2 * part, cells], &mut |t, slot, _| {
            let m = t.midpoint();
            codes.slots[slot][(m[1] * side + m[0]) as usize] = own_code(grid, t, metric);
        });
        codes
    }

    /// Posts a side of the block.
    pub fn side(&self) -> u32 {
        self.side
    }

    /// Takes in a part's codes, its post 0 at block post `origin`.
    fn merge(&mut self, part: &OwnCodes, origin: [u32; 2]) {
        let (side, n) = (self.side as usize, part.side as usize);
        for s in 0..2 {
            for j in 0..n {
                let at = (origin[1] as usize + j) * side + origin[0] as usize;
                let row = &mut self.slots[s][at..at + n];
                for (out, &code) in row.iter_mut().zip(&part.slots[s][j * n..(j + 1) * n]) {
                    *out = (*out).max(code);
                }
            }
        }
    }

    /// The error codes of the square of `cells` cells (a power of two)
    /// whose south-west post is block post `origin`, its roots split along
    /// `diagonal` (the block's subtree there): one per post of the square,
    /// row-major, what [`super::Rtin::new`] codes on the square's own grid.
    pub fn restrict(&self, origin: [u32; 2], cells: u32, diagonal: Diagonal) -> Vec<u8> {
        let side = cells as usize + 1;
        self.propagate(origin, cells, diagonal, vec![0u8; side * side])
    }

    /// [`Self::restrict`], but the posts on the square's edges in `shared`
    /// (bits of [`ErrorMap::shared_edges`]) start from `block`, one code per
    /// post of the block: those of the square's share square's own map,
    /// which take the triangles on both sides of the edge (`meshes::block`
    /// restricts each share square so). The neighbouring square reads
    /// the same codes there, so the two squares' meshes of one error keep
    /// the same posts along their edge (no crack to fill). The square's
    /// own posts are closed over them as over any child's. The square's
    /// corners keep their own codes.
    ///
    /// [`ErrorMap::shared_edges`]: crate::node::ErrorMap::shared_edges
    pub fn restrict_sharing(
        &self,
        origin: [u32; 2],
        cells: u32,
        diagonal: Diagonal,
        shared: u8,
        block: &[u8],
    ) -> Vec<u8> {
        use crate::node::ErrorMap;
        debug_assert_eq!(block.len(), self.side as usize * self.side as usize);
        let side = cells as usize + 1;
        let mut codes = vec![0u8; side * side];
        let block_at =
            |[x, y]: [u32; 2]| block[((origin[1] + y) * self.side + origin[0] + x) as usize];
        // Not the corners: every mesh keeps a node's corners, and a corner
        // on the share square's boundary has a code from each square
        // around it (the block's and a shard's read different ones).
        for i in 1..cells {
            for (bit, p) in [
                (ErrorMap::WEST, [0, i]),
                (ErrorMap::EAST, [cells, i]),
                (ErrorMap::SOUTH, [i, 0]),
                (ErrorMap::NORTH, [i, cells]),
            ] {
                if shared & bit != 0 {
                    codes[p[1] as usize * side + p[0] as usize] = block_at(p);
                }
            }
        }
        self.propagate(origin, cells, diagonal, codes)
    }

    /// Closes `codes` (the square's, row-major, each at least what it
    /// starts from) over the square's hierarchy: each split's code is the
    /// largest of its own and its children's.
    fn propagate(
        &self,
        origin: [u32; 2],
        cells: u32,
        diagonal: Diagonal,
        mut codes: Vec<u8>,
    ) -> Vec<u8> {
        debug_assert!(cells.is_power_of_two());
        debug_assert!(origin[0] + cells < self.side && origin[1] + cells < self.side);
        let side = cells + 1;
        let block_side = self.side;
        for_each_split(cells, diagonal, [2, cells], &mut |t, slot, mids| {
            let m = t.midpoint();
            let block = ((origin[1] + m[1]) * block_side + origin[0] + m[0]) as usize;
            let mut code = self.slots[slot][block];
            for mid in mids {
                code = code.max(codes[(mid[1] * side + mid[0]) as usize]);
            }
            let out = &mut codes[(m[1] * side + m[0]) as usize];
            *out = (*out).max(code);
        });
        codes
    }
}

fn own_code(grid: &HeightGrid, t: Triangle, metric: Metric) -> u8 {
    error_code(own_error(grid, t, metric).0 as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Rtin, RtinOptions};

    #[test]
    fn a_whole_block_restricted_is_its_own_rtin() {
        let side = 33u32;
        let heights: Vec<f32> =
            (0..side * side).map(|k| (k.wrapping_mul(2_654_435_761) >> 24) as f32 * 0.1).collect();
        let grid = HeightGrid::new(side, &heights).unwrap();
        let own = OwnCodes::new(&grid, Diagonal::SouthEast, Metric::Surface);
        let options = RtinOptions {
            metric: Metric::Surface,
            diagonal: Diagonal::SouthEast,
            ..RtinOptions::default()
        };
        let rtin = Rtin::new(&grid, options).unwrap();
        let codes = own.restrict([0, 0], 32, Diagonal::SouthEast);
        for j in 0..side {
            for i in 0..side {
                let expected = error_code(rtin.error_at(i, j) as f64);
                assert_eq!(codes[(j * side + i) as usize], expected, "({i}, {j})");
            }
        }
    }

    /// Squares of a block and the block, with a hierarchy closed over
    /// its children (every split's code at least its children's).
    fn closed(codes: &[u8], cells: u32, diagonal: Diagonal) -> bool {
        let side = cells + 1;
        let mut ok = true;
        for_each_split(cells, diagonal, [2, cells], &mut |t, _, mids| {
            let at = |p: [u32; 2]| codes[(p[1] * side + p[0]) as usize];
            ok &= mids.iter().all(|&m| at(t.midpoint()) >= at(m));
        });
        ok
    }

    #[test]
    fn shared_edges_code_alike_on_both_sides_and_stay_closed() {
        use crate::node::ErrorMap;
        let side = 65u32;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| (k.wrapping_mul(2_654_435_761) >> 22) as f32 * 0.05 + (k % side) as f32)
            .collect();
        let grid = HeightGrid::new(side, &heights).unwrap();
        let own = OwnCodes::new(&grid, Diagonal::SouthEast, Metric::Surface);
        let block = own.restrict([0, 0], 64, Diagonal::SouthEast);
        let all = ErrorMap::WEST | ErrorMap::EAST | ErrorMap::SOUTH | ErrorMap::NORTH;
        let square = |q: [u32; 2]| {
            let diagonal = Diagonal::of_node(q[0], q[1]);
            let origin = q.map(|v| v * 16);
            let plain = own.restrict(origin, 16, diagonal);
            let shared = own.restrict_sharing(origin, 16, diagonal, all, &block);
            assert!(shared.iter().zip(&plain).all(|(s, p)| s >= p), "never below its own");
            assert!(closed(&shared, 16, diagonal), "closed at {q:?}");
            shared
        };
        let mut differ = 0;
        for qy in 0..4 {
            for qx in 0..3 {
                let (west, east) = (square([qx, qy]), square([qx + 1, qy]));
                // The west square's east edge is the east square's west
                // (corners apart: every mesh keeps them).
                for j in 1..16usize {
                    assert_eq!(west[j * 17 + 16], east[j * 17], "({qx}, {qy}) post {j}");
                }
                let plain = own.restrict([qx * 16, qy * 16], 16, Diagonal::of_node(qx, qy));
                let other =
                    own.restrict([qx * 16 + 16, qy * 16], 16, Diagonal::of_node(qx + 1, qy));
                differ += (1..16).filter(|j| plain[j * 17 + 16] != other[j * 17]).count();
            }
        }
        assert!(differ > 0, "the squares' own codes differ somewhere along an edge");
    }
}
