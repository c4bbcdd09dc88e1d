//! Curtains: the data's cut face drawn solid (issue 25). Where the data
//! end (the grid's edge, a no-data outline, a void), a tile hangs a
//! vertical sheet from its last drawn edge down [`CURTAIN_DEPTH_M`], drawn
//! as the "no data" hatching and read as no terrain by the accuracy tool.
//!
//! **Why.** Seen from past the data's edge, rays that pass beneath the
//! terrain's cut edge used to travel under the surface and meet whatever
//! hangs there: the skirts under tile edges further in, which exist to fill
//! cracks seen from above and err up to the two sides' errors seen from
//! below, and the terrain's underside. Neither is the terrain. A curtain
//! stops those rays where the data end, in the display and in the truth
//! alike (the truth mesh hangs the same curtains from its own edges), so
//! what a pilot sees past the edge is the terrain down to its cut edge and
//! "no data" below it. From above a curtain is never seen: it hangs below
//! the surface it ends.
//!
//! **Where.** A curtain hangs along every edge of a drawn triangle (one
//! with no vertex without data) whose neighbour across that edge, in the
//! same mesh, is dropped (has a vertex without data): [`CurtainFinder`]. A
//! tile's own edge facing posts without data hangs one through its skirt
//! vertices (`vertex::fill_skirts`, `MeshCutter::fill_skirts`). A curtain
//! past the data's last post (on a lattice coarser than the data's, whose
//! first post beyond carries an extrapolated height) is clipped with the
//! cell it hangs from: such tiles are far from the camera.

use super::block::TileVertex;

/// The `skirt` field of a curtain's foot (a skirt's is its edge, 1 to 4).
pub const CURTAIN: u16 = 5;

/// How far a curtain hangs below its top, metres: below any terrain and
/// any skirt (the deepest trench lies 11 km below sea level, the highest
/// summit 9 km above it).
pub const CURTAIN_DEPTH_M: f32 = 25_000.0;

/// The foot of a curtain hanging from `top`.
pub fn foot(top: TileVertex) -> TileVertex {
    TileVertex {
        height: top.height - CURTAIN_DEPTH_M,
        target: top.target - CURTAIN_DEPTH_M,
        ..top.with_edge(CURTAIN)
    }
}

/// Whether `vertex` is a curtain's foot.
pub fn is_foot(vertex: &TileVertex) -> bool {
    vertex.edge() == CURTAIN
}

/// Finds a mesh's curtain edges and numbers their feet. Scratch kept
/// between meshes: no allocation once the largest mesh has been seen.
#[derive(Default)]
pub struct CurtainFinder {
    /// Every triangle's edges: (lower vertex, higher vertex, drawn, from, to).
    sides: Vec<(u16, u16, bool, u16, u16)>,
    /// The curtain edges found, each as its drawn triangle winds it.
    edges: Vec<[u16; 2]>,
    /// The edges' top vertices, sorted, once each: foot `k` hangs from `tops[k]`.
    tops: Vec<u16>,
}

