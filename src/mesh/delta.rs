//! Ulrich's delta for a mesh: the exact maximum vertical distance from the
//! mesh to the level-0 posts under it, and the height on a mesh at any place
//! (a child vertex's morph target is its place's height on the parent's mesh).
//!
//! Two measures. [`max_post_distance`] takes every level-0 post, the mesh
//! interpolated linearly on the triangle that covers it: the definition the
//! pyramid's delta uses. [`max_surface_distance`] is the supremum over the
//! whole square against the level-0 surface the truth mesh draws (cells split
//! south-west to north-east): both surfaces are piecewise linear, so the
//! supremum lies on a vertex of their overlay, which is a post or a cell
//! centre where a mesh edge running north-west to south-east crosses a cell's
//! diagonal. Regular grids have no such edge, so the two agree on them; RTIN
//! meshes do, and there the surface measure can be larger.

use std::collections::HashMap;

use super::rtin::{anti_diagonal_crossings, for_each_post, on_plane, Diagonal, Rtin, Triangle};
use super::{HeightGrid, Mesh};

/// The largest `|mesh - post|` over every post of `grid` covered by `mesh`,
/// mesh vertex `v` at height `vertex_heights[v]`.
pub fn max_post_distance(mesh: &Mesh, vertex_heights: &[f32], grid: &HeightGrid) -> f64 {
    debug_assert_eq!(mesh.side, grid.side());
    debug_assert_eq!(vertex_heights.len(), mesh.vertices.len());
    let mut worst = 0.0f64;
    for t in 0..mesh.triangle_count() {
        let corners = mesh.triangle(t).map(|[i, j]| [i as u32, j as u32]);
        let h = triangle_heights(mesh, vertex_heights, t);
        for_each_post(corners, |i, j, w| {
            worst = worst.max((grid.at(i, j) as f64 - on_plane(h, w)).abs());
        });
    }
    worst
}

/// [`max_post_distance`], and the distance at every cell centre where a
/// north-west to south-east mesh edge crosses the level-0 cell's diagonal:
/// the exact supremum of `|mesh - level-0 surface|`.
pub fn max_surface_distance(mesh: &Mesh, vertex_heights: &[f32], grid: &HeightGrid) -> f64 {
    let mut worst = max_post_distance(mesh, vertex_heights, grid);
    for t in 0..mesh.triangle_count() {
        let corners = mesh.triangle(t);
        let h = triangle_heights(mesh, vertex_heights, t);
        for k in 0..3 {
            let (p, q) = (corners[k], corners[(k + 1) % 3]);
            let (p, q) = (p.map(u32::from), q.map(u32::from));
            worst = worst.max(anti_diagonal_crossings(grid, p, h[k], q, h[(k + 1) % 3]));
        }
    }
    worst
}

fn triangle_heights(mesh: &Mesh, vertex_heights: &[f32], t: usize) -> [f64; 3] {
    let idx = &mesh.indices[3 * t..3 * t + 3];
    [0, 1, 2].map(|k| vertex_heights[idx[k] as usize] as f64)
}

/// Heights on one RTIN mesh (one made by [`super::Rtin`]): the triangle under
/// a place is found by descending the bisection hierarchy, a triangle being
/// split exactly where its hypotenuse's midpoint is a mesh vertex.
#[derive(Clone, Debug)]
pub struct MeshSampler {
    cells: u32,
    diagonal: Diagonal,
    hierarchy_leaves: bool,
    /// Post `(i, j)` as `j * side + i` to the vertex's height.
    heights: HashMap<u32, f32>,
}

impl MeshSampler {
    /// Indexes `mesh`, vertex `v` at height `vertex_heights[v]`.
    pub fn new(mesh: &Mesh, vertex_heights: &[f32]) -> MeshSampler {
        MeshSampler::along(mesh, vertex_heights, Diagonal::SouthWest)
    }

    /// [`Self::new`] for a mesh whose root triangles meet along `diagonal`.
    pub fn along(mesh: &Mesh, vertex_heights: &[f32], diagonal: Diagonal) -> MeshSampler {
        debug_assert_eq!(vertex_heights.len(), mesh.vertices.len());
        let side = mesh.side;
        let heights = mesh
            .vertices
            .iter()
            .zip(vertex_heights)
            .map(|(&[i, j], &h)| (j as u32 * side + i as u32, h))
            .collect();
        MeshSampler { cells: side - 1, diagonal, hierarchy_leaves: false, heights }
    }

    /// [`Self::new`] for a mesh `rtin` extracted: its diagonal and leaves.
    pub fn of_rtin(mesh: &Mesh, vertex_heights: &[f32], rtin: &Rtin) -> MeshSampler {
        let sampler = MeshSampler::along(mesh, vertex_heights, rtin.diagonal());
        MeshSampler { hierarchy_leaves: rtin.hierarchy_leaves(), ..sampler }
    }

