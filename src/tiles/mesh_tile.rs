//! Tiles cut from a node's adaptive mesh (Ulrich's chunks, issue 11): the
//! node mesh's triangles inside the tile's square, renumbered for the tile,
//! with a skirt along each edge (Ulrich section 11).
//!
//! A node's mesh is split at least into squares of `MeshOptions::tile_cells`
//! node posts, so a tile of its own node (or of an ancestor at most
//! `log2(grid_size / tile_cells)` levels up) takes whole triangles: the
//! tiles of one node together draw exactly its mesh, and two tiles of the
//! same node share every vertex of their common edge. Where an ancestor's
//! triangles are larger than the tile, [`MeshCutter::cut`] says so and the
//! tile is drawn from the ancestor's posts as a regular grid instead.

use super::block::TileVertex;
use super::curtain::{self, CurtainFinder};
use super::vertex::{PostReader, TileCoverage, NO_DATA};
use crate::lod::TileKey;
use crate::node::{NodeId, NodeLayout, NodeMesh};

/// Largest vertex count of a node mesh (16-bit indices).
const MAX_MESH_VERTICES: usize = 1 << 16;

/// Where a tile lies in a node mesh's posts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileSquare {
    /// The tile's south-west corner, mesh posts from the node's.
    pub origin: [u32; 2],
    /// The tile's side, mesh posts.
    pub width: u32,
    /// Level-0 posts between mesh posts (`2^NodeMesh::post_level`).
    pub step: u32,
}

impl TileSquare {
    /// The square of tile `key` (of `grid_size` cells) in the mesh of
    /// `node`, if the tile lies inside the node on whole mesh posts.
    pub fn of(
        layout: &NodeLayout,
        key: TileKey,
        grid_size: u32,
        node: NodeId,
        post_level: u8,
    ) -> Option<TileSquare> {
        let step = 1u64 << post_level;
        let tile_span = (grid_size as u64) << key.level;
        let node_span = (layout.node_size as u64) << node.level;
        let tile0 = [key.x as u64 * tile_span, key.y as u64 * tile_span];
        let node0 = [node.x as u64 * node_span, node.y as u64 * node_span];
        let inside =
            (0..2).all(|k| tile0[k] >= node0[k] && tile0[k] + tile_span <= node0[k] + node_span);
        // Meshes are extracted split to the tile's square, so any tile of
        // whole map posts takes whole triangles.
        if !inside || tile_span % step != 0 {
            return None;
        }
        let origin = [0, 1].map(|k| ((tile0[k] - node0[k]) / step) as u32);
        Some(TileSquare { origin, width: (tile_span / step) as u32, step: step as u32 })
    }
}

/// What one cut holds: counts, skirts included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CutSize {
    /// Vertices: the mesh's inside the square, then the skirts'.
    pub vertices: usize,
    /// Indices: the triangles', then the skirts'.
    pub indices: usize,
    /// Of those, the skirts'.
    pub skirt_indices: usize,
}

/// Scratch for cutting tiles out of node meshes, sized once (no allocation
/// per frame once the largest mesh has been cut).
pub struct MeshCutter {
    /// Per node-mesh vertex: the cut that last numbered it ...
    stamp: Vec<u32>,
    /// ... and its number in that cut.
    number: Vec<u16>,
    cut: u32,
    /// Node-mesh vertices in tile order.
    order: Vec<u16>,
    /// The tile's triangles, tile numbering.
    indices: Vec<u16>,
    /// Per edge (south, east, north, west): position along it and tile vertex.
    edges: [Vec<(u32, u16)>; 4],
    /// The curtains where the cut's drawn triangles meet dropped ones.
    curtains: CurtainFinder,
}

impl Default for MeshCutter {
    fn default() -> Self {
        MeshCutter {
            stamp: vec![0; MAX_MESH_VERTICES],
            number: vec![0; MAX_MESH_VERTICES],
            cut: 0,
            order: Vec::new(),
            indices: Vec::new(),
            edges: Default::default(),
            curtains: CurtainFinder::default(),
        }
    }
}

/// What a tile's vertices are made with.
pub struct CutInputs<'a> {
    /// The node mesh.
    pub mesh: &'a NodeMesh,
    /// The tile's square in it.
    pub square: TileSquare,
    /// The node's posts, for the data across each edge.
    pub reader: &'a PostReader<'a>,
    /// Level-0 posts between the tile's own posts (`2^level`).
    pub tile_step: u32,
    /// The node's south-west post, level 0.
    pub node_origin: [u64; 2],
    /// The data's last post, level 0.
    pub last_post: [u64; 2],
    /// The mesh is of the tile's own level: its morph targets and parent
    /// normals apply (an ancestor's mesh is drawn unmorphed).
    pub own_level: bool,
}

