//! Per level of a dataset's error maps (issues 21 and 22): nodes, dense and
//! sparse maps, posts kept, bytes on disk, the floor and the reference
//! deltas; then the whole dataset's bytes per level-0 post of data.
//!
//! `cargo run --release --example mesh_levels [-- DATASET]`

use std::path::Path;
use std::sync::Arc;

use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::node::{NodeData, NodeId, NodeSource};
use ridgeline::pyramid::Silent;

fn main() -> anyhow::Result<()> {
    let dir = std::env::args().nth(1);
    let pyramid = Arc::new(ridgeline::dataset::open(dir.as_deref(), Path::new("cache"), &Silent)?);
    let started = std::time::Instant::now();
    let source =
        MeshedSource::open_or_build(Arc::clone(&pyramid), MeshOptions::default(), &Silent)?;
    let map_bytes = source.file().len();
    println!(
        "{}: maps opened or built in {:.1} s, map file {:.1} MB, pyramid {:.1} MB",
        pyramid.path().display(),
        started.elapsed().as_secs_f64(),
        map_bytes as f64 / 1e6,
        pyramid.file_len() as f64 / 1e6
    );
    let layout = *pyramid.layout();
    println!(
        "{:>5} {:>6} {:>6} {:>6} {:>12} {:>10} {:>10} {:>10}",
        "level", "nodes", "dense", "sparse", "posts kept", "map MB", "floor m", "ref m"
    );
    let mut data = NodeData::default();
    let mut level0_posts = 0u64;
    for level in 0..layout.levels {
        let [nx, ny] = layout.nodes_at(level);
        let (mut nodes, mut dense, mut kept, mut bytes) = (0u64, 0u64, 0u64, 0u64);
        let (mut floor, mut reference) = (0f32, 0f32);
        for y in 0..ny {
            for x in 0..nx {
                let id = NodeId::new(level, x, y);
                if !source.has_node(id) {
                    continue;
                }
                source.read_node(id, &mut data)?;
                nodes += 1;
                let map = &data.map;
                dense += map.is_dense() as u64;
                kept += if map.is_dense() { map.codes.len() } else { map.keys.len() } as u64;
                bytes += source.file().map_bytes(&layout, id);
                floor = floor.max(map.floor_m);
                reference = reference.max(map.reference_delta);
                if level == 0 {
                    level0_posts += (layout.node_size as u64).pow(2);
                }
            }
        }
        let mb = bytes as f64 / 1e6;
        let sparse = nodes - dense;
        println!(
            "{level:>5} {nodes:>6} {dense:>6} {sparse:>6} {kept:>12} {mb:>10.2} {floor:>10.2} {reference:>10.2}"
        );
    }
    let total = map_bytes + pyramid.file_len();
    println!(
        "level-0 cells stored: {level0_posts}; pyramid + maps: {:.1} MB, {:.2} bytes per level-0 cell",
        total as f64 / 1e6,
        total as f64 / level0_posts.max(1) as f64
    );
    Ok(())
}
