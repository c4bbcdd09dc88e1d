//! The right-triangulated irregular network (RTIN) of one grid: longest-edge
//! bisection from the two triangles of the square down to half cells (Evans,
//! Kirkpatrick and Townsend 1997; the error-map form of Martini).
//!
//! Every triangle of the hierarchy is a right isosceles triangle; splitting it
//! puts a vertex on its hypotenuse's midpoint `m`, which is also the midpoint
//! of the neighbour across that hypotenuse. The error map stores, at `m`, a
//! value that (a) is at least the exact vertical error of both triangles that
//! split there, measured at every post they cover, and (b) is at least the
//! value at the midpoints of their children. (a) makes a triangle left unsplit
//! at `max_error` err by at most `max_error`; (b) makes the split set closed,
//! so the mesh is conforming (no T-junctions) without any neighbour walk.
//!
//! Unlike Martini, whose map holds only the midpoint's distance to the
//! hypotenuse, (a) is the triangle's error over all its posts: Martini's
//! errors add up down the hierarchy and its meshes exceed their threshold.

use super::error::MeshError;
use super::scan::scan_triangle;
use super::{cross, HeightGrid, Mesh, MAX_VERTICES};

/// One triangle of the hierarchy: hypotenuse `a`-`b`, right angle at `c`, in
/// post coordinates. `[a, c, b]` is counter-clockwise seen from above.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Triangle {
    /// One end of the hypotenuse.
    pub a: [u32; 2],
    /// The other end of the hypotenuse.
    pub b: [u32; 2],
    /// The right-angle corner.
    pub c: [u32; 2],
}

impl Triangle {
    /// The two triangles of a square of `cells` cells, split along its
    /// south-west to north-east diagonal (the tiles' diagonal).
    pub fn roots(cells: u32) -> [Triangle; 2] {
        let n = cells;
        [Triangle { a: [0, 0], b: [n, n], c: [n, 0] }, Triangle { a: [n, n], b: [0, 0], c: [0, n] }]
    }

    /// The two triangles of a square split along `diagonal`: the roots of a
    /// node whose hierarchy continues its parent's (see [`Diagonal`]).
    pub fn roots_along(cells: u32, diagonal: Diagonal) -> [Triangle; 2] {
        let n = cells;
        match diagonal {
            Diagonal::SouthWest => Triangle::roots(cells),
            Diagonal::SouthEast => [
                Triangle { a: [n, 0], b: [0, n], c: [n, n] },
                Triangle { a: [0, n], b: [n, 0], c: [0, 0] },
            ],
        }
    }

    /// The larger side of the triangle's bounding box, in posts.
    pub fn extent(&self) -> u32 {
        let span = |k: usize| {
            let lo = self.a[k].min(self.b[k]).min(self.c[k]);
            let hi = self.a[k].max(self.b[k]).max(self.c[k]);
            hi - lo
        };
        span(0).max(span(1))
    }

    /// The hypotenuse's midpoint, where a split puts its vertex.
    pub fn midpoint(&self) -> [u32; 2] {
        [(self.a[0] + self.b[0]) / 2, (self.a[1] + self.b[1]) / 2]
    }

    /// A half cell: its hypotenuse's midpoint is no post, it cannot split.
    pub fn is_leaf(&self) -> bool {
        (self.a[0] + self.b[0]) % 2 == 1
    }

    /// The two halves, each with a leg of this one as its hypotenuse and its
    /// right angle at the midpoint; orientation is kept.
    pub fn children(&self) -> [Triangle; 2] {
        let m = self.midpoint();
        [Triangle { a: self.c, b: self.a, c: m }, Triangle { a: self.b, b: self.c, c: m }]
    }

    /// The corners counter-clockwise seen from above.
    pub fn ccw(&self) -> [[u32; 2]; 3] {
        [self.a, self.c, self.b]
    }

    /// Calls `f` on every triangle `depth` bisections below this one
    /// (`2^depth` of them): the hierarchy one size at a time.
    pub fn for_each_at_depth(self, depth: u32, f: &mut impl FnMut(Triangle)) {
        if depth == 0 {
            f(self);
        } else {
            for child in self.children() {
                child.for_each_at_depth(depth - 1, f);
            }
        }
    }

