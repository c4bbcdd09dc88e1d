//! The clipmap's update cost per frame along a scripted flight over the
//! procedural earth (2^24 samples a side, nodes of 32 cells): a primary
//! flight display alone and with a map view 15 km above it, loading on the
//! loader thread (the clipmap's own cost) and inline (including node
//! generation). Frames are paced in real time at 60 fps, as in the display,
//! so each update starts with caches other work has used; one run repeats
//! the first back to back, where caches stay warm but the loader thread
//! falls behind and competes for the cores. Prints a table,
//! writes target/bench/clipmap.json and target/bench/clipmap.svg.
//! `-- --quick` flies 10 s instead of 60 s.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec2, DVec3};
use plotters::prelude::*;
use ridgeline::clipmap::{Clipmap, ClipmapConfig, LoaderMode, ViewConfig};
use ridgeline::node::NodeSource;
use ridgeline::procedural::{EarthParams, ProceduralEarth};

const FPS: f64 = 60.0;
const SPEED_M_S: f64 = 250.0;
const SLOTS: u32 = 4096;
const BUDGET: u32 = 16;
const PFD: ViewConfig = ViewConfig { node_count: 16, view_distance: 4.0, load_distance: 6.0 };
const MAP: ViewConfig = ViewConfig { node_count: 8, view_distance: 2.0, load_distance: 2.5 };
const MAP_ABOVE_M: f64 = 15_000.0;

/// One configuration's per-frame record.
struct Run {
    name: &'static str,
    update_us: Vec<f64>,
    applied: Vec<u32>,
    missing: Vec<u32>,
    wanted: Vec<u32>,
    height_at_ns: f64,
}

#[derive(serde::Serialize)]
struct Summary {
    name: &'static str,
    frames: usize,
    mean_us: f64,
    p50_us: f64,
    p99_us: f64,
    max_us: f64,
    loads_per_frame_mean: f64,
    loads_per_frame_max: u32,
    wanted_mean: f64,
    missing_mean: f64,
    height_at_ns: f64,
}

/// The PFD's path: a climb from 60 m to 3000 m above ground, a cruise with
/// gentle turns, a descent to 150 m; one position per frame.
fn flight(earth: &ProceduralEarth, frames: u32) -> Vec<DVec3> {
    let mut at = DVec2::new(1.2e7, 8.0e6);
    (0..frames)
        .map(|frame| {
            let t = frame as f64 / FPS;
            let progress = frame as f64 / frames as f64;
            let heading = 0.3 + 0.4 * (t / 20.0).sin();
            at += DVec2::from_angle(heading) * SPEED_M_S / FPS;
            let agl = if progress < 0.25 {
                60.0 + (3000.0 - 60.0) * progress / 0.25
            } else if progress < 0.75 {
                3000.0
            } else {
                3000.0 - (3000.0 - 150.0) * (progress - 0.75) / 0.25
            };
            let ground =
                earth.exact_height(at.x, at.y).expect("the flight stays over the earth") as f64;
            at.extend(ground + agl)
        })
        .collect()
}

fn run(
    name: &'static str,
    earth: &Arc<ProceduralEarth>,
    path: &[DVec3],
    map: bool,
    loader: LoaderMode,
    paced: bool,
) -> Run {
    let config = ClipmapConfig { atlas_bytes: None, atlas_slots: SLOTS, budget: BUDGET, loader };
    let mut clipmap = Clipmap::new(earth.clone(), config).expect("clipmap");
    let pfd = clipmap.add_view(PFD, path[0]).expect("pfd view");
    let map =
        map.then(|| clipmap.add_view(MAP, path[0] + DVec3::Z * MAP_ABOVE_M).expect("map view"));
    let mut record = Run {
        name,
        update_us: vec![],
        applied: vec![],
        missing: vec![],
        wanted: vec![],
        height_at_ns: 0.0,
    };
    let pace = Duration::from_secs_f64(1.0 / FPS);
    for &at in path {
        let frame_start = Instant::now();
        clipmap.set_view_position(pfd, at).expect("finite");
        if let Some(map) = map {
            clipmap.set_view_position(map, at + DVec3::Z * MAP_ABOVE_M).expect("finite");
        }
        let start = Instant::now();
        let stats = clipmap.update().expect("update");
        record.update_us.push(start.elapsed().as_secs_f64() * 1e6);
        record.applied.push(stats.applied);
        record.missing.push(stats.missing);
        record.wanted.push(stats.wanted);
        if paced {
            // Real time: the loader thread works as it would at 60 fps.
            std::thread::sleep(pace.saturating_sub(frame_start.elapsed()));
        }
    }
    record.height_at_ns = height_at_cost(&clipmap, pfd, *path.last().unwrap());
    record
}

