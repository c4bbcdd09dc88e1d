//! The regular grid mesh: a tile of `grid_size` cells a side, every post a
//! vertex, with skirts. The tile cache writes it into each regular tile's
//! block ([`super::block`]): the positions and indices below, the heights
//! made per tile.
//!
//! Vertex numbering: the `(g + 1)^2` posts row by row from the south-west
//! corner (`i + j * (g + 1)`), then the skirt: for each edge (south, east,
//! north, west) the `g + 1` posts along it, repeated with their edge's number
//! (1 to 4) as skirt flag, so the shader lowers them by the tile's skirt
//! depth where that edge hangs a skirt (Ulrich section 11).
//! Cells are split from their south-west to their north-east corner, the same
//! diagonal the pyramid's delta is measured on.

use super::block::{MeshCounts, TileVertex};

/// The regular grid of one grid size: the vertices with their positions
/// (surfaces zero, for the tile fill to write) and the indices.
#[derive(Clone, Debug, PartialEq)]
pub struct TileGrid {
    /// Cells per tile side (1..=256).
    pub grid_size: u32,
    /// The `(g + 1)^2` posts row by row, then the skirt vertices of each edge.
    pub vertices: Vec<TileVertex>,
    /// Triangles, counter-clockwise seen from above.
    pub indices: Vec<u16>,
}

impl TileGrid {
    /// Builds the mesh for tiles of `grid_size` cells a side (1..=256; its
    /// vertices must number in 16 bits).
    pub fn new(grid_size: u32) -> Self {
        debug_assert!((1..=256).contains(&grid_size));
        let g = grid_size;
        let vertices = positions(g)
            .map(|(post, skirt)| TileVertex { post, skirt, ..TileVertex::default() })
            .collect();
        let mut indices = Vec::with_capacity(index_count(g));
        let post = |i: u32, j: u32| (i + j * (g + 1)) as u16;
        for j in 0..g {
            for i in 0..g {
                let (sw, se, nw, ne) =
                    (post(i, j), post(i + 1, j), post(i, j + 1), post(i + 1, j + 1));
                indices.extend_from_slice(&[sw, se, ne, sw, ne, nw]);
            }
        }
        // Skirt quads hang below each edge, wound to face outward.
        let skirt_base = (g + 1) * (g + 1);
        for edge in 0..4 {
            for k in 0..g {
                let top0 = edge_post_index(g, edge, k);
                let top1 = edge_post_index(g, edge, k + 1);
                let low0 = (skirt_base + edge * (g + 1) + k) as u16;
                let low1 = low0 + 1;
                indices.extend_from_slice(&[top0, low0, low1, top0, low1, top1]);
            }
        }
        debug_assert_eq!(indices.len(), index_count(g));
        TileGrid { grid_size, vertices, indices }
    }
}

/// Every vertex's position in grid numbering: its post and its skirt edge
/// (1 to 4, or 0 for a post of the surface).
pub fn positions(g: u32) -> impl Iterator<Item = ([u16; 2], u16)> {
    let posts = (0..=g).flat_map(move |j| (0..=g).map(move |i| ([i as u16, j as u16], 0)));
    let skirts = edge_posts(g)
        .enumerate()
        .map(move |(k, (i, j))| ([i as u16, j as u16], (k as u32 / (g + 1) + 1) as u16));
    posts.chain(skirts)
}

/// Vertices and indices of a regular tile of `grid_size` cells.
pub fn counts(grid_size: u32) -> MeshCounts {
    MeshCounts {
        vertices: vertex_count(grid_size) as u32,
        indices: index_count(grid_size) as u32,
        skirt_indices: 0,
    }
}

/// Bytes of a regular tile's block of `grid_size` cells (vertices, indices, padding).
pub fn tile_bytes(grid_size: u32) -> u32 {
    counts(grid_size).block_bytes()
}

/// Vertices per tile, skirt included.
pub fn vertex_count(grid_size: u32) -> usize {
    let side = grid_size as usize + 1;
    side * side + 4 * side
}

/// Indices per tile: two triangles per cell and per skirt segment.
pub fn index_count(grid_size: u32) -> usize {
    let g = grid_size as usize;
    6 * g * g + 4 * 6 * g
}

/// Triangles per tile (cells and skirts).
pub fn triangle_count(grid_size: u32) -> usize {
    index_count(grid_size) / 3
}

/// The posts along the four edges in skirt order: south west to east, east
/// south to north, north east to west, west north to south (counter-clockwise
/// around the tile, so every skirt quad faces outward).
pub fn edge_posts(g: u32) -> impl Iterator<Item = (u32, u32)> {
    (0..4).flat_map(move |edge| (0..=g).map(move |k| edge_post(g, edge, k)))
}

fn edge_post(g: u32, edge: u32, k: u32) -> (u32, u32) {
    match edge {
        0 => (k, 0),
        1 => (g, k),
        2 => (g - k, g),
        _ => (0, g - k),
    }
}

fn edge_post_index(g: u32, edge: u32, k: u32) -> u16 {
    let (i, j) = edge_post(g, edge, k);
    (i + j * (g + 1)) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_triangles_face_up_and_cover_each_cell_once() {
        let grid = TileGrid::new(4);
        let pos = |v: u16| {
            let [i, j] = grid.vertices[v as usize].post;
            (i as f64, j as f64)
        };
        let mut area = 0.0;
        for tri in grid.indices[..6 * 16].chunks(3) {
            let (a, b, c) = (pos(tri[0]), pos(tri[1]), pos(tri[2]));
            let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
            assert!(cross > 0.0, "counter-clockwise from above");
            area += cross / 2.0;
        }
        assert_eq!(area, 16.0);
        assert_eq!(tile_bytes(4), (45 * 20 + (96 + 96) * 2) as u32);
        assert!(grid.indices.iter().all(|&i| (i as usize) < grid.vertices.len()));
    }

    #[test]
    fn skirt_vertices_repeat_the_edge_posts() {
        let grid = TileGrid::new(8);
        let skirt = &grid.vertices[81..];
        assert_eq!(skirt.len(), 36);
        assert!(grid.vertices[..81].iter().all(|v| v.skirt == 0));
        // Each skirt vertex names the edge it hangs from.
        for v in skirt {
            let [i, j] = v.post;
            let on = [j == 0, i == 8, j == 8, i == 0];
            assert!((1..=4).contains(&v.skirt) && on[v.skirt as usize - 1], "{v:?}");
        }
    }
}
