//! `ridgeline fly`: the main job. Flies a camera path (the built-in approach
//! over the built-in terrain by default) in a window where a display answers,
//! headless otherwise; headless it writes PNG snapshots, the last frame and
//! `stats.json`, and ends with a summary table.

use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use ridgeline::display::{Display, DisplayConfig};
use ridgeline::flight::FlightPath;
use ridgeline::gl::{GlBackend, GlInfo, GlesVersion, OpenedBackend};
use ridgeline::input::place::DisplayFrame;
use ridgeline::input::InputSpec;
use ridgeline::pipeline::FrameStats;
use ridgeline::symbology::{reference_symbols, SymbolMesh};
use serde_json::json;

use super::frames::{FrameRecord, Row};
use super::live::{self, InputReport, Live};
use super::progress::Bar;

pub use super::fly_args::FlyArgs;

/// The smallest and largest `--memory-mb` (besides 0, no budget).
const MEMORY_MB_RANGE: std::ops::RangeInclusive<u32> = 4..=65_536;
/// The frame rate a window is taken to keep for the valid life's declared travel.
const WINDOW_RATE_HZ: f64 = 10.0;

impl FlyArgs {
    /// `--memory-mb`, `None` for 0 (no budget).
    fn memory(&self) -> Option<u32> {
        Some(self.memory_mb).filter(|&mb| mb > 0)
    }
}

pub fn run(args: &FlyArgs) -> Result<()> {
    check_args(args)?;
    let bar = Bar::new();
    let terrain = args.view.open_terrain(&bar)?;
    bar.finish();
    super::heap::restart_peak();
    // Live runs need the dataset's latitude and longitude; path runs report
    // them where the dataset has them.
    let frame = match args.input {
        Some(_) => Some(live::display_frame(&terrain)?),
        None => live::display_frame(&terrain).ok(),
    };
    let path = match args.input {
        Some(_) => None,
        None => Some(terrain.flight_path(args.view.path.as_deref(), args.view.flight)?),
    };
    let config = display_config(args, &terrain, path.as_ref())?;
    let dataset_name = terrain.name.clone();
    let opening = match (args.memory(), config.memory_budget_bytes) {
        (Some(mb), Some(display)) => format!(
            "opening the display with --memory-mb {mb} ({:.1} MB after headless snapshots)",
            display as f64 / MB as f64
        ),
        _ => "opening the display".to_owned(),
    };
    let mut display = Display::new(&config, terrain.source, terrain.summary).context(opening)?;
    let info = display.info().clone();
    print_context(&dataset_name, &info);
    let window = info.backend == OpenedBackend::Window;
    let (rows, input) = match (path, args.input, frame) {
        (Some(path), _, _) => (fly_path(args, &mut display, &path, frame.as_ref(), window)?, None),
        (None, Some(spec), Some(frame)) => fly_live(args, &mut display, &spec, frame, window)?,
        (None, _, _) => bail!("--input: no dataset frame"),
    };
    let memory = memory_report(args, &display, &rows);
    if !window {
        let travel = config.scene.lod.max_travel_m;
        let run = RunInfo { info: &info, dataset: &dataset_name, max_travel_m: travel };
        write_stats(args, &run, &rows, &memory, input.as_ref())?;
    }
    print_summary(&rows, &memory, input.as_ref())
}

/// Refuses settings no flight can run with before anything is opened.
fn check_args(args: &FlyArgs) -> Result<()> {
    args.view.check()?;
    live::check(args)?;
    if !(args.warning_above.is_finite()
        && args.caution_below.is_finite()
        && args.caution_below >= 0.0)
    {
        bail!("--warning-above and --caution-below must be finite metres, the caution band not negative");
    }
    if let Some(mb) = args.memory().filter(|mb| !MEMORY_MB_RANGE.contains(mb)) {
        bail!(
            "--memory-mb {mb} must be between {} and {} MB",
            MEMORY_MB_RANGE.start(),
            MEMORY_MB_RANGE.end()
        );
    }
    Ok(())
}

