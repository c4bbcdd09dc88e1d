//! Page-in cost of a node on the loader thread (issue 21): the built-in
//! terrain's pyramid node alone (heights) against the node with its error
//! map (format 2: keys decoded, stored heights dequantised, and for the
//! maps that store none, levels 1 and 2 over level-0 data, the heights and
//! normals read from the pyramid's nodes under it). Every stored node of
//! each level is read, best of a few interleaved repeats; per frame is the
//! mean node at the clipmap's load budget of 16 nodes a frame. For the
//! maps that store no heights, their fill alone both ways: through the
//! node's reference grid (`reference_grid` then `fill_posts`, the build's
//! path and page-in's before `meshes::pagein`) and straight from the
//! nodes (`fill_from_pyramid`, page-in's now). Prints a table, writes
//! target/bench/pagein.json and pagein.svg. `-- --quick`: fewer repeats.

mod support;

use std::time::Instant;

use ridgeline::meshes::build::fill_posts;
use ridgeline::meshes::pagein::fill_from_pyramid;
use ridgeline::meshes::record::{FROM_PYRAMID, STORED};
use ridgeline::meshes::reference::reference_grid;
use ridgeline::meshes::MeshOptions;
use ridgeline::node::{ErrorMap, NodeData, NodeId, NodeSource};
use ridgeline::pyramid::Silent;
use support::{print_table, BenchArgs, Panel, Series};

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
    /// Mean keys of the maps that store no heights.
    from_pyramid_keys: f64,
    /// Their heights and normals through the reference grid, mean us.
    grid_fill_us: f64,
    /// The same straight from the nodes, mean us.
    direct_fill_us: f64,
}

/// Times filling one map that stores no heights both ways, us.
fn fill_both_us(repeats: usize, source: &dyn NodeSource, id: NodeId, map: &ErrorMap) -> [f64; 2] {
    let layout = *source.layout();
    let mut scratch = map.clone();
    let grid = best_us(repeats, || {
        let reference = reference_grid(source, id, map.post_level).expect("reads the grid");
        fill_posts(&mut scratch, &reference, &layout);
    });
    let direct =
        best_us(repeats, || fill_from_pyramid(source, id, &mut scratch).expect("reads the posts"));
    [grid, direct]
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
        let (mut keys, mut grid_fill, mut direct_fill) = (0, 0.0, 0.0);
        for &id in &ids {
            heights += best_us(repeats, || pyramid.read_node(id, &mut data).expect("reads"));
            with_map += best_us(repeats, || meshed.read_node(id, &mut data).expect("reads"));
            match ridgeline::meshes::record::kind_of(&data.map) {
                FROM_PYRAMID => {
                    from_pyramid += 1;
                    keys += data.map.keys.len();
                    let [grid, direct] = fill_both_us(repeats, pyramid.as_ref(), id, &data.map);
                    (grid_fill, direct_fill) = (grid_fill + grid, direct_fill + direct);
                }
                STORED => stored += 1,
                _ => {}
            }
        }
        let n = ids.len().max(1) as f64;
        let m = from_pyramid.max(1) as f64;
        rows.push(Row {
            level,
            nodes: ids.len(),
            from_pyramid,
            stored,
            heights_us: heights / n,
            with_map_us: with_map / n,
            map_us: (with_map - heights) / n,
            from_pyramid_keys: keys as f64 / m,
            grid_fill_us: grid_fill / m,
            direct_fill_us: direct_fill / m,
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
                format!("{:.0}", r.from_pyramid_keys),
                format!("{:.0}", r.grid_fill_us),
                format!("{:.1}", r.direct_fill_us),
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
        "keys (from pyramid)",
        "grid fill us",
        "direct fill us",
    ];
    print_table("page-in per node, built-in terrain (best of repeats)", &header, &cells);
    let report = serde_json::json!({ "bench": "pagein", "repeats": repeats, "rows": rows });
    let json = support::write_json("pagein", &report);
    let svg = support::write_svg("pagein", &[plot(&rows)]);
    println!("\nwrote {} and {}", json.display(), svg.display());
}

/// Microseconds per node by level: the heights, the node with its map,
/// and the two fills of the maps that store no heights (where there are).
fn plot(rows: &[Row]) -> Panel {
    let line = |label: &str, value: &dyn Fn(&Row) -> Option<f64>| Series {
        label: label.into(),
        points: rows.iter().filter_map(|r| Some((r.level as f64, value(r)?))).collect(),
    };
    let filled = |r: &Row, v: f64| (r.from_pyramid > 0).then_some(v);
    Panel {
        title: "page-in per node, built-in terrain".into(),
        x_label: "level".into(),
        y_label: "us per node".into(),
        log_x: false,
        log_y: true,
        series: vec![
            line("heights", &|r| Some(r.heights_us)),
            line("with map", &|r| Some(r.with_map_us)),
            line("fill through reference grid", &|r| filled(r, r.grid_fill_us)),
            line("fill straight from nodes", &|r| filled(r, r.direct_fill_us)),
        ],
    }
}