    /// A half cell whose hypotenuse runs north-west to south-east, across
    /// the level-0 diagonal.
    pub fn is_anti_diagonal_leaf(&self) -> bool {
        self.is_leaf() && (self.a[0] < self.b[0]) != (self.a[1] < self.b[1])
    }

    /// The corners as drawn, counter-clockwise. A half cell across the
    /// level-0 diagonal whose cell has all four corners as vertices (its other
    /// half is a half cell too) is redrawn along the south-west to north-east
    /// diagonal, so that the two halves together are
    /// the level-0 cell and a fully refined mesh is the truth mesh.
    pub fn drawn(&self, is_vertex: impl Fn([u32; 2]) -> bool) -> [[u32; 2]; 3] {
        if !self.is_anti_diagonal_leaf() {
            return self.ccw();
        }
        let (x, y) = (self.a[0].min(self.b[0]), self.a[1].min(self.b[1]));
        let (sw, ne) = ([x, y], [x + 1, y + 1]);
        if !(is_vertex(sw) && is_vertex(ne)) {
            return self.ccw();
        }
        // The halves' right angles are the south-west and north-east corners;
        // each emits one of the two redrawn halves, so the pair emits both.
        if self.c == sw {
            [sw, [x + 1, y], ne]
        } else {
            [sw, ne, [x, y + 1]]
        }
    }

    /// The hypotenuse lies on the boundary of a square of `cells` cells.
    fn hypotenuse_on_boundary(&self, cells: u32) -> bool {
        let on = |k: usize, v: u32| self.a[k] == v && self.b[k] == v;
        on(0, 0) || on(0, cells) || on(1, 0) || on(1, cells)
    }

    /// Hypotenuse length in cells when it is axis-aligned (0 otherwise).
    fn axis_hypotenuse(&self) -> u32 {
        let dx = self.a[0].abs_diff(self.b[0]);
        let dy = self.a[1].abs_diff(self.b[1]);
        if dx == 0 || dy == 0 {
            dx + dy
        } else {
            0
        }
    }
}

/// Every post a triangle covers (edges and corners included), in rows.
pub(crate) fn for_each_post(corners: [[u32; 2]; 3], mut f: impl FnMut(u32, u32, [i64; 3])) {
    let [v0, v1, v2] = corners.map(|v| [v[0] as i64, v[1] as i64]);
    debug_assert!(cross(v0, v1, v2) > 0, "corners counter-clockwise");
    let x0 = v0[0].min(v1[0]).min(v2[0]);
    let x1 = v0[0].max(v1[0]).max(v2[0]);
    let y0 = v0[1].min(v1[1]).min(v2[1]);
    let y1 = v0[1].max(v1[1]).max(v2[1]);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let p = [x, y];
            let w = [cross(v1, v2, p), cross(v2, v0, p), cross(v0, v1, p)];
            if w.iter().all(|&w| w >= 0) {
                f(x as u32, y as u32, w);
            }
        }
    }
}

/// The plane through three corner heights at barycentric weights `w`.
pub(crate) fn on_plane(h: [f64; 3], w: [i64; 3]) -> f64 {
    let sum = (w[0] + w[1] + w[2]) as f64;
    (w[0] as f64 * h[0] + w[1] as f64 * h[1] + w[2] as f64 * h[2]) / sum
}

/// Which level-0 points a triangle's error is measured at.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Metric {
    /// Every post it covers: the pyramid's delta.
    #[default]
    Posts,
    /// Every post, and every cell centre where one of its edges crosses a
    /// level-0 cell's south-west to north-east diagonal: the supremum of the
    /// distance to the surface the truth mesh draws (see [`super::delta`]).
    Surface,
}

