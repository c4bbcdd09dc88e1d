//! Adaptive chunk meshes, GL-free (issue 11): the right-triangulated irregular
//! network (RTIN, longest-edge bisection as in Evans et al. and Martini) over
//! one node's level-0 posts, the exact vertical error of any mesh against
//! those posts, the height on a mesh at any place (Ulrich's morph target), and
//! a view-dependent RTIN refinement that is the triangle floor of a tiled LOD.
//!
//! Coordinates: a grid is `side = 2^k + 1` posts a side, row-major, post
//! `(i, j)` at `heights[j * side + i]`, `i` east and `j` north (row 0 south,
//! the [`crate::dem::ElevationGrid`] convention). Mesh vertices are post
//! coordinates, so a mesh's heights are the grid's own samples and neighbours
//! on the same lattice get identical positions. Triangles are counter-clockwise
//! seen from above, as in [`crate::tiles::grid`].
//!
//! | module | owns |
//! |---|---|
//! | [`rtin`] | the per-post error map, computed once, and `extract(max_error)` |
//! | [`restrict`] | one block's own error codes, and every aligned square's error map read from them |
//! | [`delta`] | the exact maximum vertical distance from a mesh to the level-0 posts under it; `height_on_mesh` |
//! | `view_refine` | RTIN refinement for a camera: split while error > tau D / K (the lod bench's floor; feature `test-support`) |
//! | [`error`] | [`MeshError`]: why a grid or a mesh is refused |

pub mod code;
pub mod delta;
pub mod error;
pub mod restrict;
pub mod rtin;
mod scan;
#[cfg(feature = "test-support")]
pub mod view_refine;

pub use delta::{max_post_distance, max_surface_distance, MeshSampler};
pub use error::MeshError;
pub use restrict::OwnCodes;
pub use rtin::{Diagonal, Metric, Rtin, RtinOptions};
#[cfg(feature = "test-support")]
pub use view_refine::{view_refine, ViewParams};

/// Largest vertex count a mesh may have: indices are 16-bit.
pub const MAX_VERTICES: usize = 65_536;

/// A square grid of heights, `side = 2^k + 1` posts a side (see the module
/// notes for the layout). Borrowed: the caller owns the samples.
#[derive(Clone, Copy, Debug)]
pub struct HeightGrid<'a> {
    side: u32,
    heights: &'a [f32],
}

impl<'a> HeightGrid<'a> {
    /// Checks the shape (`2^k + 1` posts a side, at most `2^15 + 1` so that
    /// coordinates fit `u16`) and that every height is finite.
    pub fn new(side: u32, heights: &'a [f32]) -> Result<Self, MeshError> {
        let grid = Self::with_voids(side, heights)?;
        if let Some(index) = heights.iter().position(|h| h.is_nan()) {
            let side = side as usize;
            return Err(MeshError::NotFinite {
                i: (index % side) as u32,
                j: (index / side) as u32,
            });
        }
        Ok(grid)
    }

    /// [`Self::new`], but NaN marks a post without data (a void, or beyond
    /// the data): the error map then splits every triangle that mixes posts
    /// with and without data down to half cells, and leaves triangles
    /// without any alone. Infinite heights are still refused.
    pub fn with_voids(side: u32, heights: &'a [f32]) -> Result<Self, MeshError> {
        let cells = side.wrapping_sub(1);
        if side < 2 || !cells.is_power_of_two() || cells > 1 << 15 {
            return Err(MeshError::Side(side));
        }
        let expected = side as usize * side as usize;
        if heights.len() != expected {
            return Err(MeshError::Length { expected, found: heights.len() });
        }
        if let Some(index) = heights.iter().position(|h| h.is_infinite()) {
            let side = side as usize;
            return Err(MeshError::NotFinite {
                i: (index % side) as u32,
                j: (index / side) as u32,
            });
        }
        Ok(HeightGrid { side, heights })
    }

    /// Posts a side.
    pub fn side(&self) -> u32 {
        self.side
    }

    /// Cells a side, `side - 1`, a power of two.
    pub fn cells(&self) -> u32 {
        self.side - 1
    }