/// Mean cost of `height_at` around the viewer, in nanoseconds.
fn height_at_cost(clipmap: &Clipmap, view: ridgeline::clipmap::ViewId, at: DVec3) -> f64 {
    let queries = 20_000;
    let start = Instant::now();
    let mut sum = 0.0;
    for k in 0..queries {
        let offset = DVec2::from_angle(k as f64 * 0.37) * (k % 500) as f64 * 20.0;
        sum += clipmap.height_at(view, at.truncate() + offset).map_or(0.0, |s| s.height_m as f64);
    }
    std::hint::black_box(sum);
    start.elapsed().as_secs_f64() * 1e9 / queries as f64
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn summarise(run: &Run) -> Summary {
    let mut sorted = run.update_us.clone();
    sorted.sort_by(f64::total_cmp);
    let frames = sorted.len();
    let mean = |v: &[u32]| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    Summary {
        name: run.name,
        frames,
        mean_us: sorted.iter().sum::<f64>() / frames as f64,
        p50_us: percentile(&sorted, 0.5),
        p99_us: percentile(&sorted, 0.99),
        max_us: sorted[frames - 1],
        loads_per_frame_mean: mean(&run.applied),
        loads_per_frame_max: *run.applied.iter().max().unwrap(),
        wanted_mean: mean(&run.wanted),
        missing_mean: mean(&run.missing),
        height_at_ns: run.height_at_ns,
    }
}

fn print_table(summaries: &[Summary]) {
    println!(
        "\n{:<34} {:>6} {:>9} {:>9} {:>9} {:>9} {:>10} {:>9} {:>8} {:>8} {:>11}",
        "clipmap update per frame",
        "frames",
        "mean µs",
        "p50 µs",
        "p99 µs",
        "max µs",
        "loads/fr",
        "max load",
        "wanted",
        "missing",
        "height_at ns"
    );
    for s in summaries {
        println!(
            "{:<34} {:>6} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>10.2} {:>9} {:>8.0} {:>8.0} {:>11.0}",
            s.name,
            s.frames,
            s.mean_us,
            s.p50_us,
            s.p99_us,
            s.max_us,
            s.loads_per_frame_mean,
            s.loads_per_frame_max,
            s.wanted_mean,
            s.missing_mean,
            s.height_at_ns
        );
    }
}

fn plot(runs: &[Run], path: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (1000, 700)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(420);
    let frames = runs[0].update_us.len() as u32;
    let floor = 10.0;
    let ceiling =
        runs.iter().flat_map(|r| r.update_us.iter()).copied().fold(floor * 10.0, f64::max) * 1.5;
    let mut chart = ChartBuilder::on(&top)
        .caption("clipmap update per frame along the flight", ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0u32..frames, (floor..ceiling).log_scale())?;
    chart.configure_mesh().x_desc("frame").y_desc("µs (log)").draw()?;
    let colours = [BLUE, RED, GREEN, MAGENTA, BLACK];
    for (run, colour) in runs.iter().zip(colours) {
        let points = run.update_us.iter().enumerate().map(|(f, &us)| (f as u32, us.max(floor)));
        chart
            .draw_series(LineSeries::new(points, colour))?
            .label(run.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    let most = runs.iter().flat_map(|r| r.missing.iter()).copied().max().unwrap_or(1).max(1);
    let mut lower = ChartBuilder::on(&bottom)
        .caption("wanted nodes not yet resident", ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0u32..frames, 0u32..most)?;
    lower.configure_mesh().x_desc("frame").y_desc("nodes").draw()?;
    for (run, colour) in runs.iter().zip(colours) {
        let points = run.missing.iter().enumerate().map(|(f, &m)| (f as u32, m));
        lower.draw_series(LineSeries::new(points, colour))?;
    }
    root.present()?;
    Ok(())
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let seconds = if quick { 10 } else { 60 };
    let earth = Arc::new(ProceduralEarth::new(EarthParams::earth(32, 2024)).expect("earth"));
    let path = flight(&earth, seconds * FPS as u32);
    println!(
        "flight: {seconds} s at {SPEED_M_S} m/s, {FPS} fps; earth {} samples a side, node_size {}, {} levels; \
         {SLOTS} slots, budget {BUDGET}; PFD node_count {} load_distance {}, map node_count {} {} m above",
        earth.layout().posts[0], earth.layout().node_size, earth.layout().levels,
        PFD.node_count, PFD.load_distance, MAP.node_count, MAP_ABOVE_M
    );
    let thread = LoaderMode::Thread { queue: 16 };
    let runs = vec![
        run("PFD, loader thread", &earth, &path, false, thread, true),
        run("PFD + map, loader thread", &earth, &path, true, thread, true),
        run("PFD, inline (incl. generation)", &earth, &path, false, LoaderMode::Inline, true),
        run("PFD + map, inline (incl. gen.)", &earth, &path, true, LoaderMode::Inline, true),
        run("PFD, loader thread, unpaced", &earth, &path, false, thread, false),
    ];
    let summaries: Vec<Summary> = runs.iter().map(summarise).collect();
    print_table(&summaries);
    let ratio = summaries[1].p50_us / summaries[0].p50_us;
    let inline_ratio = summaries[2].mean_us / summaries[0].mean_us;
    let warm_ratio = summaries[0].p50_us / summaries[4].p50_us;
    println!(
        "\nratios (same run): 2 views / 1 view (thread, p50) {ratio:.2}; inline / thread (1 view, mean) {inline_ratio:.2}; \
         paced / unpaced (thread, p50) {warm_ratio:.2}"
    );
    std::fs::create_dir_all("target/bench").expect("target/bench");
    let json = serde_json::json!({
        "quick": quick,
        "flight_s": seconds, "fps": FPS, "speed_m_s": SPEED_M_S,
        "node_size": earth.layout().node_size, "levels": earth.layout().levels,
        "slots": SLOTS, "budget": BUDGET,
        "summaries": summaries,
        "ratio_two_views_over_one_p50": ratio,
        "ratio_inline_over_thread": inline_ratio,
        "ratio_paced_over_unpaced": warm_ratio,
        "per_frame_update_us": runs.iter().map(|r| (r.name, &r.update_us)).collect::<std::collections::BTreeMap<_, _>>(),
    });
    let tmp = Path::new("target/bench/clipmap.json.tmp");
    std::fs::write(tmp, serde_json::to_string_pretty(&json).expect("json")).expect("write json");
    std::fs::rename(tmp, "target/bench/clipmap.json").expect("rename json");
    plot(&runs, Path::new("target/bench/clipmap.svg")).expect("plot");
    println!("wrote target/bench/clipmap.json and target/bench/clipmap.svg");
}