/// Which diagonal splits the square into the hierarchy's two root triangles.
///
/// Two levels of bisection below a square split south-west to north-east,
/// its south-west and north-east quadrants are split the same way and the
/// other two the other way. So a node whose hierarchy must be the continuation
/// of its parent's (every parent mesh then is a coarsening of the child's, and
/// a child morphed fully onto its parent draws the parent's very surface) is
/// split along [`Diagonal::of_node`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Diagonal {
    /// South-west to north-east (the level-0 cells' diagonal).
    #[default]
    SouthWest,
    /// South-east to north-west.
    SouthEast,
}

impl Diagonal {
    /// The diagonal of square `(x, y)` of a level of squares that halve a
    /// root square split south-west to north-east: the parity of `x + y`.
    pub fn of_node(x: u32, y: u32) -> Diagonal {
        if (x + y) % 2 == 0 {
            Diagonal::SouthWest
        } else {
            Diagonal::SouthEast
        }
    }
}

/// Options fixed when the error map is built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RtinOptions {
    /// Force every boundary post at a multiple of this step (a power of two)
    /// into every mesh, so neighbours built with the same step share at least
    /// those edge vertices. `None`: the boundary is refined by error only.
    pub edge_step: Option<u32>,
    /// Also keep each split's nested bounding box, for `view_refine` (the lod bench's floor).
    pub bounds: bool,
    /// What the error map measures.
    pub metric: Metric,
    /// The diagonal of the two root triangles.
    pub diagonal: Diagonal,
    /// Draw half cells as the hierarchy makes them, never redrawn along the
    /// south-west to north-east diagonal ([`Triangle::drawn`]). Needed when
    /// the grid is coarser than the data: then a coarser mesh of the same
    /// hierarchy is refined by this one only if neither redraws (a redrawn
    /// cell of the coarse lattice is no leaf of the fine one).
    pub hierarchy_leaves: bool,
}

/// The box around everything a split at one midpoint refines, nested: it
/// holds both triangles that split there and every box below them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitBounds {
    /// South-west corner, post coordinates.
    pub min: [u16; 2],
    /// North-east corner, post coordinates.
    pub max: [u16; 2],
    /// Lowest and highest height under it, metres.
    pub z: [f32; 2],
}

impl SplitBounds {
    const EMPTY: SplitBounds =
        SplitBounds { min: [u16::MAX; 2], max: [0; 2], z: [f32::INFINITY, f32::NEG_INFINITY] };

    fn union(self, other: SplitBounds) -> SplitBounds {
        SplitBounds {
            min: [self.min[0].min(other.min[0]), self.min[1].min(other.min[1])],
            max: [self.max[0].max(other.max[0]), self.max[1].max(other.max[1])],
            z: [self.z[0].min(other.z[0]), self.z[1].max(other.z[1])],
        }
    }
}

/// The error map of one grid, built once; meshes of any error come from it.
#[derive(Clone, Debug)]
pub struct Rtin {
    side: u32,
    diagonal: Diagonal,
    hierarchy_leaves: bool,
    /// Per post: the bound described in the module notes (0 where no split
    /// lands, infinite on forced edge posts), rounded up to `f32`.
    errors: Vec<f32>,
    bounds: Option<Vec<SplitBounds>>,
}

impl Rtin {
    /// Builds the error map: every triangle of the hierarchy, finest first,
    /// scanned over the posts it covers. O(posts x log posts).
    pub fn new(grid: &HeightGrid, options: RtinOptions) -> Result<Rtin, MeshError> {
        if let Some(step) = options.edge_step {
            if !step.is_power_of_two() {
                return Err(MeshError::EdgeStep(step));
            }
        }
        let side = grid.side();
        let posts = side as usize * side as usize;
        let mut rtin = Rtin {
            side,
            diagonal: options.diagonal,
            hierarchy_leaves: options.hierarchy_leaves,
            errors: vec![0.0; posts],
            bounds: options.bounds.then(|| vec![SplitBounds::EMPTY; posts]),
        };
        let depths = 2 * grid.cells().trailing_zeros();
        // Leaves (depth `depths`) cover no post but their corners: nothing to record.
        for depth in (0..depths).rev() {
            for root in Triangle::roots_along(grid.cells(), options.diagonal) {
                root.for_each_at_depth(depth, &mut |t| rtin.record(grid, t, options));
            }
        }
        Ok(rtin)
    }