/// The line naming the dataset and the context the flight draws with.
fn print_context(dataset_name: &str, info: &GlInfo) {
    println!(
        "ridgeline fly: {} on {} ({}), {}",
        dataset_name,
        info.backend.name(),
        info.version,
        info.renderer
    );
    if info.requested == GlesVersion::Es2 {
        // Mesa answers an ES 2.0 request with a newer context; the renderer
        // then uses only what ES 2.0 has.
        println!("ridgeline fly: OpenGL ES 2.0 requested: features capped to ES 2.0");
    }
}

/// The display's configuration for `args` over `terrain`, along `path`
/// (or live, without one).
fn display_config(
    args: &FlyArgs,
    terrain: &super::terrain::Terrain,
    path: Option<&FlightPath>,
) -> Result<DisplayConfig> {
    let mut config = DisplayConfig::new(args.backend, args.view.size);
    config.memory_budget_bytes = args.memory().map(|mb| display_budget(args, mb)).transpose()?;
    config.version = if args.es2 { GlesVersion::Es2 } else { GlesVersion::Es3 };
    config.scene.warning_above_m = args.warning_above;
    config.scene.caution_below_m = args.caution_below;
    config.scene.curvature = !args.flat_earth;
    if !args.flat_earth {
        args.view.configure_earth(&mut config, terrain);
    }
    match path {
        Some(path) => {
            // Headless frames are evenly spaced along the path; a window is
            // taken to show WINDOW_RATE_HZ (slower frames re-test every
            // tile); `auto` may open either, so it declares the longer interval.
            let headless = path.duration() / args.frames.saturating_sub(1).max(1) as f64;
            let interval = match args.backend {
                GlBackend::Window => 1.0 / WINDOW_RATE_HZ,
                GlBackend::Auto => headless.max(1.0 / WINDOW_RATE_HZ),
                _ => headless,
            };
            args.view.configure(&mut config, path, interval);
        }
        None => args.view.configure_at(&mut config, live::max_speed(args), 1.0 / args.fps),
    }
    config.scene.clusters = args.clusters;
    config.fov_x_deg = args.view.fov;
    Ok(config)
}

/// Flies `path` in a window or headless.
fn fly_path(
    args: &FlyArgs,
    display: &mut Display,
    path: &FlightPath,
    frame: Option<&DisplayFrame>,
    window: bool,
) -> Result<Vec<Row>> {
    let mut drawer = PathFrames { args, path, frame, symbols: SymbolMesh::new() };
    if window {
        fly_window(display, &mut drawer)
    } else {
        fly_headless(args, display, &mut drawer)
    }
}

/// Flies live from `spec`: listens, draws, stops; the rows and what the
/// input did.
fn fly_live(
    args: &FlyArgs,
    display: &mut Display,
    spec: &InputSpec,
    frame: DisplayFrame,
    window: bool,
) -> Result<(Vec<Row>, Option<InputReport>)> {
    let mut live = Live::start(args, spec, frame)?;
    println!("ridgeline fly: listening for {} on {}", spec.kind.name(), live.address());
    std::io::Write::flush(&mut std::io::stdout())?;
    let rows = if window {
        live::fly_window(args, display, &mut live)?
    } else {
        live::fly_headless(args, display, &mut live)?
    };
    let address = live.address().to_owned();
    let (counts, recorded) = live.stop()?;
    let report = InputReport::new(args, &address, &rows, counts, recorded);
    Ok((rows, Some(report)))
}

const MB: u64 = 1 << 20;

/// Heap a headless snapshot takes while it is read back and encoded (the
/// image, flipped in place, and the PNG encoder's buffers), per pixel:
/// measured 5.3 MB at 1280x720 (6 bytes a pixel).
const SNAPSHOT_BYTES_PER_PIXEL: u64 = 8;

