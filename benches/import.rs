//! Import throughput: building the node pyramid from a grid, writing it
//! atomically and opening (verifying) it, each as megabytes of input heights
//! per second and as a ratio to reading the same bytes raw from a file in the
//! same run (the machine is shared and noisy; the ratio is what compares).
//!
//! `cargo bench --bench import [-- --quick]` prints a table and writes
//! `target/bench/import.json` and `target/bench/import.svg`.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use plotters::prelude::*;
use ridgeline::pyramid::{self, BuildOptions, Pyramid, Silent};

/// One grid size's measurements, best of the repeats.
#[derive(serde::Serialize)]
struct Row {
    size: u32,
    input_mb: f64,
    pyramid_mb: f64,
    /// Seconds.
    raw_read_s: f64,
    build_s: f64,
    write_s: f64,
    open_verify_s: f64,
    /// Input MB per second.
    raw_read_mb_s: f64,
    build_mb_s: f64,
    write_mb_s: f64,
    open_verify_mb_s: f64,
    /// Time relative to reading the input bytes raw (1 = as fast as reading).
    build_over_raw: f64,
    write_over_raw: f64,
    import_over_raw: f64,
    open_verify_over_raw: f64,
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (sizes, repeats): (&[u32], usize) = if quick { (&[1024, 2048], 2) } else { (&[1024, 2048, 4096, 8192], 3) };
    let out_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench");
    let scratch = out_dir.join("import-scratch");
    std::fs::create_dir_all(&scratch).expect("create target/bench");
    println!("import throughput, {} threads, best of {repeats} interleaved repeats{}", rayon::current_num_threads(), if quick { " (quick)" } else { "" });
    let rows: Vec<Row> = sizes.iter().map(|&size| measure(size, repeats, &scratch)).collect();
    print_table(&rows);
    let json = serde_json::json!({ "bench": "import", "quick": quick, "threads": rayon::current_num_threads(), "rows": rows });
    std::fs::write(out_dir.join("import.json"), serde_json::to_string_pretty(&json).expect("json")).expect("write json");
    plot(&rows, &out_dir.join("import.svg")).expect("write svg");
    std::fs::remove_dir_all(&scratch).ok();
    println!("wrote {0}/import.json and {0}/import.svg", out_dir.display());
}

fn measure(size: u32, repeats: usize, scratch: &Path) -> Row {
    let grid = pyramid::synthetic_grid(size).expect("bench sizes are valid");
    let input_bytes = grid.heights.len() * 4;
    let raw_path = scratch.join(format!("raw-{size}.f32"));
    std::fs::write(&raw_path, bytemuck::cast_slice::<f32, u8>(&grid.heights)).expect("write raw input");
    let cache = scratch.join(format!("cache-{size}"));
    std::fs::create_dir_all(&cache).expect("cache dir");
    let path: PathBuf = cache.join(pyramid::FILE_NAME);
    // Each repeat times every step back to back, so the raw read and the
    // steps it is compared with see the same load on the shared machine.
    // The raw read fills a buffer whose pages are already mapped, so it
    // measures reading the bytes, not the kernel handing out fresh pages.
    let mut raw = vec![1u8; input_bytes];
    let mut times = [Duration::MAX; 4];
    for _ in 0..repeats {
        let raw_read = timed(|| {
            let mut file = std::fs::File::open(&raw_path).expect("open raw");
            file.read_exact(&mut raw).expect("read raw");
        });
        let (build, built) = timed_value(|| pyramid::build(&grid, &BuildOptions::default(), &Silent).expect("build"));
        let write = timed(|| pyramid::write_atomic(&built, &path, &Silent).expect("write"));
        let open = timed(|| drop(Pyramid::open(&path).expect("open")));
        for (best, now) in times.iter_mut().zip([raw_read, build, write, open]) {
            *best = (*best).min(now);
        }
    }
    let [raw_read, build, write, open] = times;
    let pyramid_bytes = std::fs::metadata(&path).expect("pyramid size").len();
    let mb = input_bytes as f64 / 1e6;
    let secs = |d: Duration| d.as_secs_f64();
    Row {
        size,
        input_mb: mb,
        pyramid_mb: pyramid_bytes as f64 / 1e6,
        raw_read_s: secs(raw_read),
        build_s: secs(build),
        write_s: secs(write),
        open_verify_s: secs(open),
        raw_read_mb_s: mb / secs(raw_read),
        build_mb_s: mb / secs(build),
        write_mb_s: mb / secs(write),
        open_verify_mb_s: mb / secs(open),
        build_over_raw: secs(build) / secs(raw_read),
        write_over_raw: secs(write) / secs(raw_read),
        import_over_raw: (secs(build) + secs(write)) / secs(raw_read),
        open_verify_over_raw: secs(open) / secs(raw_read),
    }
}

/// How long `f` takes.
fn timed(f: impl FnOnce()) -> Duration {
    timed_value(f).0
}

/// How long `f` takes, and what it returns.
fn timed_value<T>(f: impl FnOnce() -> T) -> (Duration, T) {
    let start = Instant::now();
    let value = f();
    (start.elapsed(), value)
}

fn print_table(rows: &[Row]) {
    println!(
        "{:>6} {:>9} {:>10} | {:>9} {:>9} {:>9} {:>9} | {:>7} {:>7} {:>7} {:>7}",
        "size", "input MB", "pyramid MB", "raw MB/s", "build", "write", "open", "build/", "write/", "import/", "open/"
    );
    println!("{:>6} {:>9} {:>10} | {:>39} | {:>31}", "", "", "", "MB of input heights per second", "time over raw read");
    for r in rows {
        println!(
            "{:>6} {:>9.1} {:>10.1} | {:>9.0} {:>9.0} {:>9.0} {:>9.0} | {:>7.1} {:>7.1} {:>7.1} {:>7.1}",
            r.size,
            r.input_mb,
            r.pyramid_mb,
            r.raw_read_mb_s,
            r.build_mb_s,
            r.write_mb_s,
            r.open_verify_mb_s,
            r.build_over_raw,
            r.write_over_raw,
            r.import_over_raw,
            r.open_verify_over_raw
        );
    }
}

/// Time over raw read against input size, one line per step.
fn plot(rows: &[Row], path: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (800, 480)).into_drawing_area();
    root.fill(&WHITE)?;
    let x_max = rows.iter().map(|r| r.input_mb).fold(1.0, f64::max) * 1.1;
    type Series = (&'static str, fn(&Row) -> f64, RGBColor);
    let series: [Series; 4] = [
        ("build / raw read", |r| r.build_over_raw, BLUE),
        ("write / raw read", |r| r.write_over_raw, RED),
        ("build + write / raw read", |r| r.import_over_raw, BLACK),
        ("open + verify / raw read", |r| r.open_verify_over_raw, GREEN),
    ];
    let y_max = rows.iter().flat_map(|r| series.iter().map(move |s| (s.1)(r))).fold(1.0, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption("pyramid import time relative to reading the input raw", ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..x_max, 0.0..y_max)?;
    chart.configure_mesh().x_desc("input heights (MB)").y_desc("time / raw read time").draw()?;
    for (name, value, colour) in series {
        let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.input_mb, value(r))).collect();
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        chart.draw_series(points.into_iter().map(|p| Circle::new(p, 3, colour.filled())))?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    root.present()?;
    Ok(())
}