    /// Posts a side of the grid.
    pub fn side(&self) -> u32 {
        self.side
    }

    /// The diagonal of the root triangles.
    pub fn diagonal(&self) -> Diagonal {
        self.diagonal
    }

    /// Whether half cells are drawn as the hierarchy makes them.
    pub fn hierarchy_leaves(&self) -> bool {
        self.hierarchy_leaves
    }

    /// The error map at post `(i, j)`: splitting there is needed for any
    /// `max_error` below it.
    pub fn error_at(&self, i: u32, j: u32) -> f32 {
        self.errors[self.index([i, j])]
    }

    /// The nested box of the split at post `(i, j)`, when kept.
    pub fn bounds_at(&self, i: u32, j: u32) -> Option<SplitBounds> {
        self.bounds.as_ref().map(|b| b[self.index([i, j])])
    }

    /// The error of the coarsest mesh (two triangles), forced edges aside.
    pub fn root_error(&self) -> f32 {
        let centre = (self.side - 1) / 2;
        self.error_at(centre, centre)
    }

    /// Calls `emit` for every triangle of the mesh whose splits are those
    /// `split(triangle, midpoint)` asks for, in depth-first order. `split`
    /// must be closed (a split child implies a split parent) and agree for
    /// the two triangles sharing a midpoint, or the mesh has T-junctions.
    pub fn walk(
        &self,
        split: &mut impl FnMut(&Triangle, [u32; 2]) -> bool,
        emit: &mut impl FnMut(Triangle),
    ) {
        for root in Triangle::roots_along(self.side - 1, self.diagonal) {
            self.walk_from(root, split, emit);
        }
    }

    fn walk_from(
        &self,
        t: Triangle,
        split: &mut impl FnMut(&Triangle, [u32; 2]) -> bool,
        emit: &mut impl FnMut(Triangle),
    ) {
        if !t.is_leaf() && split(&t, t.midpoint()) {
            for child in t.children() {
                self.walk_from(child, split, emit);
            }
        } else {
            emit(t);
        }
    }

    /// Calls `emit` for every triangle of the mesh of `max_error`.
    pub fn for_each_triangle(&self, max_error: f64, emit: &mut impl FnMut(Triangle)) {
        let errors = &self.errors;
        let side = self.side as usize;
        self.walk(
            &mut |_, m| errors[m[1] as usize * side + m[0] as usize] as f64 > max_error,
            emit,
        );
    }

    /// Triangles in the mesh of `max_error`, without building it.
    pub fn triangle_count(&self, max_error: f64) -> usize {
        let mut count = 0;
        self.for_each_triangle(max_error, &mut |_| count += 1);
        count
    }

    /// The mesh whose vertical error at every post is at most `max_error`:
    /// vertices numbered in the order the walk first meets them.
    pub fn extract(&self, max_error: f64) -> Result<Mesh, MeshError> {
        self.extract_within(max_error, self.side - 1)
    }

    /// [`Self::extract`], also splitting every triangle wider than
    /// `max_extent` posts: each triangle then lies inside one square of that
    /// many cells (a power of two), so a tile of that size or larger takes
    /// whole triangles from the mesh.
    pub fn extract_within(&self, max_error: f64, max_extent: u32) -> Result<Mesh, MeshError> {
        self.extract_with(max_error, max_extent, |_| false)
    }