/// The part of `--memory-mb` the display gets: all of it, less what a
/// headless run's snapshots take.
fn display_budget(args: &FlyArgs, memory_mb: u32) -> Result<u64> {
    let budget = memory_mb as u64 * MB;
    let snapshot = SNAPSHOT_BYTES_PER_PIXEL * args.view.size.x as u64 * args.view.size.y as u64;
    match budget.checked_sub(snapshot).filter(|&left| left >= ridgeline::pipeline::MIN_BUDGET_BYTES)
    {
        Some(left) => Ok(left),
        None => bail!(
            "--memory-mb {}: {:.1} MB go to snapshots at {}x{}, too little is left for the display",
            memory_mb,
            snapshot as f64 / MB as f64,
            args.view.size.x,
            args.view.size.y
        ),
    }
}

/// What the run took of the board's memory (stats.json's `memory`).
#[derive(serde::Serialize)]
struct MemoryReport {
    /// `--memory-mb`, bytes (null: unset, sized for the view).
    budget_bytes: Option<u64>,
    /// Of it, what the display was planned for (the rest: snapshots).
    display_budget_bytes: u64,
    /// Ridgeline's own heap at its peak (the counting allocator).
    heap_peak_bytes: u64,
    /// Ridgeline's own heap at the end of the run.
    heap_bytes: u64,
    /// The GPU tile buffer.
    gpu_buffer_bytes: u64,
    /// Heap peak plus GPU buffer: what the budget bounds.
    own_bytes: u64,
    /// The most bytes the atlas's nodes may take (null: no budget).
    atlas_budget_bytes: Option<u64>,
    /// The most the atlas's nodes took in a frame.
    atlas_peak_bytes: u64,
    /// How the budget was shared (null: no budget).
    plan: Option<ridgeline::pipeline::MemoryPlan>,
    /// The process's peak and current resident memory (VmHWM, VmRSS).
    resident_peak_bytes: u64,
    resident_bytes: u64,
    /// Resident peak minus Ridgeline's heap peak: the GL driver (on
    /// llvmpipe the GPU buffer too, and every buffer the driver keeps),
    /// code and memory-mapped data.
    driver_and_rest_bytes: u64,
}

fn memory_report(args: &FlyArgs, display: &Display, rows: &[Row]) -> MemoryReport {
    let pipeline = display.pipeline();
    let heap_peak_bytes = super::heap::peak() as u64;
    let config = pipeline.scene().config();
    // With clusters the GPU holds the cluster vertex buffer and its index
    // buffer at half the size, and not the tile buffer.
    let copies = if config.clusters { 1.5 } else { 1.0 };
    let gpu_buffer_bytes = (config.buffer_bytes as f64 * copies) as u64;
    let (resident_peak_bytes, resident_bytes) = super::heap::resident().unwrap_or((0, 0));
    let plan = pipeline.memory_plan();
    MemoryReport {
        budget_bytes: args.memory().map(|mb| mb as u64 * MB),
        display_budget_bytes: plan.map_or(0, |p| p.budget_bytes),
        heap_peak_bytes,
        heap_bytes: super::heap::in_use() as u64,
        gpu_buffer_bytes,
        own_bytes: heap_peak_bytes + gpu_buffer_bytes,
        atlas_budget_bytes: pipeline.clipmap().atlas().byte_budget(),
        atlas_peak_bytes: rows.iter().map(|r| r.stats.atlas_bytes).max().unwrap_or(0),
        plan,
        resident_peak_bytes,
        resident_bytes,
        driver_and_rest_bytes: resident_peak_bytes.saturating_sub(heap_peak_bytes),
    }
}

/// Draws a path's frames, with the reference symbols unless they are off.
struct PathFrames<'a> {
    args: &'a FlyArgs,
    path: &'a FlightPath,
    frame: Option<&'a DisplayFrame>,
    symbols: SymbolMesh,
}

