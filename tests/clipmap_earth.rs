//! The clipmap's wanted set on the ellipsoid (`Clipmap::set_earth`): over a
//! global geographic grid, the nodes wanted are those whose footprint lies
//! within the level's load radius of the viewer *on the earth* (checked
//! against a brute-force distance to points along every footprint's
//! outline), at the equator, at 60 N (where the chart overstates east-west
//! distances twice), near the pole and across the grid's seam; the chart's
//! wanted set, for comparison, misses the fine nodes east and west at 60 N.
//! A Web Mercator grid at 60 N is measured on the earth too.
//! Lookups under a viewer just west of the seam answer from the finest
//! data.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DVec2, DVec3};
use ridgeline::clipmap::{Clipmap, ClipmapConfig, LoaderMode, ViewConfig, ViewId};
use ridgeline::earth::{ellipsoid, GridPlacement};
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// A global grid of 0.02-degree posts (0 to 360 degrees with its closing
/// column), heights a gentle function of the place.
struct Globe {
    layout: NodeLayout,
    placement: GridPlacement,
}

const VIEW: ViewConfig = ViewConfig { node_count: 16, view_distance: 2.0, load_distance: 2.5 };

impl Globe {
    fn new() -> Globe {
        let posts = [18_001, 9_001];
        let georef = GeoRef { crs: Crs::Geographic, origin: [0.0, -90.0], spacing: [0.02; 2] };
        let spacing_m = georef.spacing_m(posts);
        let layout = NodeLayout {
            levels: NodeLayout::levels_for(posts, 64),
            node_size: 64,
            border: 1,
            posts,
            spacing_m,
        };
        Globe { layout, placement: GridPlacement::new(&georef, posts, spacing_m) }
    }
}

impl Globe {
    /// A Web Mercator (EPSG:3857) grid of 500 m posts, 1024 km of the
    /// plane a side centred on 60 N 10 E, where the plane is twice the earth.
    fn mercator() -> Globe {
        let posts = [2049, 2049];
        let (x, y) = (1_113_194.9, 8_399_737.9);
        let georef = GeoRef {
            crs: Crs::Projected { epsg: Some(3857) },
            origin: [x - 512_000.0, y - 512_000.0],
            spacing: [500.0; 2],
        };
        let spacing_m = georef.spacing_m(posts);
        let layout = NodeLayout {
            levels: NodeLayout::levels_for(posts, 64),
            node_size: 64,
            border: 1,
            posts,
            spacing_m,
        };
        let placement = GridPlacement::new(&georef, posts, spacing_m);
        assert!(placement.projected_lattice().is_some(), "placed by its projection");
        Globe { layout, placement }
    }
}

impl NodeSource for Globe {
    fn layout(&self) -> &NodeLayout {
        &self.layout
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        let side = self.layout.stored_side() as i64;
        let (span, stride) = (self.layout.span(id.level) as i64, 1i64 << id.level);
        let last = self.layout.posts.map(|p| p as i64 - 1);
        out.heights.clear();
        for b in 0..side {
            for a in 0..side {
                let i = (id.x as i64 * span + (a - 1) * stride).clamp(0, last[0]);
                let j = (id.y as i64 * span + (b - 1) * stride).clamp(0, last[1]);
                let p = self.placement.ecef(i as f64, j as f64, 0.0);
                out.heights.push((200.0 + 100.0 * (p.x / 50_000.0).sin()) as f32);
            }
        }
        out.min = out.heights.iter().copied().fold(f32::INFINITY, f32::min);
        out.max = out.heights.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        Ok(())
    }
}

/// A clipmap over `globe` with one view at `(lat, lon)` degrees, 3000 m,
/// settled; on the ellipsoid or in the chart.
fn settled(globe: &Arc<Globe>, lat: f64, lon: f64, earth: bool) -> (Clipmap, ViewId, DVec3) {
    let config = ClipmapConfig {
        atlas_slots: 20_000,
        atlas_bytes: None,
        budget: 20_000,
        loader: LoaderMode::Inline,
    };
    let mut clipmap = Clipmap::new(globe.clone(), config).unwrap();
    clipmap.set_earth(earth.then_some(globe.placement));
    let [x, y] = globe.placement.chart_of_geodetic(lat.to_radians(), lon.to_radians());
    // A path runs on past the seam in the chart: a place just west of 0
    // degrees is at x below 0.
    let x = if lon < 0.0 { x - 360.0 / 0.02 * globe.layout.spacing_m[0] } else { x };
    let position = DVec3::new(x, y, 3000.0);
    let view = clipmap.add_view(VIEW, position).unwrap();
    clipmap.set_view_position(view, position).unwrap();
    for _ in 0..4 {
        clipmap.update().unwrap();
    }
    (clipmap, view, position)
}

