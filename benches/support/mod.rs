//! What every Ridgeline benchmark shares: the `--quick` flag, readable tables,
//! the JSON report and the SVG plot under `target/bench/`.
#![allow(dead_code)] // each bench uses its own subset

pub mod rtin_floor;

use plotters::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Command-line flags common to the benches (`cargo bench --bench NAME -- --quick`).
pub struct BenchArgs {
    pub quick: bool,
}

impl BenchArgs {
    pub fn parse() -> Self {
        // cargo passes `--bench`; anything else we do not know is ignored.
        BenchArgs { quick: std::env::args().any(|a| a == "--quick") }
    }
}

/// `target/bench`, created on demand (respects CARGO_TARGET_DIR).
pub fn out_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"));
    let dir = target.join("bench");
    std::fs::create_dir_all(&dir).expect("create target/bench");
    dir
}

/// Prints a table with a title, right-aligned columns.
pub fn print_table(title: &str, header: &[&str], rows: &[Vec<String>]) {
    let mut width: Vec<usize> = header.iter().map(|h| h.len()).collect();
    for row in rows {
        for (w, cell) in width.iter_mut().zip(row) {
            *w = (*w).max(cell.len());
        }
    }
    println!("\n{title}");
    let line = |cells: Vec<&str>| {
        let padded: Vec<String> =
            cells.iter().zip(&width).map(|(c, w)| format!("{c:>w$}", w = *w)).collect();
        println!("  {}", padded.join("  "));
    };
    line(header.to_vec());
    println!("  {}", width.iter().map(|w| "-".repeat(*w)).collect::<Vec<_>>().join("  "));
    for row in rows {
        line(row.iter().map(String::as_str).collect());
    }
}

/// Writes `target/bench/NAME.json`.
pub fn write_json(name: &str, value: &serde_json::Value) -> PathBuf {
    let path = out_dir().join(format!("{name}.json"));
    let text = serde_json::to_string_pretty(value).expect("serialise report");
    std::fs::write(&path, text).expect("write bench JSON");
    path
}

/// One line of points in a plot.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// One panel of a plot: a title, axis labels, log scales and its series.
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
}

/// Draws the panels side by side into `target/bench/NAME.svg`.
pub fn write_svg(name: &str, panels: &[Panel]) -> PathBuf {
    let path = out_dir().join(format!("{name}.svg"));
    let width = 560 * panels.len() as u32;
    {
        let root = SVGBackend::new(&path, (width, 440)).into_drawing_area();
        root.fill(&WHITE).expect("svg background");
        let areas = root.split_evenly((1, panels.len()));
        for (area, panel) in areas.iter().zip(panels) {
            draw_panel(area, panel);
        }
        root.present().expect("write svg");
    }
    path
}

fn bounds(panel: &Panel, axis: impl Fn(&(f64, f64)) -> f64, log: bool) -> (f64, f64) {
    let values = panel.series.iter().flat_map(|s| s.points.iter().map(&axis));
    let (lo, hi) = values.fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return (1.0, 10.0);
    }
    if log {
        (lo.max(1e-9) / 1.5, hi * 1.5)
    } else {
        let pad = ((hi - lo) * 0.08).max(1e-9);
        (lo - pad, hi + pad)
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, plotters::coord::Shift>, panel: &Panel) {
    let (x0, x1) = bounds(panel, |p| p.0, panel.log_x);
    let (y0, y1) = bounds(panel, |p| p.1, panel.log_y);
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(&panel.title, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(&panel.x_label)
                .y_desc(&panel.y_label)
                .draw()
                .expect("mesh");
            for (i, series) in panel.series.iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                chart
                    .draw_series(LineSeries::new(
                        series.points.iter().copied(),
                        color.stroke_width(2),
                    ))
                    .expect("series")
                    .label(&series.label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
                chart
                    .draw_series(series.points.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .expect("points");
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .expect("legend");
        }};
    }
    match (panel.log_x, panel.log_y) {
        (false, false) => finish!(builder.build_cartesian_2d(x0..x1, y0..y1).expect("axes")),
        (true, false) => {
            finish!(builder.build_cartesian_2d((x0..x1).log_scale(), y0..y1).expect("axes"))
        }
        (false, true) => {
            finish!(builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale()).expect("axes"))
        }
        (true, true) => finish!(builder
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .expect("axes")),
    }
}

/// Median of `runs` timings of `f`, in seconds.
pub fn median_secs(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Mean and sample standard deviation.
pub fn mean_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

/// CPU time every thread of this process has run so far, nanoseconds
/// (the first field of each `/proc/self/task/*/schedstat`); `None` where
/// the kernel does not keep it. On llvmpipe the GPU's work is the
/// process's own threads, so a frame's CPU time is what it cost, whatever
/// else the shared machine ran meanwhile (which wall time also counts).
/// Threads that have exited are not counted.
pub fn process_cpu_ns() -> Option<u64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let path = task.ok()?.path().join("schedstat");
        let Ok(text) = std::fs::read_to_string(path) else { continue };
        total += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total)
}