    /// [`Self::extract_within`], also splitting wherever `keep(midpoint)`
    /// says: the vertices of a coarser mesh of the same hierarchy (a
    /// parent node's), so that this mesh refines that one. `keep` must be
    /// closed like a mesh's vertex set, or the mesh has T-junctions.
    pub fn extract_with(
        &self,
        max_error: f64,
        max_extent: u32,
        keep: impl Fn([u32; 2]) -> bool,
    ) -> Result<Mesh, MeshError> {
        if !(max_error >= 0.0 && max_error.is_finite()) {
            return Err(MeshError::MaxError(max_error));
        }
        let mut vertex_of = vec![u32::MAX; self.errors.len()];
        let mut vertices: Vec<[u16; 2]> = Vec::new();
        let mut triangles: Vec<u32> = Vec::new();
        let errors = &self.errors;
        let side = self.side as usize;
        let is_vertex = |p: [u32; 2]| {
            self.is_vertex(p, max_error) || self.forced_vertex(p, max_extent) || keep(p)
        };
        let mut split = |t: &Triangle, m: [u32; 2]| {
            t.extent() > max_extent
                || errors[m[1] as usize * side + m[0] as usize] as f64 > max_error
                || keep(m)
        };
        self.walk(&mut split, &mut |t| {
            let corners = if self.hierarchy_leaves { t.ccw() } else { t.drawn(is_vertex) };
            for v in corners {
                let slot = &mut vertex_of[self.index(v)];
                if *slot == u32::MAX {
                    *slot = vertices.len() as u32;
                    vertices.push([v[0] as u16, v[1] as u16]);
                }
                triangles.push(*slot);
            }
        });
        if vertices.len() > MAX_VERTICES {
            return Err(MeshError::TooManyVertices { count: vertices.len() });
        }
        let indices = triangles.into_iter().map(|v| v as u16).collect();
        Ok(Mesh { side: self.side, vertices, indices })
    }

    /// Post `p` is a vertex of the mesh of `max_error`: a corner of the
    /// square, or the midpoint of a split (every other post is the midpoint
    /// of exactly one pair of triangles).
    fn is_vertex(&self, p: [u32; 2], max_error: f64) -> bool {
        let n = self.side - 1;
        let corner = (p[0] == 0 || p[0] == n) && (p[1] == 0 || p[1] == n);
        corner || self.errors[self.index(p)] as f64 > max_error
    }

    /// Post `p` is a vertex forced by `max_extent`: the splits of every
    /// triangle wider than `max_extent` put a vertex on every post of the
    /// lattice `max_extent` apart (the corners of the squares that size).
    fn forced_vertex(&self, p: [u32; 2], max_extent: u32) -> bool {
        p[0] % max_extent == 0 && p[1] % max_extent == 0
    }

    fn index(&self, p: [u32; 2]) -> usize {
        p[1] as usize * self.side as usize + p[0] as usize
    }

    /// One triangle's contribution at its midpoint: its own exact error,
    /// its children's midpoints' values (final: they are one depth finer),
    /// and a forced split where the boundary must keep its posts.
    fn record(&mut self, grid: &HeightGrid, t: Triangle, options: RtinOptions) {
        let corners = t.ccw();
        let (mut error, z) = own_error(grid, t, options.metric);
        let forced = options.edge_step.is_some_and(|step| {
            t.hypotenuse_on_boundary(self.side - 1) && t.axis_hypotenuse() >= 2 * step
        });
        if forced {
            error = f32::INFINITY;
        }
        let m = self.index(t.midpoint());
        let [x0, y0] = corners.iter().fold([u32::MAX; 2], |a, v| [a[0].min(v[0]), a[1].min(v[1])]);
        let [x1, y1] = corners.iter().fold([0; 2], |a, v| [a[0].max(v[0]), a[1].max(v[1])]);
        let mut bounds =
            SplitBounds { min: [x0 as u16, y0 as u16], max: [x1 as u16, y1 as u16], z };
        for child in t.children().iter().filter(|c| !c.is_leaf()) {
            let cm = self.index(child.midpoint());
            error = error.max(self.errors[cm]);
            if let Some(all) = &self.bounds {
                bounds = bounds.union(all[cm]);
            }
        }
        self.errors[m] = self.errors[m].max(error);
        if let Some(all) = &mut self.bounds {
            all[m] = all[m].union(bounds);
        }
    }
}

