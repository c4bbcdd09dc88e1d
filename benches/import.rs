//! Import throughput: building the node pyramid from a grid, writing it
//! atomically and opening (verifying) it, each as megabytes of input heights
//! per second and as a ratio to reading the same bytes raw from a file in the
//! same run (the machine is shared and noisy; the ratio is what compares).
//!
//! A second table measures opening against file size: `Pyramid::open` reads
//! only the fixed header and the level table (format 3: no node table entry
//! is read until its node is), so its time should not grow with the file; the first
//! page-in of a node and a full `verify` are shown beside it. The pyramids,
//! 0.4 MB to 1.06 GB (fewer sizes with `--quick`), are built once from the
//! synthetic terrain into `target/bench/open-scale/` (about 20 s and 3 GB of
//! memory for the largest) and reused by later runs; delete the folder to
//! rebuild or to free its 1.5 GB. Timings are with the file in the page
//! cache, best of the repeats.
//!
//! A third table imports SRTM1-sized tiles (1, 4, 16; 64 in the full run)
//! with the release binary as a child process: time, posts per second,
//! peak resident memory, bytes per level-0 post (see `import_scale/`).
//!
//! `cargo bench --bench import [-- --quick] [--scale-only]` prints the
//! tables (`--scale-only`: the third alone, e.g. for the full run's 64
//! tiles and 30" world without the rest) and writes
//! `target/bench/import.json` and `target/bench/import.svg`, and the scale
//! table to `target/bench/import_scale.json` and `import_scale.svg`.

#[path = "import_scale/mod.rs"]
mod scale;
mod support;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use ridgeline::node::{NodeData, NodeId, NodeSource};
use ridgeline::pyramid::{self, BuildOptions, Pyramid, Silent};
use support::{print_table, BenchArgs, Panel, Series};

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

/// Opening one pyramid, best of the repeats.
#[derive(serde::Serialize)]
struct OpenRow {
    /// Synthetic grid side.
    size: u32,
    pyramid_mb: f64,
    nodes: u64,
    /// Milliseconds to open (map, check the header and its checksum).
    open_ms: f64,
    /// Milliseconds to read (and check) one level-0 node right after opening.
    first_page_in_ms: f64,
    /// Milliseconds to check every node, what opening cost before.
    verify_ms: f64,
}

fn main() {
    let quick = BenchArgs::parse().quick;
    let scale_rows = scale::measure_all(quick);
    scale::print_scale_rows(&scale_rows);
    let threads = rayon::current_num_threads();
    let scale_report = serde_json::json!({
        "bench": "import_scale", "quick": quick, "threads": threads, "rows": scale_rows,
    });
    let json = support::write_json("import_scale", &scale_report);
    let svg = support::write_svg("import_scale", &[scale::scale_panel(&scale_rows)]);
    println!("\nwrote {} and {}\n", json.display(), svg.display());
    if std::env::args().any(|a| a == "--scale-only") {
        return;
    }
    let (sizes, repeats): (&[u32], usize) =
        if quick { (&[1024, 2048], 2) } else { (&[1024, 2048, 4096, 8192], 3) };
    let scratch = support::out_dir().join("import-scratch");
    std::fs::create_dir_all(&scratch).expect("create the scratch directory");
    let rows: Vec<Row> = sizes.iter().map(|&size| measure(size, repeats, &scratch)).collect();
    std::fs::remove_dir_all(&scratch).ok();
    let title = format!(
        "import, {threads} threads, best of {repeats} interleaved repeats{}",
        if quick { " (quick)" } else { "" }
    );
    print_rows(&title, &rows);
    // 13056 = 204 nodes of 64 cells: a 1.06 GB pyramid.
    let (open_sizes, open_repeats): (&[u32], usize) =
        if quick { (&[256, 4096, 13056], 3) } else { (&[256, 1024, 4096, 8192, 13056], 5) };
    let open_dir = support::out_dir().join("open-scale");
    let open_rows: Vec<OpenRow> =
        open_sizes.iter().map(|&size| measure_open(size, open_repeats, &open_dir)).collect();
    print_open_rows(quick, open_repeats, &open_rows);
    let report = serde_json::json!({
        "bench": "import",
        "quick": quick,
        "threads": threads,
        "rows": rows,
        "open_scale": open_rows,
    });
    let json = support::write_json("import", &report);
    let mut plots = Vec::from(panels(&rows));
    plots.push(open_panel(&open_rows));
    let svg = support::write_svg("import", &plots);
    println!("\nwrote {} and {}", json.display(), svg.display());
}

