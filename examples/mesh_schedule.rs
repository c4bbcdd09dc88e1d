//! Measures adaptive chunk meshes (issue 11) on the built-in SRTM tile, with
//! `ridgeline::mesh` only (no GL, no pyramid):
//!
//! 1. the table 1: RTIN triangles at 1, 5, 10, 25 and 50 m over a
//!    513^2 crop, with this crate's exact error map and with Martini's
//!    midpoint-only map (and what that one really errs by), against per-node
//!    regular tiles (node 64, the coarsest level within the error);
//! 2. per node size (32, 64 cells) and level (0..5): the subsampled grid's
//!    delta (today's tiles, every 2^l-th post) against RTIN meshes over the
//!    level-0 posts under each node for several delta schedules: triangles,
//!    vertices and bytes per node, and the measured delta;
//! 3. per schedule, an all-round quadtree selection at tau 1 for three eyes
//!    (a node is drawn when its delta is within tau D / K, D to its box)
//!    against the view-dependent RTIN floor of the whole tile;
//! 4. cracks: the vertical gap between same-level neighbours' shared edges,
//!    with the boundary refined by error only or forced to the level's posts.
//!
//! `cargo run --release --example mesh_schedule [-- --quick]`

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use ridgeline::dem::{import_file, ElevationGrid};
use ridgeline::mesh::rtin::Triangle;
use ridgeline::mesh::{
    max_post_distance, max_surface_distance, view_refine, HeightGrid, Mesh, Metric, Rtin,
    RtinOptions, ViewParams, MAX_VERTICES,
};

/// 1280 px across a 60 degree field of view, the `fly` defaults.
const K: f64 = 1280.0 / (2.0 * 0.577_350_269_189_625_8);
const TAU: f64 = 1.0;
/// The repo's tile vertex (`TileVertex`), and an irregular tile's extra
/// per-tile position (`[u16; 2]`): positions are no longer shared.
const TILE_VERTEX_BYTES: usize = 12;
const POSITION_BYTES: usize = 4;
/// Ulrich section 13: x, y, z and the morph delta as 16-bit numbers.
const ULRICH_VERTEX_BYTES: usize = 8;

