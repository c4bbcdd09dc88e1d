//! [`TileTriangles`]: the surface triangles of a frame's drawn tiles, read
//! from their blocks and sorted into the cells of each tile, so that the
//! triangle drawn at a point is found among a few. Nothing here assumes the
//! regular grid: any mesh whose vertices lie on the tile's posts works.

use crate::render::TileUniforms;
use crate::tiles::TileBlock;

/// A triangle counts as containing a point this far outside it, in
/// barycentric weight (rounding on its edges).
const INSIDE_TOLERANCE: f64 = 1e-9;

/// Per drawn tile (in the order given) and per cell of it, the surface
/// triangles whose bounding box meets the cell; skirts left out.
#[derive(Debug, Default)]
pub(super) struct TileTriangles {
    /// Cells per tile side.
    grid_size: u32,
    /// For tile `k`, cell `c` (row by row from the south-west): its triangles
    /// are `triangles[starts[k g^2 + c]..starts[k g^2 + c + 1]]`.
    starts: Vec<u32>,
    /// Triangle numbers in their tile's block.
    triangles: Vec<u32>,
    /// Surface triangles of all tiles, each once.
    surface: u64,
    /// Per tile: its posts per vertex post (`vertex_step / post_step`; a
    /// node mesh's vertices may lie on a finer lattice than the tile's).
    scales: Vec<f64>,
}

/// A triangle's vertices, as read from the block: post positions and numbers.
pub(super) type Corners = [([f64; 2], usize); 3];

impl TileTriangles {
    /// Indexes the surface triangles of `tiles` (of `grid_size` cells),
    /// their blocks in `staging`.
    pub(super) fn new(tiles: &[TileUniforms], staging: &[u8], grid_size: u32) -> TileTriangles {
        let cells = (grid_size * grid_size) as usize;
        let mut index = TileTriangles {
            grid_size,
            starts: vec![0; tiles.len() * cells + 1],
            scales: tiles.iter().map(|t| t.vertex_step as f64 / t.post_step as f64).collect(),
            ..TileTriangles::default()
        };
        // Counting sort: count per cell, then place.
        index.each_cell(tiles, staging, |index, cell, _| index.starts[cell + 1] += 1);
        for k in 1..index.starts.len() {
            index.starts[k] += index.starts[k - 1];
        }
        index.triangles = vec![0; *index.starts.last().unwrap_or(&0) as usize];
        let mut next = index.starts.clone();
        index.each_cell(tiles, staging, |index, cell, t| {
            index.triangles[next[cell] as usize] = t;
            next[cell] += 1;
        });
        index.surface =
            tiles.iter().map(|tile| tile.block(staging).surface_triangle_count() as u64).sum();
        index
    }

    /// Surface triangles of all tiles, skirts left out.
    pub(super) fn surface_triangles(&self) -> u64 {
        self.surface
    }

    /// Calls `visit(self, cell, triangle)` for every surface triangle of
    /// every tile and every cell its bounding box meets (cells numbered
    /// across all tiles).
    fn each_cell(
        &mut self,
        tiles: &[TileUniforms],
        staging: &[u8],
        mut visit: impl FnMut(&mut Self, usize, u32),
    ) {
        let g = self.grid_size;
        for (k, tile) in tiles.iter().enumerate() {
            let block = tile.block(staging);
            for t in 0..block.triangle_count() {
                if block.is_skirt(t) {
                    continue;
                }
                let [x, y] = cell_span(&corners(&block, t, self.scales[k]), g);
                for j in y[0]..y[1] {
                    for i in x[0]..x[1] {
                        let cell = k * (g * g) as usize + (i + j * g) as usize;
                        visit(self, cell, t as u32);
                    }
                }
            }
        }
    }