impl MeshCutter {
    /// Cuts the triangles whose centroid lies inside `square` and returns
    /// the tile's size, or `None` when one of them reaches outside it (the
    /// mesh's triangles are larger than the tile).
    pub fn cut(&mut self, mesh: &NodeMesh, square: TileSquare) -> Option<CutSize> {
        self.cut = self.cut.wrapping_add(1);
        if self.cut == 0 {
            self.stamp.fill(0);
            self.cut = 1;
        }
        self.order.clear();
        self.indices.clear();
        // Mesh posts count half steps: the square's, doubled.
        let [x0, y0] = square.origin.map(|o| 2 * o as i64);
        let w = 2 * square.width as i64;
        let inside = |p: [u16; 2]| {
            let (x, y) = (p[0] as i64 - x0, p[1] as i64 - y0);
            (0..=w).contains(&x) && (0..=w).contains(&y)
        };
        for tri in mesh.indices.chunks_exact(3) {
            let p = [0, 1, 2].map(|k| mesh.vertices[tri[k] as usize].post);
            // Three times the centroid, against three times the square.
            let c = [0, 1].map(|k| p.iter().map(|q| q[k] as i64).sum::<i64>());
            let strictly = |c: i64, o: i64| c > 3 * o && c < 3 * (o + w);
            if !(strictly(c[0], x0) && strictly(c[1], y0)) {
                continue;
            }
            if !p.iter().all(|&q| inside(q)) {
                return None;
            }
            for &v in tri {
                let number = self.number_of(v);
                self.indices.push(number);
            }
        }
        if self.indices.is_empty() {
            // No triangle of the mesh is centred in the square: an
            // ancestor's triangles are all larger than the tile.
            return None;
        }
        self.gather_edges(mesh, square);
        self.find_curtains(mesh);
        let skirt_vertices: usize = self.edges.iter().map(Vec::len).sum();
        let skirt_indices: usize = self.edges.iter().map(|e| 6 * e.len().saturating_sub(1)).sum();
        let curtain_indices = self.curtains.index_count();
        Some(CutSize {
            vertices: self.order.len() + skirt_vertices + self.curtains.feet(),
            indices: self.indices.len() + skirt_indices + curtain_indices,
            skirt_indices: skirt_indices + curtain_indices,
        })
    }

    /// Curtains between the cut's drawn triangles and those a post without
    /// data drops (none where every vertex has data: nothing to sort).
    fn find_curtains(&mut self, mesh: &NodeMesh) {
        let void = |v: u16| mesh.vertices[v as usize].height.is_nan();
        if !self.order.iter().any(|&v| void(v)) {
            self.curtains.clear();
            return;
        }
        let order = &self.order;
        self.curtains.find(&self.indices, |n| void(order[n as usize]));
    }

    fn number_of(&mut self, v: u16) -> u16 {
        let k = v as usize;
        if self.stamp[k] != self.cut {
            self.stamp[k] = self.cut;
            self.number[k] = self.order.len() as u16;
            self.order.push(v);
        }
        self.number[k]
    }

    /// The cut's vertices on each edge, in skirt order (counter-clockwise
    /// around the tile, as `grid::edge_posts`).
    fn gather_edges(&mut self, mesh: &NodeMesh, square: TileSquare) {
        let w = 2 * square.width;
        for edge in &mut self.edges {
            edge.clear();
        }
        for (n, &v) in self.order.iter().enumerate() {
            let [x, y] =
                [0, 1].map(|k| mesh.vertices[v as usize].post[k] as u32 - 2 * square.origin[k]);
            let n = n as u16;
            if y == 0 {
                self.edges[0].push((x, n));
            }
            if x == w {
                self.edges[1].push((y, n));
            }
            if y == w {
                self.edges[2].push((w - x, n));
            }
            if x == 0 {
                self.edges[3].push((w - y, n));
            }
        }
        for edge in &mut self.edges {
            edge.sort_unstable();
        }
    }

