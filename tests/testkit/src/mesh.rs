//! Node meshes by brute force: where a vertex lies and the surface's height
//! anywhere, by testing every triangle (`tests/meshes*.rs`).

use ridgeline::node::{NodeData, NodeId, NodeLayout, NodeMesh};
use ridgeline::tiles::extract::{forced_step, PlacedMap};

/// Level-0 post of a mesh vertex's post `p` (half steps of the map's lattice).
pub fn level0(layout: &NodeLayout, id: NodeId, mesh: &NodeMesh, p: [u16; 2]) -> [f64; 2] {
    let origin = [id.x, id.y].map(|v| (v as u64 * layout.node_size as u64) << id.level);
    [0, 1].map(|k| origin[k] as f64 + p[k] as f64 * (1u64 << mesh.post_level) as f64 / 2.0)
}

/// Twice the signed area of triangle `a b c` (positive counter-clockwise).
pub fn area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The mesh's height (or target) at level-0 place `q` by testing every
/// triangle; `None` outside it.
pub fn brute(
    layout: &NodeLayout,
    id: NodeId,
    mesh: &NodeMesh,
    q: [f64; 2],
    target: bool,
) -> Option<f64> {
    for tri in mesh.indices.chunks_exact(3) {
        let v = [0, 1, 2].map(|k| mesh.vertices[tri[k] as usize]);
        let p = v.map(|v| level0(layout, id, mesh, v.post));
        let w = [area(p[1], p[2], q), area(p[2], p[0], q), area(p[0], p[1], q)];
        if w.iter().all(|&w| w >= -1e-9) {
            let sum = w[0] + w[1] + w[2];
            let h = |k: usize| if target { v[k].target } else { v[k].height } as f64;
            return Some((0..3).map(|k| w[k] * h(k)).sum::<f64>() / sum);
        }
    }
    None
}

/// Node `id`'s map placed for meshes of `error_m`, split at least to the
/// squares of tiles of `tile_cells` cells.
pub fn place<'a>(
    layout: &'a NodeLayout,
    id: NodeId,
    data: &'a NodeData,
    tile_cells: u32,
    error_m: f64,
) -> PlacedMap<'a> {
    let map = &data.map;
    let tile = tile_cells << (id.level - map.post_level);
    let forced = forced_step(layout, map.post_level, map.cells, tile, error_m);
    PlacedMap::new(layout, id, data, error_m, forced)
}