impl PathFrames<'_> {
    /// Draws the path's pose at `t`.
    fn draw(&mut self, display: &mut Display, t: f64) -> Result<(FrameStats, FrameRecord)> {
        let size = [self.args.view.size.x, self.args.view.size.y];
        let pose = self.path.sample(t);
        let camera = pose.camera(self.args.view.fov, size);
        let stats = if self.args.symbology.on() {
            let velocity = live::path_velocity(self.path, t);
            reference_symbols(&mut self.symbols, &camera, velocity);
            display.frame_with_symbols(&camera, &self.symbols)?
        } else {
            display.frame(&camera)?
        };
        let record = FrameRecord {
            pose: self.frame.map(|f| f.geodetic(&pose)),
            input: None,
            wall_time: super::frames::wall_time(),
        };
        Ok((stats, record))
    }
}

fn fly_headless(
    args: &FlyArgs,
    display: &mut Display,
    drawer: &mut PathFrames,
) -> Result<Vec<Row>> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create the output folder", args.out.display()))?;
    let frames = args.frames.max(1);
    let path = drawer.path;
    // Start-up: page in the terrain around the first pose, as a display would
    // before it is shown, so the first frame is not drawn from the root alone.
    let first =
        path.sample(path.start_time()).camera(args.view.fov, [args.view.size.x, args.view.size.y]);
    display.settle(&first, 10_000)?;
    let every = (frames / args.snapshots.max(1)).max(1);
    let mut rows = Vec::with_capacity(frames as usize);
    for (k, t) in path.frame_times(frames).enumerate() {
        let k = k as u32;
        let (stats, record) =
            drawer.draw(display, t).with_context(|| format!("frame {k} at t = {t:.2} s"))?;
        let last = k + 1 == frames;
        if k % every == 0 || last {
            let image = display.read_pixels()?;
            let name = if last { "last.png".to_string() } else { format!("frame_{k:05}.png") };
            super::save_png(&image, &args.out.join(name))?;
        }
        rows.push(Row { frame: k, t, stats, record });
    }
    Ok(rows)
}

fn fly_window(display: &mut Display, drawer: &mut PathFrames) -> Result<Vec<Row>> {
    let start = Instant::now();
    let mut rows = Vec::new();
    let path = drawer.path;
    let duration = path.end_time() - path.start_time();
    loop {
        let elapsed = start.elapsed().as_secs_f64();
        if elapsed > duration {
            break;
        }
        let t = path.start_time() + elapsed;
        let (stats, record) = drawer.draw(display, t)?;
        display.present()?;
        rows.push(Row { frame: rows.len() as u32, t, stats, record });
        if display.pump_events(Some(Duration::ZERO)).close_requested {
            break;
        }
    }
    Ok(rows)
}

/// What stats.json says about the run besides its frames.
struct RunInfo<'a> {
    info: &'a ridgeline::gl::GlInfo,
    dataset: &'a str,
    max_travel_m: Option<f64>,
}

fn write_stats(
    args: &FlyArgs,
    run: &RunInfo,
    rows: &[Row],
    memory: &MemoryReport,
    input: Option<&InputReport>,
) -> Result<()> {
    let (info, dataset, max_travel_m) = (run.info, run.dataset, run.max_travel_m);
    let report = json!({
        "backend": info.backend.name(),
        "gl_version": info.version,
        "gl_renderer": info.renderer,
        "shading_language_version": info.shading_language_version,
        "requested": if info.requested == GlesVersion::Es2 { "es2" } else { "es3" },
        "dataset": dataset,
        "size": [args.view.size.x, args.view.size.y],
        "tau_px": args.view.tau,
        "triangle_budget": args.view.triangle_budget,
        "frame_ms_target": args.view.frame_ms,
        "max_travel_m": max_travel_m,
        "tau_loosened_frames": rows.iter().filter(|r| r.stats.tau_loosened()).count(),
        "clusters": args.clusters,
        "fov_x_deg": args.view.fov,
        "flight": format!("{:?}", args.view.flight).to_lowercase(),
        "memory": memory,
        "symbology": args.symbology.on(),
        "input": input,
        // Each frame is `Row`'s serde output: `FrameStats`' own keys.
        "frames": rows,
    });
    let path = args.out.join("stats.json");
    super::write_beside(&path, serde_json::to_string_pretty(&report)?.as_bytes())?;
    println!("wrote {} and {} images", path.display(), rows.len().min(args.snapshots as usize + 1));
    Ok(())
}

