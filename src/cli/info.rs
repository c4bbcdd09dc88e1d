//! `ridgeline info cache/NAME [--json]`: opens and verifies a pyramid cache and
//! describes it, for people or (with `--json`) for scripts.

use std::path::{Path, PathBuf};

use anyhow::Result;
use ridgeline::geo::Crs;
use ridgeline::pyramid::{format::VERSION, LevelSummary, Pyramid};

#[derive(clap::Args)]
pub struct InfoArgs {
    /// Cache directory (or its pyramid.rlp file).
    pub cache: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// What `--json` prints.
#[derive(serde::Serialize)]
struct Summary<'a> {
    path: &'a Path,
    format_version: u32,
    file_bytes: u64,
    levels: u8,
    node_size: u32,
    border: u32,
    node_count: u64,
    /// Nodes stored; the others are absent (no data of their resolution).
    nodes_present: u64,
    /// Layers (files of one spacing) the pyramid was built from.
    layers: u32,
    /// Level-0 posts, east and north.
    posts: [u32; 2],
    spacing_m: [f64; 2],
    /// Distance from the first to the last post, east and north.
    extent: Extent,
    georef: Georef,
    delta_per_level: Vec<f32>,
    height_min: f32,
    height_max: f32,
    /// Void posts interpolated from their neighbours (small voids).
    voids_filled: u64,
    /// The same count under the name.
    posts_interpolated: u64,
    /// Void posts of a layer filled from a coarser layer (large voids).
    posts_from_layer: u64,
    /// Void posts no layer covers: no data, not drawn.
    posts_no_data: u64,
    level_details: &'a [LevelSummary],
}

#[derive(serde::Serialize)]
struct Extent {
    east_m: f64,
    north_m: f64,
}

#[derive(serde::Serialize)]
struct Georef {
    crs: Crs,
    origin: [f64; 2],
    spacing: [f64; 2],
    /// Degrees, where the grid is geographic; null otherwise.
    west: Option<f64>,
    south: Option<f64>,
    east: Option<f64>,
    north: Option<f64>,
}

pub fn run(args: &InfoArgs) -> Result<()> {
    let pyramid = Pyramid::open(&args.cache)?;
    pyramid.verify()?; // open checks the header only; info vouches for every node
    let summary = summarise(&pyramid);
    let text =
        if args.json { serde_json::to_string_pretty(&summary)? + "\n" } else { table(&summary) };
    super::print(&text)
}

fn summarise(pyramid: &Pyramid) -> Summary<'_> {
    let info = pyramid.info();
    let layout = &info.layout;
    let bounds = info.georef.bounds_deg(layout.posts);
    let extent = |axis: usize| (layout.posts[axis] - 1) as f64 * layout.spacing_m[axis];
    Summary {
        path: pyramid.path(),
        format_version: VERSION,
        file_bytes: pyramid.file_len(),
        levels: layout.levels,
        node_size: layout.node_size,
        border: layout.border,
        node_count: layout.node_count(),
        nodes_present: info.levels.iter().map(|l| l.present).sum(),
        layers: info.layers,
        posts: layout.posts,
        spacing_m: layout.spacing_m,
        extent: Extent { east_m: extent(0), north_m: extent(1) },
        georef: Georef {
            crs: info.georef.crs,
            origin: info.georef.origin,
            spacing: info.georef.spacing,
            west: bounds.map(|b| b.west),
            south: bounds.map(|b| b.south),
            east: bounds.map(|b| b.east),
            north: bounds.map(|b| b.north),
        },
        delta_per_level: info.levels.iter().map(|l| l.delta_max).collect(),
        height_min: info.stats.height_min,
        height_max: info.stats.height_max,
        voids_filled: info.stats.voids_filled,
        posts_interpolated: info.stats.voids_filled,
        posts_from_layer: info.stats.posts_from_layer,
        posts_no_data: info.stats.posts_no_data,
        level_details: &info.levels,
    }
}

/// `writeln!` into a `String`, which cannot fail.
macro_rules! line {
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($out, $($arg)*);
    }};
}

fn table(s: &Summary) -> String {
    let mut out = String::new();
    line!(
        out,
        "{} (format {}, {:.1} MB, all checksums verified)",
        s.path.display(),
        s.format_version,
        s.file_bytes as f64 / 1e6
    );
    line!(
        out,
        "posts     {} x {}, {:.2} x {:.2} m apart, extent {:.2} x {:.2} km",
        s.posts[0],
        s.posts[1],
        s.spacing_m[0],
        s.spacing_m[1],
        s.extent.east_m / 1e3,
        s.extent.north_m / 1e3
    );
    line!(out, "georef    {}", describe_georef(&s.georef));
    line!(
        out,
        "nodes     {} cells + {} border posts, {} levels, {} of {} nodes stored, {} layers",
        s.node_size,
        s.border,
        s.levels,
        s.nodes_present,
        s.node_count,
        s.layers
    );
    line!(
        out,
        "heights   {:.1} .. {:.1} m; void posts: {} interpolated, {} from a coarser layer, {} no data",
        s.height_min,
        s.height_max,
        s.posts_interpolated,
        s.posts_from_layer,
        s.posts_no_data
    );
    line!(out, "level  nodes        stored  delta max (m)  heights (m)");
    for (level, summary) in s.level_details.iter().enumerate() {
        let nodes = format!("{} x {}", summary.nodes[0], summary.nodes[1]);
        line!(
            out,
            "{level:>5}  {nodes:<11}  {:>6}  {:>13.3}  {:.1} .. {:.1}",
            summary.present,
            summary.delta_max,
            summary.height_min,
            summary.height_max
        );
    }
    out
}

fn describe_georef(g: &Georef) -> String {
    match (g.crs, g.west, g.south, g.east, g.north) {
        (Crs::Geographic, Some(west), Some(south), Some(east), Some(north)) => {
            format!("WGS 84 longitude {west:.5}..{east:.5}, latitude {south:.5}..{north:.5}")
        }
        (Crs::Projected { epsg: Some(code) }, ..) => format!("EPSG:{code}, origin {:?}", g.origin),
        (Crs::Projected { epsg: None }, ..) => {
            format!("projected (unknown EPSG), origin {:?}", g.origin)
        }
        _ => "local frame, no georeference".to_string(),
    }
}
