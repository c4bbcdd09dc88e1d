//! Per level of a pyramid's node meshes (issue 11): nodes, vertices and
//! triangles, the mesh delta against the pyramid's regular-grid delta, and
//! the bytes a node's mesh and a 32-cell tile take, stored and uploaded.
//!
//! `cargo run --release --example mesh_levels [-- CACHE_DIR [MESH_ERROR_M]]`
//! (default: the built-in terrain under `cache/`, the default mesh error).

use std::path::Path;
use std::sync::Arc;

use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::node::{NodeData, NodeId, NodeSource};
use ridgeline::pyramid::Silent;
use ridgeline::tiles::block::VERTEX_BYTES;

fn main() -> anyhow::Result<()> {
    let dir = std::env::args().nth(1);
    let error_m = std::env::args().nth(2).map(|e| e.parse()).transpose()?;
    let options = MeshOptions {
        error_m: error_m.unwrap_or(MeshOptions::default().error_m),
        ..MeshOptions::default()
    };
    let pyramid = Arc::new(ridgeline::dataset::open(dir.as_deref(), Path::new("cache"), &Silent)?);
    let started = std::time::Instant::now();
    let source = MeshedSource::open_or_build(Arc::clone(&pyramid), options, &Silent)?;
    println!(
        "{}: mesh error {} m at level 1 (opened or built in {:.1} s), mesh file {:.1} MB, pyramid {:.1} MB",
        pyramid.path().display(),
        options.error_m,
        started.elapsed().as_secs_f64(),
        std::fs::metadata(source.file().path())?.len() as f64 / 1e6,
        pyramid.file_len() as f64 / 1e6
    );
    let layout = *pyramid.layout();
    let grid_triangles = 2 * layout.node_size as u64 * layout.node_size as u64;
    println!(
        "{:>5} {:>6} {:>10} {:>10} {:>12} {:>12} {:>14} {:>16}",
        "level",
        "nodes",
        "vertices",
        "triangles",
        "mesh delta",
        "grid delta",
        "tris/grid tris",
        "upload B/tri"
    );
    let mut data = NodeData::default();
    for level in 0..layout.levels {
        let [nx, ny] = layout.nodes_at(level);
        let (mut nodes, mut vertices, mut triangles, mut delta) = (0u64, 0u64, 0u64, 0f32);
        for y in 0..ny {
            for x in 0..nx {
                let id = NodeId::new(level, x, y);
                if !source.has_node(id) {
                    continue;
                }
                source.read_node(id, &mut data)?;
                nodes += 1;
                vertices += data.mesh.vertices.len() as u64;
                triangles += data.mesh.indices.len() as u64 / 3;
                delta = delta.max(data.delta);
            }
        }
        let grid_delta = pyramid.info().levels[level as usize].delta_max;
        // Uploaded per triangle: 20-byte tile vertices and 3 indices of 2 bytes.
        let per_triangle =
            (vertices * VERTEX_BYTES as u64 + triangles * 6) as f64 / triangles.max(1) as f64;
        println!(
            "{level:>5} {nodes:>6} {vertices:>10} {triangles:>10} {delta:>12.2} {grid_delta:>12.2} {:>14.3} {per_triangle:>16.1}",
            triangles as f64 / (nodes * grid_triangles).max(1) as f64
        );
    }
    Ok(())
}