fn print_summary(rows: &[Row], memory: &MemoryReport, input: Option<&InputReport>) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    let mut out = String::new();
    write_frames(&mut out, rows)?;
    write_memory(&mut out, memory)?;
    write_tau(&mut out, rows)?;
    write_split_tests(&mut out, rows)?;
    if let Some(input) = input {
        input.write(&mut out, rows.len())?;
    }
    super::print(&out)
}

/// The frames' times, tiles, calls, uploads and culling (`rows` is not empty).
fn write_frames(out: &mut String, rows: &[Row]) -> Result<()> {
    use std::fmt::Write as _;
    let mut frame_ms: Vec<f64> = rows.iter().map(|r| r.stats.frame_ms).collect();
    frame_ms.sort_by(f64::total_cmp);
    let pick = |q: f64| frame_ms[((frame_ms.len() - 1) as f64 * q).round() as usize];
    let mean = |f: &dyn Fn(&FrameStats) -> f64| {
        rows.iter().map(|r| f(&r.stats)).sum::<f64>() / rows.len() as f64
    };
    writeln!(out)?;
    writeln!(out, "  frames            {}", rows.len())?;
    writeln!(
        out,
        "  frame ms          mean {:.1}, p50 {:.1}, p95 {:.1}, max {:.1}",
        mean(&|s| s.frame_ms),
        pick(0.5),
        pick(0.95),
        pick(1.0)
    )?;
    writeln!(
        out,
        "  cpu ms            clipmap {:.2}, select {:.2}, tiles {:.2}",
        mean(&|s| s.clipmap_ms),
        mean(&|s| s.scene.cpu_ms.select_ms),
        mean(&|s| s.scene.cpu_ms.tiles_ms)
    )?;
    writeln!(
        out,
        "  tiles             mean {:.0} ({:.0} triangles, {:.0} draw calls, {:.0} clusters)",
        mean(&|s| s.scene.tiles as f64),
        mean(&|s| s.scene.triangles as f64),
        mean(&|s| s.calls.draw_calls as f64),
        mean(&|s| s.scene.clusters as f64)
    )?;
    writeln!(
        out,
        "  GL calls          mean {:.0} a frame ({:.0} attribute pointer changes, {:.0} vertex array binds, {:.0} uniform writes)",
        mean(&|s| s.calls.calls() as f64),
        mean(&|s| s.calls.attribute_pointer_changes as f64),
        mean(&|s| s.calls.vertex_array_binds as f64),
        mean(&|s| s.calls.uniform_writes as f64)
    )?;
    write_uploads(out, rows)
}

/// What the GPU received, the allocator and the atlas at the end, horizon culling.
fn write_uploads(out: &mut String, rows: &[Row]) -> Result<()> {
    use std::fmt::Write as _;
    let mean = |f: &dyn Fn(&FrameStats) -> f64| {
        rows.iter().map(|r| f(&r.stats)).sum::<f64>() / rows.len() as f64
    };
    // What the GPU received: tile blocks, or cluster blocks with clusters on.
    let uploaded: u64 = rows.iter().map(|r| r.stats.calls.bytes_uploaded).sum();
    let Some(last) = rows.last() else { return Ok(()) };
    writeln!(
        out,
        "  uploaded          {:.1} MB in all, {:.0} KB per frame",
        uploaded as f64 / 1e6,
        uploaded as f64 / 1e3 / rows.len() as f64
    )?;
    writeln!(
        out,
        "  allocator         {:.1} MB used at the end",
        last.stats.scene.allocator_used_bytes as f64 / 1e6
    )?;
    writeln!(out, "  resident nodes    {} at the end", last.stats.resident_nodes)?;
    let kept = mean(&|s| s.scene.tiles as f64);
    let hidden = mean(&|s| s.scene.horizon_culled as f64);
    writeln!(
        out,
        "  horizon culled    mean {hidden:.0} tiles a frame ({:.1} % of the tiles the frustum kept)",
        100.0 * hidden / (hidden + kept).max(1.0)
    )?;
    Ok(())
}