    /// The mesh's height at `(x, y)` in post coordinates (`x` east, `y`
    /// north), `None` outside the square. On an edge both triangles agree.
    pub fn height_on_mesh(&self, x: f64, y: f64) -> Option<f64> {
        let n = self.cells as f64;
        if !(0.0..=n).contains(&x) || !(0.0..=n).contains(&y) {
            return None;
        }
        let [first, second] = Triangle::roots_along(self.cells, self.diagonal);
        // The first root holds its right angle's side of the diagonal a-b.
        let (a, b) = (as_f64(first.a), as_f64(first.b));
        let c_side = signed_area(a, b, as_f64(first.c));
        let mut t = if signed_area(a, b, [x, y]) * c_side >= 0.0 { first } else { second };
        while !t.is_leaf() && self.vertex(t.midpoint()).is_some() {
            let [first, second] = t.children();
            // The children meet on the line from the right angle to the midpoint.
            let (c, m) = (as_f64(t.c), as_f64(t.midpoint()));
            let side_of_a = signed_area(c, m, as_f64(t.a));
            t = if side_of_a * signed_area(c, m, [x, y]) >= 0.0 { first } else { second };
        }
        Some(self.interpolate(self.drawn_under(&t, x, y), x, y))
    }

    /// The drawn triangle under `(x, y)` in hierarchy triangle `t`: a half
    /// cell redrawn along the level-0 diagonal ([`Triangle::drawn`]) may hand
    /// the place to the other drawn half.
    fn drawn_under(&self, t: &Triangle, x: f64, y: f64) -> [[u32; 2]; 3] {
        if self.hierarchy_leaves {
            return t.ccw();
        }
        let drawn = t.drawn(|p| self.vertex(p).is_some());
        if drawn == t.ccw() {
            return drawn;
        }
        let (sx, sy) = (t.a[0].min(t.b[0]), t.a[1].min(t.b[1]));
        let (sw, ne) = ([sx, sy], [sx + 1, sy + 1]);
        if x - sx as f64 >= y - sy as f64 {
            [sw, [sx + 1, sy], ne]
        } else {
            [sw, ne, [sx, sy + 1]]
        }
    }

    /// Whether post `(i, j)` is a vertex of the mesh.
    pub fn has_vertex(&self, i: u32, j: u32) -> bool {
        i <= self.cells && j <= self.cells && self.vertex([i, j]).is_some()
    }

    fn vertex(&self, p: [u32; 2]) -> Option<f32> {
        self.heights.get(&(p[1] * (self.cells + 1) + p[0])).copied()
    }

    fn interpolate(&self, corners: [[u32; 2]; 3], x: f64, y: f64) -> f64 {
        let [v0, v1, v2] = corners.map(as_f64);
        let h =
            corners.map(|v| self.vertex(v).expect("a mesh triangle's corners are vertices") as f64);
        let p = [x, y];
        let w = [signed_area(v1, v2, p), signed_area(v2, v0, p), signed_area(v0, v1, p)];
        (w[0] * h[0] + w[1] * h[1] + w[2] * h[2]) / (w[0] + w[1] + w[2])
    }
}

fn as_f64(p: [u32; 2]) -> [f64; 2] {
    [p[0] as f64, p[1] as f64]
}

fn signed_area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_grid_errs_at_the_skipped_posts_only() {
        // Heights 0 except one post between the stride-2 posts.
        let mut heights = vec![0.0f32; 25];
        heights[5 + 1] = 3.0;
        let grid = HeightGrid::new(5, &heights).unwrap();
        let mesh = Mesh::regular(5, 2).unwrap();
        let h = mesh.vertex_heights(&grid);
        assert_eq!(max_post_distance(&mesh, &h, &grid), 3.0);
        assert_eq!(max_surface_distance(&mesh, &h, &grid), 3.0);
        assert_eq!(max_post_distance(&Mesh::regular(5, 1).unwrap(), grid.heights(), &grid), 0.0);
    }

    #[test]
    fn a_cell_centre_on_an_anti_diagonal_edge_counts() {
        // One cell whose south-west and north-east posts are high: the level-0
        // surface's diagonal is high, a mesh edge across the other way is low.
        let heights = [10.0, 0.0, 0.0, 10.0];
        let grid = HeightGrid::new(2, &heights).unwrap();
        let mesh = Mesh {
            side: 2,
            vertices: vec![[0, 0], [1, 0], [1, 1], [0, 1]],
            indices: vec![0, 1, 3, 1, 2, 3],
        };
        let h = mesh.vertex_heights(&grid);
        assert_eq!(max_post_distance(&mesh, &h, &grid), 0.0);
        assert_eq!(max_surface_distance(&mesh, &h, &grid), 10.0);
    }
}