/// Triangle `t`'s own error, before its children's are taken in: the
/// largest vertical distance from its plane to the posts it covers (and,
/// with [`Metric::Surface`], to the data's cell centres its edges cross),
/// rounded up; 0 without any post with data, infinite when it mixes posts
/// with and without data (it is then split down to half cells, so that the
/// mesh has data exactly where the grid has). Also the height range of its
/// posts with data. It depends on the heights under `t` alone, so a grid
/// holding `t` anywhere gives the same value.
pub(crate) fn own_error(grid: &HeightGrid, t: Triangle, metric: Metric) -> (f32, [f32; 2]) {
    let corners = t.ccw();
    let h = corners.map(|[i, j]| grid.at(i, j) as f64);
    let scan = scan_triangle(grid, corners, h);
    let (mut worst, with_data, without) = (scan.worst, scan.with_data, scan.without);
    if metric == Metric::Surface && without == 0 {
        for (p, q) in [(0, 1), (1, 2), (2, 0)] {
            let crossing = anti_diagonal_crossings(grid, corners[p], h[p], corners[q], h[q]);
            worst = worst.max(crossing);
        }
    }
    let error = match (with_data, without) {
        (0, _) => 0.0,
        (_, 0) => round_up_to_f32(worst),
        _ => f32::INFINITY,
    };
    (error, scan.z)
}

/// The smallest `f32` not below `value`: error maps and the pyramid's node
/// deltas are bounds, never rounded down.
pub(crate) fn round_up_to_f32(value: f64) -> f32 {
    debug_assert!(value >= 0.0, "distances are not negative");
    let rounded = value as f32;
    if (rounded as f64) < value {
        f32::from_bits(rounded.to_bits() + 1)
    } else {
        rounded
    }
}

