//! `ridgeline fly --input KIND:[ADDR:]PORT`: the display fed live over UDP.
//! Headless it draws `--frames` at `--fps` from the stream as it comes; in
//! a window it runs until the window is closed. Each frame either shows
//! the terrain at the pose extrapolated to the frame's time, with the
//! reference symbols, or (stale or invalid data) withdraws the terrain and
//! shows the failure flag. The summary and `stats.json` count the
//! datagrams taken and ignored by reason, the time spent stale and the
//! frame latency.

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use glam::DVec3;
use ridgeline::display::Display;
use ridgeline::input::place::DisplayFrame;
use ridgeline::input::receiver::ReceiverOptions;
use ridgeline::input::{Counts, Ignored, InputSpec, LiveInput, LiveView};
use ridgeline::pipeline::FrameStats;
use ridgeline::symbology::{flag, reference_symbols, SymbolMesh};

use super::fly_args::FlyArgs;
use super::frames::{wall_time, FrameRecord, InputFrame, Row};

/// The live input and what a frame needs to draw from it.
pub struct Live {
    input: LiveInput,
    frame: DisplayFrame,
    stale: Duration,
    symbols: SymbolMesh,
    flag: SymbolMesh,
    symbology: bool,
    fov: f64,
    size: [u32; 2],
    address: String,
}

impl Live {
    /// Starts listening as `args` ask, for a dataset placed by `frame`.
    pub fn start(args: &FlyArgs, spec: &InputSpec, frame: DisplayFrame) -> Result<Live> {
        let options = ReceiverOptions {
            stale: Duration::from_millis(args.stale_ms),
            geoid_m: args.geoid_m,
            record: args.record.clone(),
            xplane_request: args.xplane_host,
        };
        let input = LiveInput::start(spec, &options)?;
        let address = input.local_addr().to_string();
        Ok(Live {
            input,
            frame,
            stale: options.stale,
            symbols: SymbolMesh::new(),
            flag: SymbolMesh::new(),
            symbology: args.symbology.on(),
            fov: args.view.fov,
            size: [args.view.size.x, args.view.size.y],
            address,
        })
    }

    /// The address listened on.
    pub fn address(&self) -> &str {
        &self.address
    }

    /// Draws one frame from the newest state: the terrain at the pose
    /// extrapolated to now, or the failure flag.
    pub fn draw(&mut self, display: &mut Display) -> Result<(FrameStats, FrameRecord)> {
        let state = self.input.snapshot();
        let now = Instant::now();
        let view = state.view(now, self.stale);
        let (stats, pose) = match view {
            LiveView::Live { pose, velocity_ned, .. } => {
                let camera = self.frame.pose(&pose).camera(self.fov, self.size);
                let stats = if self.symbology {
                    let velocity = velocity_ned.map(|v| self.frame.velocity(v));
                    reference_symbols(&mut self.symbols, &camera, velocity);
                    display.frame_with_symbols(&camera, &self.symbols)?
                } else {
                    display.frame(&camera)?
                };
                (stats, Some(pose))
            }
            LiveView::Stale { reason, .. } => {
                flag::failure_flag(&mut self.flag, self.size, reason.flag_text());
                (display.withdrawn_frame(&self.flag)?, None)
            }
        };
        let drawn = Instant::now();
        let (stale, reason, age) = match view {
            LiveView::Live { age_s, .. } => (false, None, Some(age_s)),
            LiveView::Stale { reason, age_s } => (true, Some(reason), age_s),
        };
        let input = InputFrame {
            source: self.input.kind().name(),
            age_ms: age.map(|s| s * 1e3),
            stale,
            reason,
            latency_ms: state
                .newest()
                .map(|at| drawn.saturating_duration_since(at).as_secs_f64() * 1e3),
            taken: state.taken,
        };
        Ok((stats, FrameRecord { pose, input: Some(input), wall_time: wall_time() }))
    }