impl CurtainFinder {
    /// Finds the curtain edges of the triangles `indices` (counter-clockwise
    /// from above), where `dropped(v)` says vertex `v` has no data.
    pub fn find(&mut self, indices: &[u16], dropped: impl Fn(u16) -> bool) {
        self.clear();
        for tri in indices.chunks_exact(3) {
            let drawn = !tri.iter().any(|&v| dropped(v));
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                self.sides.push((a.min(b), a.max(b), drawn, a, b));
            }
        }
        self.sides.sort_unstable();
        // Within one edge's run the dropped sides sort first.
        let mut start = 0;
        while start < self.sides.len() {
            let key = (self.sides[start].0, self.sides[start].1);
            let mut end = start + 1;
            while end < self.sides.len() && (self.sides[end].0, self.sides[end].1) == key {
                end += 1;
            }
            let run = &self.sides[start..end];
            let drawn = run.iter().filter(|s| s.2).count();
            if drawn == 1 && run.len() > 1 {
                let side = run[run.len() - 1];
                debug_assert!(side.2);
                self.edges.push([side.3, side.4]);
            }
            start = end;
        }
        self.tops.extend(self.edges.iter().flatten());
        self.tops.sort_unstable();
        self.tops.dedup();
    }

    /// Forgets the last mesh's curtains (a mesh that has none).
    pub fn clear(&mut self) {
        self.sides.clear();
        self.edges.clear();
        self.tops.clear();
    }

    /// Curtain feet the last mesh needs (one per top vertex).
    pub fn feet(&self) -> usize {
        self.tops.len()
    }

    /// Indices the last mesh's curtains take (two triangles an edge).
    pub fn index_count(&self) -> usize {
        6 * self.edges.len()
    }

    /// Writes the feet (into `vertices`, from the mesh's `top` vertices,
    /// numbered from `first`) and the curtains' triangles (into `indices`),
    /// wound to face away from the drawn triangle.
    pub fn write(
        &self,
        top: impl Fn(u16) -> TileVertex,
        first: usize,
        vertices: &mut [TileVertex],
        indices: &mut [u16],
    ) {
        for (out, &v) in vertices.iter_mut().zip(&self.tops) {
            *out = foot(top(v));
        }
        let foot_of = |v: u16| {
            let k = self.tops.binary_search(&v).expect("every edge's tops are numbered");
            (first + k) as u16
        };
        for (out, &[a, b]) in indices.chunks_exact_mut(6).zip(&self.edges) {
            let (fa, fb) = (foot_of(a), foot_of(b));
            out.copy_from_slice(&[a, fa, fb, a, fb, b]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 1 cell strip, split south-west to north-east: posts 0 1 2 on
    /// the south row, 3 4 5 on the north; post 2 has no data.
    const STRIP: [u16; 12] = [0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4];

    #[test]
    fn curtains_hang_between_drawn_and_dropped_triangles_only() {
        let mut finder = CurtainFinder::default();
        finder.find(&STRIP, |v| v == 2);
        // Triangle (1, 5, 4) is drawn; (1, 2, 5) is dropped: their shared
        // edge 1-5 hangs one, wound as the drawn triangle winds it (1 -> 5).
        assert_eq!(finder.edges, vec![[1, 5]]);
        assert_eq!(finder.feet(), 2);
        let top = |v: u16| TileVertex {
            post: [v, 0],
            height: 100.0 + v as f32,
            target: 50.0,
            ..TileVertex::default()
        };
        let mut vertices = [TileVertex::default(); 2];
        let mut indices = [0u16; 6];
        finder.write(top, 6, &mut vertices, &mut indices);
        assert_eq!(indices, [1, 6, 7, 1, 7, 5]);
        assert!(vertices.iter().all(is_foot));
        assert_eq!(vertices[0].height, 101.0 - CURTAIN_DEPTH_M);
        assert_eq!(vertices[1].post, [5, 0]);
    }

    #[test]
    fn a_mesh_with_data_everywhere_or_nowhere_hangs_none() {
        let mut finder = CurtainFinder::default();
        finder.find(&STRIP, |_| false);
        assert_eq!((finder.feet(), finder.index_count()), (0, 0));
        finder.find(&STRIP, |_| true);
        assert_eq!((finder.feet(), finder.index_count()), (0, 0));
        // A lone drawn triangle's open edges are the mesh's border: the
        // tile's skirts (or curtains) decide those.
        finder.find(&STRIP[..3], |_| false);
        assert_eq!(finder.index_count(), 0);
    }

    /// The faces a curtain shows: its normal points away from the drawn
    /// triangle it hangs from (the side its rays come from), so back-face
    /// culling keeps it for a viewer in the void.
    #[test]
    fn curtains_face_the_void() {
        let mut finder = CurtainFinder::default();
        finder.find(&STRIP, |v| v == 2);
        let position = |v: usize| -> [f32; 3] {
            let (i, j) = ((v % 3) as f32, (v / 3) as f32);
            if v >= 6 {
                // Feet 6 and 7 hang under tops 1 and 5.
                let t = [1usize, 5][v - 6];
                [(t % 3) as f32, (t / 3) as f32, -10.0]
            } else {
                [i, j, 0.0]
            }
        };
        let mut indices = [0u16; 6];
        let mut vertices = [TileVertex::default(); 2];
        finder.write(|_| TileVertex::default(), 6, &mut vertices, &mut indices);
        for tri in indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| position(tri[k] as usize));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let normal = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2]];
            // The void (post 2) lies east and south of edge 1-5: +x, -y.
            assert!(normal[0] > 0.0 && normal[1] < 0.0, "{tri:?}: {normal:?}");
        }
    }
}