/// Along an edge `p`-`q`, when it runs north-west to south-east: the largest
/// distance at the cell centres it passes, where the level-0 surface is the
/// mean of the cell's south-west and north-east posts.
pub(crate) fn anti_diagonal_crossings(
    grid: &HeightGrid,
    p: [u32; 2],
    hp: f64,
    q: [u32; 2],
    hq: f64,
) -> f64 {
    let (dx, dy) = (q[0] as i32 - p[0] as i32, q[1] as i32 - p[1] as i32);
    if dx == 0 || dx != -dy {
        return 0.0;
    }
    // Walk west to east; the edge then falls one post south per step.
    let ((w, hw), (_, he)) = if dx > 0 { ((p, hp), (q, hq)) } else { ((q, hq), (p, hp)) };
    let n = dx.unsigned_abs();
    let mut worst = 0.0f64;
    for s in 0..n {
        let (i, j) = (w[0] + s, w[1] - s - 1);
        let level0 = (grid.at(i, j) as f64 + grid.at(i + 1, j + 1) as f64) / 2.0;
        let t = (s as f64 + 0.5) / n as f64;
        worst = worst.max((hw + t * (he - hw) - level0).abs());
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(side: u32) -> Vec<f32> {
        (0..side * side).map(|k| ((k % side) * 3 + (k / side) * 5) as f32).collect()
    }

    #[test]
    fn a_plane_needs_two_triangles() {
        let heights = ramp(17);
        let grid = HeightGrid::new(17, &heights).unwrap();
        let rtin = Rtin::new(&grid, RtinOptions::default()).unwrap();
        let mesh = rtin.extract(0.0).unwrap();
        assert_eq!(mesh.triangle_count(), 2);
        assert_eq!(mesh.vertices.len(), 4);
    }

    #[test]
    fn children_keep_orientation_and_halve_the_area() {
        for root in Triangle::roots(8) {
            let area = |t: &Triangle| {
                let [a, b, c] = t.ccw().map(|v| [v[0] as i64, v[1] as i64]);
                cross(a, b, c)
            };
            let kids = root.children();
            assert!(kids.iter().all(|k| area(k) * 2 == area(&root)));
        }
    }

    #[test]
    fn one_spike_splits_down_to_it_and_not_elsewhere() {
        let side = 33;
        let mut heights = vec![0.0f32; 33 * 33];
        heights[5 * 33 + 7] = 10.0;
        let grid = HeightGrid::new(side, &heights).unwrap();
        let rtin = Rtin::new(&grid, RtinOptions::default()).unwrap();
        assert_eq!(rtin.error_at(7, 5), 10.0);
        let mesh = rtin.extract(1.0).unwrap();
        assert!(mesh.vertices.contains(&[7, 5]));
        assert!(mesh.triangle_count() < 64);
        assert_eq!(rtin.extract(10.0).unwrap().triangle_count(), 2);
    }

    #[test]
    fn forced_edges_keep_every_step_post() {
        let heights = ramp(33);
        let grid = HeightGrid::new(33, &heights).unwrap();
        let options = RtinOptions { edge_step: Some(4), ..RtinOptions::default() };
        let mesh = Rtin::new(&grid, options).unwrap().extract(1e9).unwrap();
        for k in (0..=32u16).step_by(4) {
            for post in [[k, 0], [k, 32], [0, k], [32, k]] {
                assert!(mesh.vertices.contains(&post), "{post:?}");
            }
        }
        assert!(!mesh.vertices.contains(&[2, 0]));
        assert_eq!(
            Rtin::new(&grid, RtinOptions { edge_step: Some(3), ..RtinOptions::default() }).err(),
            Some(MeshError::EdgeStep(3))
        );
    }

    #[test]
    fn a_full_mesh_is_the_truth_mesh() {
        // A checkerboard needs every post; every cell must then be drawn
        // south-west to north-east, as the level-0 grid.
        let heights: Vec<f32> = (0..81u32).map(|k| ((k % 9 + k / 9) % 2 * 10) as f32).collect();
        let grid = HeightGrid::new(9, &heights).unwrap();
        let mesh = Rtin::new(&grid, RtinOptions::default()).unwrap().extract(0.0).unwrap();
        assert_eq!(mesh.triangle_count(), 128);
        for t in 0..128 {
            let [a, b, c] = mesh.triangle(t);
            let diagonal = [(a, b), (b, c), (c, a)]
                .iter()
                .any(|(p, q)| p[0] != q[0] && p[1] != q[1] && (p[0] < q[0]) != (p[1] < q[1]));
            assert!(!diagonal, "triangle {t} crosses a cell the other way");
        }
    }

    #[test]
    fn too_many_vertices_is_an_error() {
        // A checkerboard of 1 m steps needs every post of a 257 x 257 grid.
        let side = 257u32;
        let heights: Vec<f32> =
            (0..side * side).map(|k| ((k % side + k / side) % 2) as f32).collect();
        let grid = HeightGrid::new(side, &heights).unwrap();
        let rtin = Rtin::new(&grid, RtinOptions::default()).unwrap();
        assert_eq!(rtin.extract(0.1), Err(MeshError::TooManyVertices { count: 257 * 257 }));
        assert!(rtin.extract(1.0).is_ok());
    }

    /// The scan against the plain per-post loop, on every triangle of a
    /// small hierarchy over rough heights with a few posts without data.
    #[test]
    fn the_scan_matches_the_post_by_post_loop() {
        let side = 33u32;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| {
                let (i, j) = ((k % side) as f32, (k / side) as f32);
                if k % 97 == 13 {
                    f32::NAN
                } else {
                    (i * 0.7).sin() * 40.0 + (j * 1.3).cos() * 25.0 + i * j * 0.05
                }
            })
            .collect();
        let grid = HeightGrid::with_voids(side, &heights).unwrap();
        for depth in 0..10 {
            for root in Triangle::roots(side - 1) {
                root.for_each_at_depth(depth, &mut |t| {
                    let corners = t.ccw();
                    let h = corners.map(|[i, j]| grid.at(i, j) as f64);
                    let scan = scan_triangle(&grid, corners, h);
                    let (mut worst, mut with, mut without) = (0.0f64, 0u32, 0u32);
                    for_each_post(corners, |i, j, w| {
                        let post = grid.at(i, j);
                        if post.is_nan() {
                            without += 1;
                        } else {
                            with += 1;
                            worst = worst.max((post as f64 - on_plane(h, w)).abs());
                        }
                    });
                    assert_eq!((scan.with_data, scan.without), (with, without), "{t:?}");
                    if h.iter().all(|v| v.is_finite()) {
                        assert!((scan.worst - worst).abs() < 1e-9, "{t:?}: {} {worst}", scan.worst);
                    }
                });
            }
        }
    }
}