/// The memory line: Ridgeline's own bytes against the budget, and the process's.
fn write_memory(out: &mut String, memory: &MemoryReport) -> Result<()> {
    use std::fmt::Write as _;
    let mb = |b: u64| b as f64 / MB as f64;
    let budget =
        memory.budget_bytes.map_or("no budget".to_string(), |b| format!("of {:.0} MB", mb(b)));
    writeln!(
        out,
        "  memory            own {:.1} MB {budget} (heap peak {:.1}, GPU buffer {:.1}, nodes \
         {:.1}); resident peak {:.1} MB, of which the driver and the rest {:.1} MB",
        mb(memory.own_bytes),
        mb(memory.heap_peak_bytes),
        mb(memory.gpu_buffer_bytes),
        mb(memory.atlas_peak_bytes),
        mb(memory.resident_peak_bytes),
        mb(memory.driver_and_rest_bytes)
    )?;
    Ok(())
}

/// The tau line: the bound asked for and, when it was loosened (by a
/// frame budget, or by tiles drawn from coarser data than their level's
/// while nodes page in or stay out of the memory budget), on how many
/// frames and how far. A loosened bound is never left unsaid.
fn write_tau(out: &mut String, rows: &[Row]) -> Result<()> {
    use std::fmt::Write as _;
    let requested = rows[0].stats.tau_requested_px;
    let loosened = rows.iter().filter(|r| r.stats.tau_loosened()).count();
    let mut bounds: Vec<f64> = rows.iter().map(|r| r.stats.scene.bound_px).collect();
    bounds.sort_by(f64::total_cmp);
    if loosened == 0 {
        writeln!(out, "  tau               {requested} px on every frame (as requested)")?;
        return Ok(());
    }
    let raised = rows.iter().filter(|r| r.stats.scene.tau_px > requested).count();
    let full = rows.iter().filter(|r| r.stats.scene.coarsened > 0).count();
    let fallback = rows.iter().filter(|r| r.stats.scene.fallback_tiles > 0).count();
    writeln!(
        out,
        "  tau               LOOSENED on {loosened} of {} frames: requested {requested} px, \
         achieved p50 {:.2}, max {:.2} px (the bound the display held)",
        rows.len(),
        bounds[bounds.len() / 2],
        bounds[bounds.len() - 1]
    )?;
    writeln!(
        out,
        "                    selected above tau on {raised} frames ({full} for a full tile \
         buffer, the rest for the frame budget); coarser data drawn on {fallback} (nodes paging \
         in, or left out by the memory budget)"
    )?;
    Ok(())
}

/// The valid life's line: split tests made against those a full
/// re-evaluation makes.
fn write_split_tests(out: &mut String, rows: &[Row]) -> Result<()> {
    use std::fmt::Write as _;
    let n = rows.len() as f64;
    let life = |f: &dyn Fn(&ridgeline::lod::life::LifeStats) -> f64| {
        rows.iter().map(|r| f(&r.stats.scene.split_tests)).sum::<f64>() / n
    };
    let full = rows.iter().filter(|r| r.stats.scene.split_tests.full).count();
    writeln!(
        out,
        "  split tests       {:.1} of {:.1} made a frame ({:.1} % mean; valid life), {full} full re-evaluations",
        life(&|l| l.re_evaluated as f64),
        life(&|l| l.candidates as f64),
        100.0 * life(&|l| l.fraction())
    )?;
    Ok(())
}
