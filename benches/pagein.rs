//! Page-in cost of a node on the loader thread (issue 21): the built-in
//! terrain's pyramid node alone (heights) against the node with its error
//! map (format 2: keys decoded, stored heights dequantised, and for the
//! maps that store none, levels 1 and 2 over level-0 data, the heights and
//! normals read from the pyramid's nodes under it). Every stored node of
//! each level is read, best of a few interleaved repeats; per frame is the
//! mean node at the clipmap's load budget of 16 nodes a frame. Prints a
//! table, writes target/bench/pagein.json. `-- --quick`: fewer repeats.

mod support;

use std::time::Instant;

use ridgeline::meshes::record::{FROM_PYRAMID, STORED};
use ridgeline::meshes::MeshOptions;
use ridgeline::node::{NodeData, NodeId, NodeSource};
use ridgeline::pyramid::Silent;
use support::{print_table, BenchArgs};

/// Loads a frame may apply (the clipmap bench's budget).
const LOADS_PER_FRAME: f64 = 16.0;

#[derive(serde::Serialize)]
struct Row {
    level: u8,
    nodes: usize,
    /// Maps that store no heights (read from the pyramid at page-in).
    from_pyramid: usize,
    /// Maps that store quantised heights.
    stored: usize,
    heights_us: f64,
    with_map_us: f64,
    map_us: f64,
}

fn best_us(repeats: usize, mut f: impl FnMut()) -> f64 {
    (0..repeats)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e6
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let repeats = if BenchArgs::parse().quick { 2 } else { 5 };
    let cache = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cache");
    let meshed = ridgeline::dataset::open_meshed(None, &cache, MeshOptions::default(), &Silent)
        .expect("open the built-in terrain");
    let pyramid = meshed.pyramid().clone();
    let layout = *pyramid.layout();
    let mut rows = Vec::new();
    let mut data = NodeData::with_capacity(&layout);
    for level in 0..layout.levels {
        let [nx, ny] = layout.nodes_at(level);
        let ids: Vec<NodeId> = (0..ny)
            .flat_map(|y| (0..nx).map(move |x| NodeId::new(level, x, y)))
            .filter(|&id| pyramid.has_node(id))
            .collect();
        let (mut heights, mut with_map) = (0.0, 0.0);
        let (mut from_pyramid, mut stored) = (0, 0);
        for &id in &ids {
            heights += best_us(repeats, || pyramid.read_node(id, &mut data).expect("reads"));
            with_map += best_us(repeats, || meshed.read_node(id, &mut data).expect("reads"));
            match ridgeline::meshes::record::kind_of(&data.map) {
                FROM_PYRAMID => from_pyramid += 1,
                STORED => stored += 1,
                _ => {}
            }
        }
        let n = ids.len().max(1) as f64;
        rows.push(Row {
            level,
            nodes: ids.len(),
            from_pyramid,
            stored,
            heights_us: heights / n,
            with_map_us: with_map / n,
            map_us: (with_map - heights) / n,
        });
    }
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.level.to_string(),
                r.nodes.to_string(),
                format!("{}/{}", r.from_pyramid, r.stored),
                format!("{:.0}", r.heights_us),
                format!("{:.0}", r.with_map_us),
                format!("{:.0}", r.map_us),
                format!("{:.2}", r.with_map_us * LOADS_PER_FRAME / 1000.0),
            ]
        })
        .collect();
    let header = [
        "level",
        "nodes",
        "from pyramid/stored",
        "heights us",
        "with map us",
        "map us",
        "ms per frame at 16 loads",
    ];
    print_table("page-in per node, built-in terrain (best of repeats)", &header, &cells);
    let report = serde_json::json!({ "bench": "pagein", "repeats": repeats, "rows": rows });
    let json = support::write_json("pagein", &report);
    println!("\nwrote {}", json.display());
}