/// The least distance from the eye at `(lat, lon)`, 3000 m, to level-0 node
/// `(x, y)`'s footprint at 200 m (the ground under the viewer is within
/// 100 m of it), sampled along its outline and its viewer's meridian and
/// parallel.
fn brute_distance(globe: &Globe, eye: DVec3, lat: f64, lon: f64, x: u32, y: u32) -> f64 {
    let span = globe.layout.span(0) as f64;
    let last = globe.layout.posts.map(|p| (p - 1) as f64);
    let (u0, u1) = (x as f64 * span, ((x + 1) as f64 * span).min(last[0]));
    let (v0, v1) = (y as f64 * span, ((y + 1) as f64 * span).min(last[1]));
    let [vu, vv] = globe.placement.post_of_geodetic(lat.to_radians(), lon.to_radians());
    let mut best = f64::INFINITY;
    let mut at = |u: f64, v: f64| {
        best = best.min(eye.distance(globe.placement.ecef(u, v, 200.0)));
    };
    for k in 0..=256 {
        let t = k as f64 / 256.0;
        let (u, v) = (u0 + t * (u1 - u0), v0 + t * (v1 - v0));
        for (a, b) in [(u, v0), (u, v1), (u0, v), (u1, v)] {
            at(a, b);
        }
    }
    if (u0..=u1).contains(&globe.placement.wrap_u(vu)) {
        at(vu, vv.clamp(v0, v1));
    }
    best
}

/// Whether any point of level-0 node `(x, y)` may lie within `radius` of
/// `eye`: its centre's distance less the farthest of its corners and edge
/// midpoints from the centre, with a 10 % margin.
fn could_reach(globe: &Globe, eye: DVec3, x: u32, y: u32, radius: f64) -> bool {
    let span = globe.layout.span(0) as f64;
    let last = globe.layout.posts.map(|p| (p - 1) as f64);
    let (u0, u1) = (x as f64 * span, ((x + 1) as f64 * span).min(last[0]));
    let (v0, v1) = (y as f64 * span, ((y + 1) as f64 * span).min(last[1]));
    let centre = globe.placement.ecef(0.5 * (u0 + u1), 0.5 * (v0 + v1), 200.0);
    let mut reach: f64 = 0.0;
    for (u, v) in
        [(u0, v0), (u1, v0), (u0, v1), (u1, v1), (u0, 0.5 * (v0 + v1)), (u1, 0.5 * (v0 + v1))]
    {
        reach = reach.max(centre.distance(globe.placement.ecef(u, v, 200.0)));
    }
    eye.distance(centre) - 1.1 * reach < 1.01 * radius
}

/// The level-0 nodes the clipmap holds after settling (wanted nodes are
/// loaded; the atlas is big enough for all of them).
fn level0(clipmap: &Clipmap, globe: &Globe) -> Vec<[u32; 2]> {
    let [nx, ny] = globe.layout.nodes_at(0);
    let mut out = Vec::new();
    for y in 0..ny {
        for x in 0..nx {
            if clipmap.is_wanted(NodeId::new(0, x, y)) {
                out.push([x, y]);
            }
        }
    }
    out
}

/// Every level-0 node within `radius` of the eye 3000 m above `(lat, lon)`
/// on the earth is in `wanted`, and no node beyond it: 0.3 % either way,
/// since the nearest point is found on a sphere.
fn assert_wanted_within_reach(
    globe: &Globe,
    wanted: &[[u32; 2]],
    (lat, lon): (f64, f64),
    radius: f64,
) {
    let eye = ellipsoid::to_ecef(lat.to_radians(), lon.to_radians(), 3000.0);
    let [nx, ny] = globe.layout.nodes_at(0);
    for y in 0..ny {
        for x in 0..nx {
            let is = wanted.contains(&[x, y]);
            if !is && !could_reach(globe, eye, x, y, radius) {
                continue;
            }
            let d = brute_distance(globe, eye, lat, lon, x, y);
            assert!(is || d > 0.997 * radius, "{lat},{lon}: node {x},{y} at {d:.0} m not wanted");
            assert!(!is || d < 1.003 * radius, "{lat},{lon}: node {x},{y} at {d:.0} m wanted");
        }
    }
}