    /// The surface triangle of tile `k` (its `block`) drawn at `local`
    /// posts from the tile's south-west corner, with the point's
    /// barycentric weights; `None` where no triangle is near.
    pub(super) fn at(
        &self,
        k: usize,
        block: &TileBlock<'_>,
        local: [f64; 2],
    ) -> Option<(Corners, [f64; 3])> {
        let g = self.grid_size;
        let [i, j] = local.map(|p| (p.max(0.0).floor() as u32).min(g - 1));
        let cell = k * (g * g) as usize + (i + j * g) as usize;
        let range = self.starts[cell] as usize..self.starts[cell + 1] as usize;
        let mut best: Option<(Corners, [f64; 3])> = None;
        for &t in &self.triangles[range] {
            let corners = corners(block, t as usize, self.scales[k]);
            let weights = barycentric(&corners, local);
            let least = |w: &[f64; 3]| w[0].min(w[1]).min(w[2]);
            if least(&weights) >= -INSIDE_TOLERANCE {
                return Some((corners, weights));
            }
            if best.as_ref().is_none_or(|(_, b)| least(&weights) > least(b)) {
                best = Some((corners, weights));
            }
        }
        best
    }
}

/// Triangle `t` of `block`: each vertex's position in the tile's posts
/// (`scale` of them per vertex post) and number.
fn corners(block: &TileBlock<'_>, t: usize, scale: f64) -> Corners {
    block.triangle(t).map(|v| {
        let post = block.vertex(v as usize).post;
        ([post[0] as f64 * scale, post[1] as f64 * scale], v as usize)
    })
}

/// The cells, east and north (half-open, at least one each), a triangle's
/// bounding box meets in a tile of `g` cells.
fn cell_span(corners: &Corners, g: u32) -> [[u32; 2]; 2] {
    [0, 1].map(|axis| {
        let (lo, hi) = corners
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), c| (lo.min(c.0[axis]), hi.max(c.0[axis])));
        let first = (lo as u32).min(g - 1);
        [first, (hi.ceil() as u32).clamp(first + 1, g)]
    })
}

/// The barycentric weights of `p` in the triangle.
fn barycentric(corners: &Corners, p: [f64; 2]) -> [f64; 3] {
    let [a, b, c] = corners.map(|c| c.0);
    let cross = |o: [f64; 2], u: [f64; 2], v: [f64; 2]| {
        (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    };
    let area = cross(a, b, c);
    let (wb, wc) = (cross(a, p, c) / area, cross(a, b, p) / area);
    [1.0 - wb - wc, wb, wc]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::TileKey;
    use crate::tiles::block::write_block;
    use crate::tiles::grid::{self, TileGrid};

    /// One tile of 2 cells in a staging copy, 8 bytes in.
    fn staged() -> (Vec<u8>, TileUniforms) {
        let grid = TileGrid::new(2);
        let counts = grid::counts(2);
        let mut staging = vec![0; 8 + counts.block_bytes() as usize];
        write_block(&mut staging[8..], &grid.vertices, &grid.indices);
        let tile = TileUniforms {
            key: TileKey::new(0, 0, 0),
            first_post: [0.0; 2],
            post_step: 1.0,
            vertex_step: 1.0,
            morph: [0.0; 2],
            sub_morph_end: 0.0,
            skirt_depth: 0.0,
            skirt_edges: 0,
            skirt_shares: [0; 4],
            skirt_slope: f32::INFINITY,
            byte_offset: 8,
            index_byte_offset: 8 + counts.vertex_bytes(),
            index_count: counts.indices,
            no_data: false,
            place: crate::earth::NodePlace::default(),
            ground: None,
        };
        (staging, tile)
    }

    #[test]
    fn a_point_finds_the_surface_triangle_drawn_there() {
        let (staging, tile) = staged();
        let index = TileTriangles::new(std::slice::from_ref(&tile), &staging, 2);
        assert_eq!(index.surface_triangles(), 8, "skirts left out");
        let block = tile.block(&staging);
        // Cell (1, 0), below its diagonal: south-west 1, south-east 2, north-east 5.
        let (corners, weights) = index.at(0, &block, [1.75, 0.25]).expect("a triangle");
        assert_eq!(corners.map(|c| c.1), [1, 2, 5]);
        let expected = [0.25, 0.5, 0.25];
        assert!(weights.iter().zip(expected).all(|(w, e)| (w - e).abs() < 1e-12), "{weights:?}");
        // Above it, and on the tile's north-east corner.
        assert_eq!(index.at(0, &block, [1.25, 0.75]).unwrap().0.map(|c| c.1), [1, 5, 4]);
        assert!(index.at(0, &block, [2.0, 2.0]).unwrap().0.iter().any(|c| c.1 == 8));
    }
}