fn measure(size: u32, repeats: usize, scratch: &Path) -> Row {
    let grid = pyramid::synthetic_grid(size).expect("bench sizes are valid");
    let input_bytes = grid.heights.len() * 4;
    let raw_path = scratch.join(format!("raw-{size}.f32"));
    std::fs::write(&raw_path, bytemuck::cast_slice::<f32, u8>(&grid.heights))
        .expect("write raw input");
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
        let (build, built) = timed_value(|| {
            pyramid::build(&grid, &BuildOptions::default(), &Silent).expect("build")
        });
        let write = timed(|| pyramid::write_atomic(&built, &path, &Silent).expect("write"));
        let open = timed(|| {
            let pyramid = Pyramid::open(&path).expect("open");
            pyramid.verify().expect("verify");
        });
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

/// The pyramid of the synthetic grid of side `size` under `dir`, built and
/// written unless an earlier run left it there.
fn scale_pyramid(size: u32, dir: &Path) -> PathBuf {
    let cache = dir.join(format!("size-{size}"));
    let path = cache.join(pyramid::FILE_NAME);
    if Pyramid::open(&path).is_ok() {
        return path;
    }
    std::fs::create_dir_all(&cache).expect("open-scale dir");
    eprintln!("building the {size} x {size} pyramid for the open-time table (kept for next time)");
    let grid = pyramid::synthetic_grid(size).expect("bench sizes are valid");
    let built = pyramid::build(&grid, &BuildOptions::default(), &Silent).expect("build");
    drop(grid);
    pyramid::write_atomic(&built, &path, &Silent).expect("write");
    path
}

fn measure_open(size: u32, repeats: usize, dir: &Path) -> OpenRow {
    let path = scale_pyramid(size, dir);
    let mut best = [Duration::MAX; 3];
    let mut nodes = 0;
    for _ in 0..repeats {
        let (open, pyramid) = timed_value(|| Pyramid::open(&path).expect("open"));
        let layout = *pyramid.layout();
        nodes = layout.node_count();
        let [nx, ny] = layout.nodes_at(0);
        let mut node = NodeData::with_capacity(&layout);
        let page_in = timed(|| {
            pyramid.read_node(NodeId::new(0, nx / 2, ny / 2), &mut node).expect("read");
        });
        let verify = timed(|| pyramid.verify().expect("verify"));
        for (best, now) in best.iter_mut().zip([open, page_in, verify]) {
            *best = (*best).min(now);
        }
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    OpenRow {
        size,
        pyramid_mb: std::fs::metadata(&path).expect("pyramid size").len() as f64 / 1e6,
        nodes,
        open_ms: ms(best[0]),
        first_page_in_ms: ms(best[1]),
        verify_ms: ms(best[2]),
    }
}

fn print_open_rows(quick: bool, repeats: usize, rows: &[OpenRow]) {
    let title = format!(
        "open time against file size, best of {repeats}, file in the page cache{}",
        if quick { " (quick: three of the sizes)" } else { "" }
    );
    let header = ["size", "pyramid MB", "nodes", "open ms", "first page-in ms", "verify ms"];
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.size.to_string(),
                format!("{:.1}", r.pyramid_mb),
                r.nodes.to_string(),
                format!("{:.3}", r.open_ms),
                format!("{:.3}", r.first_page_in_ms),
                format!("{:.1}", r.verify_ms),
            ]
        })
        .collect();
    print_table(&title, &header, &cells);
    println!("  open checks the fixed header and level table only; each node's entry and record are checked when paged in; verify checks them all (ridgeline info)");
}

/// Open, first page-in and full verification time against file size.
fn open_panel(rows: &[OpenRow]) -> Panel {
    let series = |label: &str, value: fn(&OpenRow) -> f64| Series {
        label: label.to_string(),
        points: rows.iter().map(|r| (r.pyramid_mb, value(r))).collect(),
    };
    Panel {
        title: "opening against file size".into(),
        x_label: "pyramid file (MB)".into(),
        y_label: "milliseconds".into(),
        log_x: true,
        log_y: true,
        series: vec![
            series("open", |r| r.open_ms),
            series("first page-in", |r| r.first_page_in_ms),
            series("verify every node", |r| r.verify_ms),
        ],
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

fn print_rows(title: &str, rows: &[Row]) {
    let header = [
        "size",
        "input MB",
        "pyramid MB",
        "raw MB/s",
        "build MB/s",
        "write MB/s",
        "open MB/s",
        "build/raw",
        "write/raw",
        "import/raw",
        "open/raw",
    ];
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let mut cells = vec![
                r.size.to_string(),
                format!("{:.1}", r.input_mb),
                format!("{:.1}", r.pyramid_mb),
            ];
            let speeds = [r.raw_read_mb_s, r.build_mb_s, r.write_mb_s, r.open_verify_mb_s];
            cells.extend(speeds.iter().map(|v| format!("{v:.0}")));
            let ratios =
                [r.build_over_raw, r.write_over_raw, r.import_over_raw, r.open_verify_over_raw];
            cells.extend(ratios.iter().map(|v| format!("{v:.1}")));
            cells
        })
        .collect();
    print_table(title, &header, &cells);
    println!("  MB/s are megabytes of input heights per second; x/raw is the time of x over reading the input raw");
}

/// Throughput, and time over the raw read, against input size.
fn panels(rows: &[Row]) -> [Panel; 2] {
    let series = |label: &str, value: fn(&Row) -> f64| Series {
        label: label.to_string(),
        points: rows.iter().map(|r| (r.input_mb, value(r))).collect(),
    };
    [
        Panel {
            title: "import throughput".into(),
            x_label: "input heights (MB)".into(),
            y_label: "MB of input per second".into(),
            log_x: true,
            log_y: true,
            series: vec![
                series("raw read", |r| r.raw_read_mb_s),
                series("build", |r| r.build_mb_s),
                series("write (with fsync)", |r| r.write_mb_s),
                series("open + verify", |r| r.open_verify_mb_s),
            ],
        },
        Panel {
            title: "time relative to reading the input raw".into(),
            x_label: "input heights (MB)".into(),
            y_label: "time / raw read time".into(),
            log_x: true,
            log_y: true,
            series: vec![
                series("build", |r| r.build_over_raw),
                series("build + write", |r| r.import_over_raw),
                series("open + verify", |r| r.open_verify_over_raw),
            ],
        },
    ]
}