    /// All heights, row-major.
    pub fn heights(&self) -> &'a [f32] {
        self.heights
    }

    /// The height of post `(i, j)`.
    pub fn at(&self, i: u32, j: u32) -> f32 {
        debug_assert!(i < self.side && j < self.side);
        self.heights[j as usize * self.side as usize + i as usize]
    }
}

/// A triangle mesh on a grid's posts: vertex post coordinates, 16-bit indices,
/// triangles counter-clockwise seen from above.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mesh {
    /// Posts a side of the grid the mesh lies on.
    pub side: u32,
    /// Post coordinates `[i, j]` of each vertex.
    pub vertices: Vec<[u16; 2]>,
    /// Three indices a triangle.
    pub indices: Vec<u16>,
}

impl Mesh {
    /// The subsampled regular grid the tiles use today: every `stride`-th post
    /// (a power of two dividing `side - 1`), each cell split from its
    /// south-west to its north-east corner, as [`crate::tiles::grid`] does.
    pub fn regular(side: u32, stride: u32) -> Result<Mesh, MeshError> {
        let cells = side.wrapping_sub(1);
        if !stride.is_power_of_two() || stride > cells || cells % stride != 0 {
            return Err(MeshError::Stride { side, stride });
        }
        let n = cells / stride;
        let count = (n as usize + 1) * (n as usize + 1);
        if count > MAX_VERTICES {
            return Err(MeshError::TooManyVertices { count });
        }
        let mut vertices = Vec::with_capacity(count);
        for j in 0..=n {
            for i in 0..=n {
                vertices.push([(i * stride) as u16, (j * stride) as u16]);
            }
        }
        let post = |i: u32, j: u32| (i + j * (n + 1)) as u16;
        let mut indices = Vec::with_capacity(6 * n as usize * n as usize);
        for j in 0..n {
            for i in 0..n {
                let (sw, se, nw, ne) =
                    (post(i, j), post(i + 1, j), post(i, j + 1), post(i + 1, j + 1));
                indices.extend_from_slice(&[sw, se, ne, sw, ne, nw]);
            }
        }
        Ok(Mesh { side, vertices, indices })
    }

    /// Triangles in the mesh.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The three vertices' post coordinates of triangle `t`.
    pub fn triangle(&self, t: usize) -> [[u16; 2]; 3] {
        let idx = &self.indices[3 * t..3 * t + 3];
        [
            self.vertices[idx[0] as usize],
            self.vertices[idx[1] as usize],
            self.vertices[idx[2] as usize],
        ]
    }

    /// Each vertex's height taken from the grid it was built on.
    pub fn vertex_heights(&self, grid: &HeightGrid) -> Vec<f32> {
        debug_assert_eq!(self.side, grid.side());
        self.vertices.iter().map(|&[i, j]| grid.at(i as u32, j as u32)).collect()
    }

    /// The vertices on the grid's boundary, in skirt order (south west to
    /// east, east south to north, north east to west, west north to south:
    /// counter-clockwise, as [`crate::tiles::grid::edge_posts`]), corners at
    /// both ends of each edge. A skirt hangs from consecutive pairs.
    pub fn boundary_vertices(&self) -> [Vec<u16>; 4] {
        let last = (self.side - 1) as u16;
        let along = |edge: usize, [i, j]: [u16; 2]| -> Option<u16> {
            match edge {
                0 => (j == 0).then_some(i),
                1 => (i == last).then_some(j),
                2 => (j == last).then_some(last - i),
                _ => (i == 0).then_some(last - j),
            }
        };
        std::array::from_fn(|edge| {
            let mut on_edge: Vec<(u16, u16)> = (0..self.vertices.len())
                .filter_map(|v| along(edge, self.vertices[v]).map(|k| (k, v as u16)))
                .collect();
            on_edge.sort_unstable();
            on_edge.into_iter().map(|(_, v)| v).collect()
        })
    }
}

/// Twice the signed area of `(a, b, c)`: positive when counter-clockwise.
pub(crate) fn cross(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}