    /// Writes the last cut's vertices and indices (sized as `cut` said) and
    /// says how much of the tile has data.
    pub fn fill(
        &self,
        inputs: &CutInputs<'_>,
        vertices: &mut [TileVertex],
        indices: &mut [u16],
    ) -> TileCoverage {
        let (mut with_data, mut without, mut beyond) = (0usize, 0usize, 0usize);
        let mut nearest = f32::NAN;
        let square = inputs.square;
        for (out, &v) in vertices.iter_mut().zip(&self.order) {
            let vertex = inputs.mesh.vertices[v as usize];
            // Half steps, as the mesh's: the tile's vertex step is half its mesh's.
            let post = [0, 1].map(|k| (vertex.post[k] as u32 - 2 * square.origin[k]) as u16);
            let level0 = [0, 1]
                .map(|k| inputs.node_origin[k] + vertex.post[k] as u64 * square.step as u64 / 2);
            if vertex.height.is_nan() {
                without += 1;
                *out = TileVertex {
                    post,
                    skirt: 0,
                    _pad: 0,
                    height: NO_DATA,
                    target: f32::NAN,
                    normal: [0; 4],
                };
                continue;
            }
            if level0[0] > inputs.last_post[0] || level0[1] > inputs.last_post[1] {
                beyond += 1;
            } else {
                with_data += 1;
            }
            nearest = vertex.height;
            let (target, normal) = if inputs.own_level && vertex.target.is_finite() {
                (vertex.target, vertex.normal)
            } else {
                let [x, y, _, _] = vertex.normal;
                (vertex.height, [x, y, x, y])
            };
            let band = match inputs.own_level && vertex.target.is_finite() {
                true => inputs.mesh.bands.get(v as usize).copied().unwrap_or(0),
                false => 0,
            };
            let skirt = TileVertex::surface_code(band);
            *out = TileVertex { post, skirt, _pad: 0, height: vertex.height, target, normal };
        }
        let count = self.order.len();
        for out in &mut vertices[..count] {
            if out.target.is_nan() {
                // Dropped with its triangles; placed near the tile for the rasteriser.
                out.target = nearest;
            }
        }
        indices[..self.indices.len()].copy_from_slice(&self.indices);
        let (dropped, skirt_vertices, skirt_indices) =
            self.fill_skirts(inputs, vertices, &mut indices[self.indices.len()..]);
        let (first_foot, first_index) =
            (count + skirt_vertices, self.indices.len() + skirt_indices);
        let (tops, feet) = vertices.split_at_mut(first_foot);
        self.curtains.write(|v| tops[v as usize], first_foot, feet, &mut indices[first_index..]);
        match (with_data, without + beyond + dropped) {
            (0, _) => TileCoverage::Empty,
            (_, 0) => TileCoverage::Full,
            _ => TileCoverage::Partial,
        }
    }

    /// Skirt vertices after the cut's, a quad between each two consecutive
    /// edge vertices, wound to face outward. Where the data do not continue
    /// across the edge the vertex is a curtain's foot instead
    /// ([`curtain::foot`]), as the grid tiles' are. Returns how many were,
    /// and the vertices and indices written.
    fn fill_skirts(
        &self,
        inputs: &CutInputs<'_>,
        vertices: &mut [TileVertex],
        indices: &mut [u16],
    ) -> (usize, usize, usize) {
        let mut next = self.order.len();
        let mut written = 0;
        let mut dropped = 0;
        for (e, edge) in self.edges.iter().enumerate() {
            let first = next;
            for &(along, top) in edge {
                let above = vertices[top as usize];
                let faces_data = self.data_across(inputs, e, along);
                vertices[next] = if faces_data || above.height == NO_DATA {
                    above.with_edge(e as u16 + 1)
                } else {
                    dropped += 1;
                    curtain::foot(above)
                };
                next += 1;
            }
            for k in 1..edge.len() {
                let (top0, top1) = (edge[k - 1].1, edge[k].1);
                let (low0, low1) = ((first + k - 1) as u16, (first + k) as u16);
                indices[written..written + 6]
                    .copy_from_slice(&[top0, low0, low1, top0, low1, top1]);
                written += 6;
            }
        }
        (dropped, next - self.order.len(), written)
    }

    /// Whether the tile's posts across edge `e` (south, east, north, west),
    /// next to mesh position `along` on it, all have data.
    fn data_across(&self, inputs: &CutInputs<'_>, e: usize, along: u32) -> bool {
        let square = inputs.square;
        // Half mesh posts to the tile's own posts (a tile post is `ratio` of them).
        let ratio = 2 * (inputs.tile_step / square.step).max(1) as i64;
        let g = (2 * square.width as i64) / ratio;
        let a = along as i64;
        let (lo, hi) = (a / ratio, (a + ratio - 1) / ratio);
        let post = |k: i64| -> (i64, i64) {
            match e {
                0 => (k, -1),
                1 => (g + 1, k),
                2 => (g - k, g + 1),
                _ => (-1, g - k),
            }
        };
        [lo, hi].iter().all(|&k| {
            let (i, j) = post(k);
            !inputs.reader.post(i, j).is_nan()
        })
    }
}