fn main() -> Result<()> {
    let quick = std::env::args().any(|a| a == "--quick");
    let started = Instant::now();
    let mut dem = import_file(Path::new("assets/dem/srtm3_n39e040_1000.tif"))?;
    if std::env::var_os("MESH_NORTH_UP").is_some() {
        // Rows north first, as the GeoTIFF stores them (and Martini reads them).
        let w = dem.width as usize;
        let rows: Vec<&[f32]> = dem.heights.chunks(w).rev().collect();
        dem.heights = rows.concat();
    }
    let spacing = dem.georef.spacing_m([dem.width, dem.height]);
    println!(
        "built-in tile: {}x{} posts, spacing {:.1} m east x {:.1} m north, K = {K:.1} px, tau = {TAU} px\n",
        dem.width, dem.height, spacing[0], spacing[1]
    );
    table_1(&dem)?;
    if std::env::args().any(|a| a == "--table-1") {
        return Ok(());
    }
    let node_sizes: &[u32] = if quick { &[64] } else { &[32, 64] };
    let views = views(&dem, spacing);
    let floors = rtin_floors(&dem, &views)?;
    for &n in node_sizes {
        let levels = measure_levels(&dem, n, quick)?;
        let schedules = schedules(&levels, n, quick);
        print_schedules(n, &levels, &schedules);
        print_selection(n, &levels, &schedules, &views, &floors, spacing);
    }
    cracks(&dem, 64, 2)?;
    println!("\ntotal {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

/// The `(span + 1)^2` level-0 posts of the square at `origin`, posts past the
/// data clamped to its last row and column (the pyramid's convention).
fn square(dem: &ElevationGrid, origin: [u32; 2], span: u32) -> Vec<f32> {
    let mut out = Vec::with_capacity((span as usize + 1).pow(2));
    for j in 0..=span {
        for i in 0..=span {
            out.push(
                dem.at((origin[0] + i).min(dem.width - 1), (origin[1] + j).min(dem.height - 1)),
            );
        }
    }
    out
}

fn subsampled_delta(grid: &HeightGrid, stride: u32) -> Result<f64> {
    let mesh = Mesh::regular(grid.side(), stride)?;
    Ok(max_post_distance(&mesh, &mesh.vertex_heights(grid), grid))
}

// ---------------------------------------------------------------- table 1

/// Martini's error map: each midpoint's distance to its hypotenuse only,
/// propagated up the hierarchy the same way (finest triangles first).
fn martini_errors(grid: &HeightGrid) -> Vec<f32> {
    let side = grid.side();
    let idx = |p: [u32; 2]| (p[1] * side + p[0]) as usize;
    let at = |p: [u32; 2]| grid.at(p[0], p[1]);
    let mut errors = vec![0.0f32; (side * side) as usize];
    for depth in (0..2 * grid.cells().trailing_zeros()).rev() {
        for root in Triangle::roots(grid.cells()) {
            root.for_each_at_depth(depth, &mut |t| {
                let m = t.midpoint();
                let mut e = (at(m) - (at(t.a) + at(t.b)) / 2.0).abs();
                for child in t.children().iter().filter(|c| !c.is_leaf()) {
                    e = e.max(errors[idx(child.midpoint())]);
                }
                errors[idx(m)] = errors[idx(m)].max(e);
            });
        }
    }
    errors
}

/// The crop's south-west post: `MESH_CROP=x,y`, else the data's centre.
fn crop_origin() -> [u32; 2] {
    std::env::var("MESH_CROP")
        .ok()
        .and_then(|v| {
            let (x, y) = v.split_once(',')?;
            Some([x.trim().parse().ok()?, y.trim().parse().ok()?])
        })
        .unwrap_or([243, 243])
}

fn table_1(dem: &ElevationGrid) -> Result<()> {
    println!(
        "== table 1: RTIN triangles over the 513^2 crop at post {:?}, max vertical error per post",
        crop_origin()
    );
    println!(
        "{:>8} | {:>10} {:>8} | {:>10} {:>10} | {:>10} | {:>9}",
        "error m", "RTIN exact", "delta m", "Martini", "its delta", "tiles n64", "tiles/RTIN"
    );
    let origin = crop_origin();
    let heights = square(dem, origin, 512);
    let grid = HeightGrid::new(513, &heights)?;
    let rtin = Rtin::new(&grid, RtinOptions::default())?;
    let martini = martini_errors(&grid);
    for e in [1.0, 5.0, 10.0, 25.0, 50.0] {
        let ours = rtin_mesh_tris(&rtin, &grid, e)?;
        let (m_tris, m_delta) = martini_mesh(&rtin, &martini, &grid, e)?;
        let tiles = regular_tiles(&heights, [0, 0], 3, e)?;
        println!(
            "{e:>8} | {:>10} {:>8.2} | {m_tris:>10} {m_delta:>10.2} | {tiles:>10} | {:>9.1}",
            ours.0,
            ours.1,
            tiles as f64 / ours.0 as f64
        );
    }
    println!();
    Ok(())
}

/// Triangles and measured delta of the exact-map mesh (vertex count may pass
/// 65536 on a 513^2 crop: count without indices).
fn rtin_mesh_tris(rtin: &Rtin, grid: &HeightGrid, e: f64) -> Result<(usize, f64)> {
    let mut tris = Vec::new();
    rtin.for_each_triangle(e, &mut |t| tris.push(t.ccw()));
    Ok((tris.len(), delta_of(&tris, grid)))
}

fn martini_mesh(rtin: &Rtin, errors: &[f32], grid: &HeightGrid, e: f64) -> Result<(usize, f64)> {
    let side = grid.side() as usize;
    let mut tris = Vec::new();
    let mut split = |_: &_, m: [u32; 2]| errors[m[1] as usize * side + m[0] as usize] as f64 > e;
    rtin.walk(&mut split, &mut |t| tris.push(t.ccw()));
    Ok((tris.len(), delta_of(&tris, grid)))
}

/// The delta of a triangle list too large for one 16-bit mesh: in pieces.
fn delta_of(tris: &[[[u32; 2]; 3]], grid: &HeightGrid) -> f64 {
    tris.chunks(20_000)
        .map(|chunk| {
            let vertices: Vec<[u16; 2]> =
                chunk.iter().flatten().map(|v| [v[0] as u16, v[1] as u16]).collect();
            let indices = (0..vertices.len() as u16).collect();
            let mesh = Mesh { side: grid.side(), vertices, indices };
            max_post_distance(&mesh, &mesh.vertex_heights(grid), grid)
        })
        .fold(0.0, f64::max)
}

/// Per-node regular tiles of 64 cells under a level-`top` node: each node at
/// the coarsest level whose subsampled delta is within `e`.
fn regular_tiles(heights: &[f32], origin: [u32; 2], level: u32, e: f64) -> Result<usize> {
    let side = (64u32 << 3) + 1;
    let span = 64u32 << level;
    let mut node = Vec::with_capacity((span as usize + 1).pow(2));
    for j in 0..=span {
        let row = (origin[1] + j) as usize * side as usize;
        node.extend_from_slice(
            &heights[row + origin[0] as usize..=row + (origin[0] + span) as usize],
        );
    }
    let grid = HeightGrid::new(span + 1, &node)?;
    if level == 0 || subsampled_delta(&grid, 1 << level)? <= e {
        return Ok(2 * 64 * 64);
    }
    let half = span / 2;
    let mut total = 0;
    for (dx, dy) in [(0, 0), (half, 0), (0, half), (half, half)] {
        total += regular_tiles(heights, [origin[0] + dx, origin[1] + dy], level - 1, e)?;
    }
    Ok(total)
}

// ------------------------------------------------------ per-node measures

/// One node of one level: what the schedules need.
struct NodeInfo {
    /// Box in level-0 posts: south-west post and span.
    origin: [u32; 2],
    z: [f32; 2],
    subsampled_delta: f64,
    rtin: Rtin,
    /// The same node's map against the level-0 surface ([`Metric::Surface`]).
    surface: Rtin,
}

struct Level {
    span: u32,
    nodes: Vec<NodeInfo>,
    /// The level's largest subsampled delta (what the rings use today).
    subsampled_delta: f64,
    heights: Vec<Vec<f32>>,
}

fn measure_levels(dem: &ElevationGrid, n: u32, quick: bool) -> Result<Vec<Level>> {
    let last = if quick { 4 } else { 5 };
    let mut levels = Vec::new();
    for l in 0..=last {
        let span = n << l;
        let count = [(dem.width - 1).div_ceil(span), (dem.height - 1).div_ceil(span)];
        let (mut nodes, mut all_heights) = (Vec::new(), Vec::new());
        for y in 0..count[1] {
            for x in 0..count[0] {
                let origin = [x * span, y * span];
                let heights = square(dem, origin, span);
                let grid = HeightGrid::new(span + 1, &heights)?;
                let z =
                    heights.iter().fold([f32::MAX, f32::MIN], |z, &h| [z[0].min(h), z[1].max(h)]);
                let subsampled_delta = subsampled_delta(&grid, 1 << l)?;
                let rtin = Rtin::new(&grid, RtinOptions::default())?;
                let surface_options =
                    RtinOptions { metric: Metric::Surface, ..RtinOptions::default() };
                let surface = Rtin::new(&grid, surface_options)?;
                nodes.push(NodeInfo { origin, z, subsampled_delta, rtin, surface });
                all_heights.push(heights);
            }
        }
        let subsampled_delta = nodes.iter().map(|n| n.subsampled_delta).fold(0.0, f64::max);
        levels.push(Level { span, nodes, subsampled_delta, heights: all_heights });
    }
    Ok(levels)
}

/// A delta per level and, per level and node, the mesh's triangles and
/// vertices (vertices may pass 65536: then the schedule is unusable there).
struct Schedule {
    name: String,
    delta: Vec<f64>,
    /// Per level: (triangles, vertices, measured post delta, surface delta) per node.
    nodes: Vec<Vec<(usize, usize, f64, f64)>>,
}

fn schedules(levels: &[Level], n: u32, quick: bool) -> Vec<Schedule> {
    let mut out = Vec::new();
    let delta0s: &[f64] = if quick { &[1.0, 4.0] } else { &[0.5, 1.0, 2.0, 4.0] };
    for &d0 in delta0s {
        let delta = (0..levels.len()).map(|l| d0 * (1u32 << l) as f64).collect();
        out.push(evaluate(format!("halve d0={d0}"), delta, levels, Metric::Posts));
    }
    let today = levels.iter().map(|l| l.subsampled_delta).collect();
    out.push(evaluate("today's deltas".into(), today, levels, Metric::Posts));
    for budget in [2 * n * n, 8 * n * n] {
        let delta =
            levels.iter().map(|l| budget_delta(l, budget as usize, Metric::Posts)).collect();
        out.push(evaluate(format!("budget {budget} tris"), delta, levels, Metric::Posts));
    }
    for d0 in [2.0, 4.0] {
        let delta = (0..levels.len()).map(|l| d0 * (1u32 << l) as f64).collect();
        out.push(evaluate(format!("surf halve d0={d0}"), delta, levels, Metric::Surface));
    }
    // Level 0 exact (the eye can be a few hundred metres from the ground,
    // where tau 1 allows under half a metre), then 4 m halving.
    let delta =
        (0..levels.len()).map(|l| if l == 0 { 0.0 } else { 4.0 * (1u32 << l) as f64 }).collect();
    out.push(evaluate("surf 0, 4*2^l".into(), delta, levels, Metric::Surface));
    let budget = 2 * n * n;
    let delta = levels.iter().map(|l| budget_delta(l, budget as usize, Metric::Surface)).collect();
    out.push(evaluate(format!("surf budget {budget}"), delta, levels, Metric::Surface));
    out
}

fn map_of(node: &NodeInfo, metric: Metric) -> &Rtin {
    match metric {
        Metric::Posts => &node.rtin,
        Metric::Surface => &node.surface,
    }
}

/// The smallest delta (to 1 %) at which every node of the level fits the
/// triangle budget of today's regular tile.
fn budget_delta(level: &Level, budget: usize, metric: Metric) -> f64 {
    let fits =
        |d: f64| level.nodes.iter().all(|node| map_of(node, metric).triangle_count(d) <= budget);
    if fits(0.0) {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while !fits(hi) {
        hi *= 2.0;
    }
    while hi - lo > 0.01 * hi {
        let mid = (lo + hi) / 2.0;
        if fits(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

fn evaluate(name: String, delta: Vec<f64>, levels: &[Level], metric: Metric) -> Schedule {
    let nodes = levels
        .iter()
        .zip(&delta)
        .map(|(level, &d)| {
            level
                .nodes
                .iter()
                .zip(&level.heights)
                .map(|(node, heights)| node_mesh(map_of(node, metric), heights, level.span, d))
                .collect()
        })
        .collect();
    Schedule { name, delta, nodes }
}

fn node_mesh(rtin: &Rtin, heights: &[f32], span: u32, d: f64) -> (usize, usize, f64, f64) {
    let grid = HeightGrid::new(span + 1, heights).expect("checked when measured");
    match rtin.extract(d) {
        Ok(mesh) => {
            let h = mesh.vertex_heights(&grid);
            let post = max_post_distance(&mesh, &h, &grid);
            debug_assert!(post <= d);
            (
                mesh.triangle_count(),
                mesh.vertices.len(),
                post,
                max_surface_distance(&mesh, &h, &grid),
            )
        }
        Err(_) => {
            let tris = rtin.triangle_count(d);
            // Euler on a disc: V = (T + boundary vertices) / 2 + 1 >= T / 2 + 1.
            (tris, tris / 2 + 1 + 2 * span as usize, f64::NAN, f64::NAN)
        }
    }
}

fn print_schedules(n: u32, levels: &[Level], schedules: &[Schedule]) {
    println!("== node {n} cells: today's subsampled tiles against RTIN meshes over the level-0 posts under each node");
    println!("today: {} triangles, {} vertices per node ({} with skirts), 12 B/vertex, positions and indices shared", 2 * n * n, (n + 1).pow(2), (n + 1).pow(2) + 4 * (n + 1));
    println!(
        "{:>2} {:>5} {:>6} {:>9} | {:<18} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9} {:>9}",
        "l",
        "nodes",
        "span",
        "grid d m",
        "schedule",
        "d_l m",
        "tris avg",
        "tris max",
        "vert max",
        "post d",
        "surf d",
        "KB@16B/v",
        "KB@8B/v"
    );
    for (l, level) in levels.iter().enumerate() {
        for (s, schedule) in schedules.iter().enumerate() {
            let stats = &schedule.nodes[l];
            let avg = stats.iter().map(|s| s.0).sum::<usize>() as f64 / stats.len() as f64;
            let worst = stats.iter().max_by_key(|s| s.1).expect("a level has nodes");
            let tri_max = stats.iter().map(|s| s.0).max().unwrap_or(0);
            // NaN (a node over the vertex limit, not measured) shows as '-'.
            let largest = |f: fn(&(usize, usize, f64, f64)) -> f64| {
                stats.iter().map(f).fold(0.0, |a: f64, b| {
                    if a.is_nan() || b.is_nan() {
                        f64::NAN
                    } else {
                        a.max(b)
                    }
                })
            };
            let (post, surf) = (largest(|s| s.2), largest(|s| s.3));
            let over = worst.1 > MAX_VERTICES;
            let kb = |bpv: usize| (worst.1 * bpv + worst.0 * 6) as f64 / 1024.0;
            let head = if s == 0 {
                format!(
                    "{l:>2} {:>5} {:>6} {:>9.2}",
                    level.nodes.len(),
                    level.span,
                    level.subsampled_delta
                )
            } else {
                format!("{:>2} {:>5} {:>6} {:>9}", "", "", "", "")
            };
            println!(
                "{head} | {:<18} {:>8.2} {avg:>8.0} {tri_max:>8} {:>8} {:>8} {:>8} {:>9.1} {:>9.1}",
                schedule.name,
                schedule.delta[l],
                format!("{}{}", worst.1, if over { "!" } else { "" }),
                if post.is_nan() { "-".into() } else { format!("{post:.2}") },
                if surf.is_nan() { "-".into() } else { format!("{surf:.2}") },
                kb(TILE_VERTEX_BYTES + POSITION_BYTES),
                kb(ULRICH_VERTEX_BYTES),
            );
        }
    }
    println!("('!' = over 65536 vertices, 16-bit indices impossible; post d / surf d = largest measured delta against level-0 posts / the level-0 surface)\n");
}

// ------------------------------------------------------- view selection

struct View {
    name: &'static str,
    eye: [f64; 3],
}

/// Three eyes like the issue's: over the centre 1500 m and 800 m above the
/// highest peak, and 300 m above the lowest post.
fn views(dem: &ElevationGrid, spacing: [f64; 2]) -> Vec<View> {
    let top = dem.heights.iter().cloned().fold(f32::MIN, f32::max) as f64;
    let (low_at, low) =
        dem.heights
            .iter()
            .enumerate()
            .fold((0, f32::MAX), |best, (k, &h)| if h < best.1 { (k, h) } else { best });
    let centre = [spacing[0] * 499.5, spacing[1] * 499.5];
    let low_xy = [
        (low_at % dem.width as usize) as f64 * spacing[0],
        (low_at / dem.width as usize) as f64 * spacing[1],
    ];
    vec![
        View { name: "centre, peak + 1500 m", eye: [centre[0], centre[1], top + 1500.0] },
        View { name: "centre, peak + 800 m", eye: [centre[0], centre[1], top + 800.0] },
        View { name: "valley floor + 300 m", eye: [low_xy[0], low_xy[1], low as f64 + 300.0] },
    ]
}

/// The RTIN floor per view: the whole tile padded to 1025^2 (clamped).
fn rtin_floors(dem: &ElevationGrid, views: &[View]) -> Result<Vec<u64>> {
    let heights = square(dem, [0, 0], 1024);
    let grid = HeightGrid::new(1025, &heights)?;
    let rtin = Rtin::new(&grid, RtinOptions { bounds: true, ..RtinOptions::default() })?;
    let spacing = dem.georef.spacing_m([dem.width, dem.height]);
    println!("== view-dependent RTIN refinement of the whole tile at tau {TAU} (all round, no frustum; full resolution: {} triangles)", 2 * 999 * 999);
    let mut floors = Vec::new();
    for view in views {
        let params = ViewParams { eye: view.eye, spacing, k: K, tau: TAU };
        let mut inside = 0u64;
        let count = view_refine(&rtin, &params, &mut |t| {
            inside += u64::from(t.ccw().iter().any(|v| v[0] < 999 && v[1] < 999));
        })?;
        println!(
            "{:<24} eye ({:.0}, {:.0}, {:.0}) m: {count} triangles ({inside} touching the data)",
            view.name, view.eye[0], view.eye[1], view.eye[2]
        );
        floors.push(count);
    }
    println!();
    Ok(floors)
}

/// Quadtree selection from the coarsest level: a node is drawn when its
/// level's delta is within tau D / K, D from the eye to its box; a level-0
/// node too close for its delta is drawn at full resolution.
fn select(
    levels: &[Level],
    l: usize,
    k: usize,
    delta: &[f64],
    tris: &dyn Fn(usize, usize) -> usize,
    eye: [f64; 3],
    spacing: [f64; 2],
) -> usize {
    let node = &levels[l].nodes[k];
    let span = levels[l].span as f64;
    let gap = |lo: f64, hi: f64, e: f64| (lo - e).max(e - hi).max(0.0);
    let dx = gap(
        node.origin[0] as f64 * spacing[0],
        (node.origin[0] as f64 + span) * spacing[0],
        eye[0],
    );
    let dy = gap(
        node.origin[1] as f64 * spacing[1],
        (node.origin[1] as f64 + span) * spacing[1],
        eye[1],
    );
    let dz = gap(node.z[0] as f64, node.z[1] as f64, eye[2]);
    let d = (dx * dx + dy * dy + dz * dz).sqrt();
    if delta[l] <= TAU * d / K {
        return tris(l, k);
    }
    if l == 0 {
        // Too close for this level-0 mesh: the full-resolution node.
        return 2 * (levels[0].span as usize).pow(2);
    }
    let finer = &levels[l - 1];
    let per_row = (999u32).div_ceil(finer.span) as usize;
    let (x, y) = (node.origin[0] / finer.span, node.origin[1] / finer.span);
    let mut total = 0;
    for (cx, cy) in [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)] {
        if cx * finer.span < 999 && cy * finer.span < 999 {
            total += select(
                levels,
                l - 1,
                cy as usize * per_row + cx as usize,
                delta,
                tris,
                eye,
                spacing,
            );
        }
    }
    total
}

fn print_selection(
    n: u32,
    levels: &[Level],
    schedules: &[Schedule],
    views: &[View],
    floors: &[u64],
    spacing: [f64; 2],
) {
    // Start from the coarsest level whose single node covers the data.
    let root = levels.iter().position(|l| l.nodes.len() == 1).unwrap_or(levels.len() - 1);
    println!("== node {n}: all-round quadtree selection at tau {TAU} from level {root} (LOD triangles; / RTIN floor)");
    print!("{:<20}", "schedule");
    for v in views {
        print!(" | {:>24}", v.name);
    }
    println!();
    let today: Vec<f64> = levels.iter().map(|l| l.subsampled_delta).collect();
    let grid_tris = |_: usize, _: usize| 2 * (n as usize).pow(2);
    let row = |name: &str, delta: &[f64], tris: &dyn Fn(usize, usize) -> usize| {
        print!("{name:<20}");
        for (v, floor) in views.iter().zip(floors) {
            let count = select(levels, root, 0, delta, tris, v.eye, spacing);
            print!(" | {count:>14} {:>8.2}x", count as f64 / *floor as f64);
        }
        println!();
    };
    row("today (subsampled)", &today, &grid_tris);
    for s in schedules {
        let tris = |l: usize, k: usize| s.nodes[l][k].0;
        row(&s.name, &s.delta, &tris);
    }
    println!();
}

// ---------------------------------------------------------------- cracks

/// Heights along one edge of a mesh at every post, interpolated between the
/// mesh's boundary vertices, south to north (edge 1 east, 3 west).
fn edge_profile(mesh: &Mesh, heights: &[f32], edge: usize) -> Vec<f64> {
    let grid = HeightGrid::new(mesh.side, heights).expect("node grid");
    let mut verts: Vec<(u32, f64)> = mesh.boundary_vertices()[edge]
        .iter()
        .map(|&v| {
            let [i, j] = mesh.vertices[v as usize];
            (j as u32, grid.at(i as u32, j as u32) as f64)
        })
        .collect();
    verts.sort_by_key(|v| v.0);
    let mut out = Vec::with_capacity(mesh.side as usize);
    for w in verts.windows(2) {
        let ((p, hp), (q, hq)) = (w[0], w[1]);
        for s in p..q {
            out.push(hp + (hq - hp) * (s - p) as f64 / (q - p) as f64);
        }
    }
    out.push(verts.last().expect("corners").1);
    out
}

/// Same-level east-west neighbours of level `l`, node `n`, halving schedule
/// d0 = 1: the largest vertical gap along shared edges, with the boundary
/// refined by error only or forced to every `2^l`-th post (today's posts).
fn cracks(dem: &ElevationGrid, n: u32, l: u32) -> Result<()> {
    let span = n << l;
    let d = (1u32 << l) as f64;
    println!("== cracks: node {n}, level {l} (span {span}), delta {d} m, every east-west pair of neighbours");
    for step in [None, Some(1u32 << l), Some(1)] {
        let (mut gap, mut same, mut pairs, mut tris) = (0.0f64, 0, 0, 0usize);
        for y in 0..(999 / span) {
            for x in 0..(999 / span - 1) {
                let options = RtinOptions { edge_step: step, ..RtinOptions::default() };
                let west_h = square(dem, [x * span, y * span], span);
                let east_h = square(dem, [(x + 1) * span, y * span], span);
                let west = Rtin::new(&HeightGrid::new(span + 1, &west_h)?, options)?.extract(d)?;
                let east = Rtin::new(&HeightGrid::new(span + 1, &east_h)?, options)?.extract(d)?;
                let a = edge_profile(&west, &west_h, 1);
                let b = edge_profile(&east, &east_h, 3);
                gap = a.iter().zip(&b).map(|(p, q)| (p - q).abs()).fold(gap, f64::max);
                same += usize::from(a == b);
                pairs += 1;
                tris += west.triangle_count();
            }
        }
        let label = step.map_or("error only".to_string(), |s| format!("forced every {s}"));
        println!("{label:<18}: largest gap {gap:.2} m (2 d = {:.0} m), identical edges {same}/{pairs}, mean triangles {:.0}", 2.0 * d, tris as f64 / pairs as f64);
    }
    Ok(())
}
