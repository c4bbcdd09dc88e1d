//! Ulrich's geometric error delta of one node, measured against the best
//! data under it.
//!
//! The best data at a place is the surface of the finest *present* node
//! there (each cell split from its south-west to its north-east corner):
//! level 0 where the finest layer is, the native level of a coarser layer
//! where only that layer is. A node's delta is the largest vertical distance
//! between its own surface and the posts of those finest present nodes it
//! covers, edge posts counting for both neighbours. Both surfaces are
//! piecewise linear and the finer triangulation refines the coarser one, so
//! the largest distance is reached at a finer post: the maximum over posts
//! is the exact maximum over the area. Posts without data are left out.

use std::borrow::Cow;

use super::built::{node_of, BuiltLevel};
use crate::mesh::rtin::round_up_to_f32;
use crate::node::{cell_surface, NodeId, NodeLayout};

/// The finer levels a delta is measured against: the pyramid in memory,
/// or the records already written by a streaming build.
pub(crate) trait FinerNodes: Sync {
    /// Whether node `id` is stored.
    fn is_present(&self, id: NodeId) -> bool;
    /// The stored posts of node `id`, `None` when it is absent.
    fn posts(&self, id: NodeId) -> Option<Cow<'_, [f32]>>;
}

/// The levels of a pyramid built in memory.
pub(crate) struct InMemory<'a> {
    pub levels: &'a [BuiltLevel],
    pub layout: &'a NodeLayout,
}

impl FinerNodes for InMemory<'_> {
    fn is_present(&self, id: NodeId) -> bool {
        node_of(self.levels, self.layout, id).is_some()
    }

    fn posts(&self, id: NodeId) -> Option<Cow<'_, [f32]>> {
        node_of(self.levels, self.layout, id).map(|(posts, _)| Cow::Borrowed(posts))
    }
}

/// A node's surface: its stored posts and where it lies.
struct Surface<'a> {
    id: NodeId,
    posts: &'a [f32],
}

/// Delta of node `id` (level 1 or coarser) whose stored posts are `posts`,
/// against the present nodes of `finer`, rounded up to `f32`.
pub(crate) fn node_delta(
    finer: &dyn FinerNodes,
    layout: &NodeLayout,
    id: NodeId,
    posts: &[f32],
) -> f32 {
    let target = Surface { id, posts };
    let mut worst = 0.0f64;
    explore(finer, layout, &target, id, &mut worst);
    round_up_to_f32(worst)
}

/// Measures the finest present posts under present node `node` against `target`.
fn explore(
    finer: &dyn FinerNodes,
    layout: &NodeLayout,
    target: &Surface,
    node: NodeId,
    worst: &mut f64,
) {
    let posts = if node == target.id {
        Cow::Borrowed(target.posts)
    } else {
        match finer.posts(node) {
            Some(posts) => posts,
            None => return,
        }
    };
    let here = Surface { id: node, posts: &posts };
    if node.level == 0 {
        measure(layout, target, &here, area(layout, node), worst);
        return;
    }
    let [children_x, children_y] = layout.nodes_at(node.level - 1);
    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let child = NodeId::new(node.level - 1, 2 * node.x + dx, 2 * node.y + dy);
        if child.x >= children_x || child.y >= children_y {
            continue; // beyond the data
        }
        if finer.is_present(child) {
            explore(finer, layout, target, child, worst);
        } else if node != target.id {
            measure(layout, target, &here, area(layout, child), worst);
        }
    }
}

/// The closed area of `id` in level-0 posts, east then north.
fn area(layout: &NodeLayout, id: NodeId) -> [[u64; 2]; 2] {
    let span = layout.span(id.level);
    [[id.x as u64 * span, (id.x as u64 + 1) * span], [id.y as u64 * span, (id.y as u64 + 1) * span]]
}

/// Folds into `worst` the distance from each centre post of `from` inside
/// `area` (and inside the data) to `target`'s surface.
fn measure(
    layout: &NodeLayout,
    target: &Surface,
    from: &Surface,
    area: [[u64; 2]; 2],
    worst: &mut f64,
) {
    let side = layout.stored_side() as usize;
    let border = layout.border as usize;
    let step = 1u64 << from.id.level;
    let span = layout.span(from.id.level);
    let last = layout.posts.map(|p| p as u64 - 1);
    let start = [from.id.x as u64 * span, from.id.y as u64 * span];
    let target_step = (1u64 << target.id.level) as f64;
    let target_start = [
        target.id.x as u64 * layout.span(target.id.level),
        target.id.y as u64 * layout.span(target.id.level),
    ];
    let last_cell = layout.node_size as usize - 1;
    let t = |p: usize, q: usize| target.posts[(q + border) * side + p + border] as f64;
    for q in 0..=layout.node_size as usize {
        let y = start[1] + q as u64 * step;
        if y < area[1][0] || y > area[1][1] || y > last[1] {
            continue;
        }
        let fy = (y - target_start[1]) as f64 / target_step;
        let cy = (fy.floor() as usize).min(last_cell);
        let fv = fy - cy as f64;
        for p in 0..=layout.node_size as usize {
            let x = start[0] + p as u64 * step;
            if x < area[0][0] || x > area[0][1] || x > last[0] {
                continue;
            }
            let h = from.posts[(q + border) * side + p + border] as f64;
            let fx = (x - target_start[0]) as f64 / target_step;
            let cx = (fx.floor() as usize).min(last_cell);
            let fu = fx - cx as f64;
            let surface =
                cell_surface(t(cx, cy), t(cx + 1, cy), t(cx, cy + 1), t(cx + 1, cy + 1), fu, fv);
            let distance = (h - surface).abs();
            if distance > *worst {
                // NaN (no data on either side) never compares greater.
                *worst = distance;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_up_never_loses_the_bound() {
        for value in [0.0, 0.1, 1.0 / 3.0, 1234.5678901, 1e-30] {
            let r = round_up_to_f32(value);
            assert!(r as f64 >= value);
            assert!((r as f64 - value) <= (value * 1e-6).max(1e-40));
        }
    }

    #[test]
    fn the_cell_surface_meets_its_corners_and_diagonal() {
        let (h00, h10, h01, h11) = (1.0, 2.0, 4.0, 8.0);
        assert_eq!(cell_surface(h00, h10, h01, h11, 0.0, 0.0), h00);
        assert_eq!(cell_surface(h00, h10, h01, h11, 1.0, 0.0), h10);
        assert_eq!(cell_surface(h00, h10, h01, h11, 0.0, 1.0), h01);
        assert_eq!(cell_surface(h00, h10, h01, h11, 1.0, 1.0), h11);
        // On the diagonal both triangles agree: linear from h00 to h11.
        assert_eq!(cell_surface(h00, h10, h01, h11, 0.5, 0.5), 4.5);
    }
}