#[test]
fn wanted_nodes_are_those_within_reach_on_the_earth() {
    let globe = Arc::new(Globe::new());
    let radius =
        VIEW.load_distance * globe.layout.node_size_m(0)[0].min(globe.layout.node_size_m(0)[1]);
    let mut spans = HashMap::new();
    for (lat, lon) in [(0.0, 10.0), (60.0, 10.0), (89.9, 10.0), (51.5, -0.1), (-65.0, 179.9)] {
        let (clipmap, _, _) = settled(&globe, lat, lon, true);
        let wanted = level0(&clipmap, &globe);
        assert_wanted_within_reach(&globe, &wanted, (lat, lon), radius);
        let columns = wanted.iter().map(|n| n[0]).collect::<std::collections::BTreeSet<_>>().len();
        let rows = wanted.iter().map(|n| n[1]).collect::<std::collections::BTreeSet<_>>().len();
        println!(
            "{lat},{lon}: {} level-0 nodes wanted, {columns} columns, {rows} rows",
            wanted.len()
        );
        spans.insert(lat as i64, (columns, rows));
    }
    let (equator, sixty) = (spans[&0], spans[&60]);
    assert!(sixty.0 >= 2 * equator.0 - 2, "twice the columns at 60 N: {sixty:?} vs {equator:?}");
    // Across Greenwich from 0.1 W: columns on both sides of the seam.
    let (clipmap, _, _) = settled(&globe, 51.5, -0.1, true);
    let seam = level0(&clipmap, &globe);
    let [nx, _] = globe.layout.nodes_at(0);
    assert!(seam.iter().any(|n| n[0] == 0) && seam.iter().any(|n| n[0] == nx - 1));
}

/// A projected grid's wanted set is measured on the earth too: over Web
/// Mercator at 60 N (the plane twice the earth) the wanted level-0 nodes
/// are those within reach on the earth, about three times the plane's
/// (four times the area, less the nodes cut at the edge of reach).
#[test]
fn a_projected_grids_wanted_nodes_are_within_reach_on_the_earth() {
    let globe = Arc::new(Globe::mercator());
    let radius =
        VIEW.load_distance * globe.layout.node_size_m(0)[0].min(globe.layout.node_size_m(0)[1]);
    let (lat, lon) = (60.0f64, 10.0f64);
    let (clipmap, _, _) = settled(&globe, lat, lon, true);
    let wanted = level0(&clipmap, &globe);
    assert_wanted_within_reach(&globe, &wanted, (lat, lon), radius);
    let (chart, _, _) = settled(&globe, lat, lon, false);
    let in_chart = level0(&chart, &globe).len();
    println!(
        "Web Mercator at 60 N: {} level-0 nodes wanted, {in_chart} in the plane",
        wanted.len()
    );
    assert!(2 * wanted.len() >= 5 * in_chart, "{} against {in_chart}", wanted.len());
}

#[test]
fn the_chart_wants_too_few_columns_at_sixty_north() {
    let globe = Arc::new(Globe::new());
    let (chart, _, _) = settled(&globe, 60.0, 10.0, false);
    let (earth, _, _) = settled(&globe, 60.0, 10.0, true);
    let (chart, earth) = (level0(&chart, &globe).len(), level0(&earth, &globe).len());
    println!("60 N, level-0 nodes wanted: chart {chart}, ellipsoid {earth}");
    assert!(earth as f64 > 1.7 * chart as f64);
}

#[test]
fn the_height_under_a_viewer_west_of_the_seam_is_the_finest() {
    let globe = Arc::new(Globe::new());
    let (clipmap, view, position) = settled(&globe, 51.5, -0.1, true);
    let sample = clipmap.height_at(view, DVec2::new(position.x, position.y)).unwrap();
    assert_eq!(sample.node.level, 0, "answered from {:?}", sample.node);
    let [u, v] = globe.placement.post_of_geodetic(51.5f64.to_radians(), (-0.1f64).to_radians());
    let p = globe.placement.ecef(u, v, 0.0);
    let expected = 200.0 + 100.0 * (p.x / 50_000.0).sin();
    assert!((sample.height_m as f64 - expected).abs() < 5.0, "{} vs {expected}", sample.height_m);
}