    /// Stops listening: the datagrams counted and the rows recorded.
    pub fn stop(self) -> Result<(Counts, u64)> {
        let counts = self.input.counts();
        let recorded = self.input.stop()?;
        Ok((counts, recorded))
    }
}

/// The dataset's geographic frame, or why live input cannot use it.
pub fn display_frame(terrain: &super::terrain::Terrain) -> Result<DisplayFrame> {
    let super::terrain::Ground::Pyramid(pyramid) = &terrain.ground else {
        bail!("--input: the procedural earth has no latitude and longitude; use a real dataset")
    };
    Ok(DisplayFrame::new(&pyramid.info().georef, pyramid.info().layout.posts)?)
}

/// Headless: `--frames` frames at `--fps`, each drawn from the state at
/// its time; snapshots as a path run writes them.
pub fn fly_headless(args: &FlyArgs, display: &mut Display, live: &mut Live) -> Result<Vec<Row>> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create the output folder", args.out.display()))?;
    let frames = args.frames.max(1);
    let every = (frames / args.snapshots.max(1)).max(1);
    let interval = Duration::from_secs_f64(1.0 / args.fps);
    let start = Instant::now();
    let mut rows = Vec::with_capacity(frames as usize);
    for k in 0..frames {
        let due = start + interval * k;
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let t = start.elapsed().as_secs_f64();
        let (stats, record) = live.draw(display).with_context(|| format!("frame {k}"))?;
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

/// In a window: until it is closed, at most `--fps` frames a second.
pub fn fly_window(args: &FlyArgs, display: &mut Display, live: &mut Live) -> Result<Vec<Row>> {
    let interval = Duration::from_secs_f64(1.0 / args.fps);
    let start = Instant::now();
    let mut rows = Vec::new();
    loop {
        let began = Instant::now();
        let t = start.elapsed().as_secs_f64();
        let (stats, record) = live.draw(display)?;
        display.present()?;
        rows.push(Row { frame: rows.len() as u32, t, stats, record });
        let wait = interval.saturating_sub(began.elapsed());
        if display.pump_events(Some(wait)).close_requested {
            return Ok(rows);
        }
    }
}

/// What the run's input did, for the summary and `stats.json`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct InputReport {
    /// The protocol.
    pub source: &'static str,
    /// The address listened on.
    pub address: String,
    /// `--stale-ms`.
    pub stale_ms: u64,
    /// Datagrams taken and ignored.
    pub datagrams: Counts,
    /// Frames drawn with the terrain withdrawn.
    pub stale_frames: usize,
    /// Time spent stale, seconds (each stale frame until the next frame).
    pub stale_s: f64,
    /// Frame drawn minus newest sample received, ms: p50, p99, max over
    /// the frames drawn from live data.
    pub latency_ms: Option<[f64; 3]>,
    /// One frame interval plus 5 ms, ms: the latency bound the p99 is held to.
    pub latency_bound_ms: f64,
    /// Rows written by `--record`.
    pub recorded_rows: u64,
}

impl InputReport {
    /// The report of a run of `rows` whose input counted `datagrams`.
    pub fn new(
        args: &FlyArgs,
        address: &str,
        rows: &[Row],
        datagrams: Counts,
        recorded_rows: u64,
    ) -> InputReport {
        let source = rows.iter().find_map(|r| r.record.input).map_or("", |i| i.source);
        let stale = |r: &Row| r.record.input.is_some_and(|i| i.stale);
        let stale_s = rows
            .windows(2)
            .filter(|pair| stale(&pair[0]))
            .map(|pair| pair[1].t - pair[0].t)
            .sum::<f64>()
            + rows.last().filter(|r| stale(r)).map_or(0.0, |_| 1.0 / args.fps);
        // Frames drawn from live data only: a withdrawn frame shows no sample.
        let mut latency: Vec<f64> = rows
            .iter()
            .filter_map(|r| r.record.input.filter(|i| !i.stale).and_then(|i| i.latency_ms))
            .collect();
        latency.sort_by(f64::total_cmp);
        let pick = |q: f64| latency[((latency.len() - 1) as f64 * q).round() as usize];
        InputReport {
            source,
            address: address.to_owned(),
            stale_ms: args.stale_ms,
            datagrams,
            stale_frames: rows.iter().filter(|r| stale(r)).count(),
            stale_s,
            latency_ms: (!latency.is_empty()).then(|| [pick(0.5), pick(0.99), pick(1.0)]),
            latency_bound_ms: 1e3 / args.fps + 5.0,
            recorded_rows,
        }
    }

    /// The summary's input lines.
    pub fn write(&self, out: &mut String, frames: usize) -> std::fmt::Result {
        use std::fmt::Write as _;
        let d = &self.datagrams;
        let reasons: Vec<String> = Ignored::ALL
            .iter()
            .filter(|&&r| d.ignored_for(r) > 0)
            .map(|&r| format!("{} {}", r.name(), d.ignored_for(r)))
            .collect();
        let reasons =
            if reasons.is_empty() { String::new() } else { format!(" ({})", reasons.join(", ")) };
        writeln!(
            out,
            "  input             {} on {}: {} datagrams taken, {} ignored{reasons}",
            self.source,
            self.address,
            d.taken,
            d.ignored_total()
        )?;
        writeln!(
            out,
            "  stale             {} of {frames} frames, {:.2} s (terrain withdrawn after {} ms without valid data)",
            self.stale_frames, self.stale_s, self.stale_ms
        )?;
        if let Some([p50, p99, max]) = self.latency_ms {
            let verdict = if p99 <= self.latency_bound_ms { "within" } else { "OVER" };
            writeln!(
                out,
                "  latency           frame drawn - newest sample: p50 {p50:.1} ms, p99 {p99:.1} ms, max {max:.1} ms ({verdict} {:.1} ms)",
                self.latency_bound_ms
            )?;
        }
        if self.recorded_rows > 0 {
            writeln!(out, "  recorded          {} poses", self.recorded_rows)?;
        }
        Ok(())
    }
}

/// Refuses live options that cannot work together.
pub fn check(args: &FlyArgs) -> Result<()> {
    if args.input.is_none() {
        return Ok(());
    }
    if args.view.path.is_some() {
        bail!("--input and --path: fly live or along a path, not both");
    }
    if !(1..=60_000).contains(&args.stale_ms) {
        bail!("--stale-ms {} must be between 1 and 60000", args.stale_ms);
    }
    if !(args.fps.is_finite() && args.fps > 0.0 && args.fps <= 1000.0) {
        bail!("--fps {} must be a rate above 0 and at most 1000 frames a second", args.fps);
    }
    if !(args.geoid_m.is_finite() && args.geoid_m.abs() <= 200.0) {
        bail!("--geoid-m {} must be within 200 m (the geoid departs from the ellipsoid by 106 m at most)", args.geoid_m);
    }
    if let Some(record) = &args.record {
        check_record_path(record)?;
    }
    Ok(())
}

fn check_record_path(record: &Path) -> Result<()> {
    let parent = record.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !parent.is_dir() {
        bail!("--record {}: {} is not a folder", record.display(), parent.display());
    }
    Ok(())
}

/// The travel a frame may make, metres, for the valid life: `--max-speed`,
/// else the fastest aircraft a display draws live (Mach 1 at sea level).
pub fn max_speed(args: &FlyArgs) -> f64 {
    args.view.max_speed.unwrap_or(LIVE_MAX_SPEED_MPS)
}

/// The speed a live run's valid life assumes without `--max-speed`, m/s.
pub const LIVE_MAX_SPEED_MPS: f64 = 340.0;

/// The velocity of a path at `t`, by a central difference (display frame, m/s).
pub fn path_velocity(path: &ridgeline::flight::FlightPath, t: f64) -> Option<DVec3> {
    let h = 0.05;
    let (a, b) = (t - h, t + h);
    if a < path.start_time() || b > path.end_time() {
        return None;
    }
    Some((path.sample(b).position - path.sample(a).position) / (b - a))
}
