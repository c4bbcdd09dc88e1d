//! Import at scale: SRTM1-sized `.hgt` tiles (3601 x 3601, 1") of a
//! deterministic terrain that is continuous across the seams (every
//! height is a function of the post's place on the shared lattice, so
//! adjacent tiles repeat each other's edge rows exactly), in squares of
//! 1, 4 and 16 tiles (`--quick`; 64 more in the full run), each imported
//! by the release `ridgeline` binary as a child process. Reported per row:
//! wall time, level-0 posts per second, the child's peak resident memory
//! (`VmHWM` of `/proc/PID/status`, sampled every 10 ms until it exits),
//! and the bytes the dataset takes per level-0 post (pyramid + map file).
//! The tiles are generated once into `target/bench/import-tiles/`.
//!
//! World rows: a synthetic global grid (`world.rs`) as one GeoTIFF, which
//! the importer decodes strip by strip: at 2.5' (8640 x 4320 posts, both
//! runs: the world path's memory against one tile's, in a minute) and at
//! 30" (43200 x 21600, 933 M posts, 1.9 GB of file, the full run), kept in
//! `target/bench/import-world/`.

#[path = "world.rs"]
mod world;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::support::{self, print_table, Panel, Series};

/// Posts per side of an SRTM1 tile.
const SIDE: usize = 3601;
/// The south-west tile's corner: latitude, longitude.
const FIRST: (i32, i32) = (40, 10);

/// One import's measurements.
#[derive(serde::Serialize)]
pub struct ScaleRow {
    /// What was imported: `N tiles` or `world W x H`.
    input: String,
    /// SRTM1 tiles (0 for a world grid).
    tiles: usize,
    /// Level-0 posts of the mosaic.
    posts: u64,
    seconds: f64,
    posts_per_s: f64,
    peak_rss_mb: f64,
    pyramid_mb: f64,
    meshes_mb: f64,
    bytes_per_post: f64,
    /// Peak over the one-tile row's peak.
    peak_over_one_tile: f64,
}

/// Measures every tile count of the run, then the world grids.
pub fn measure_all(quick: bool) -> Vec<ScaleRow> {
    let counts: &[usize] = if quick { &[1, 4, 16] } else { &[1, 4, 16, 64] };
    let tiles_dir = support::out_dir().join("import-tiles");
    std::fs::create_dir_all(&tiles_dir).expect("create the tile directory");
    let mut rows: Vec<ScaleRow> = Vec::new();
    for &count in counts {
        let paths = tiles(&tiles_dir, count);
        let k = (count as f64).sqrt().round() as u64;
        let posts = (k * (SIDE as u64 - 1) + 1).pow(2);
        rows.push(import(&format!("{count} tiles"), &paths, count, posts));
    }
    let worlds: &[[u32; 2]] = if quick { &[[8640, 4320]] } else { &[[8640, 4320], [43200, 21600]] };
    let world_dir = support::out_dir().join("import-world");
    std::fs::create_dir_all(&world_dir).expect("create the world directory");
    for &[width, height] in worlds {
        let path = world_dir.join(format!("world-{width}x{height}.tif"));
        world::write_world(&path, width, height);
        // The importer adds the closing column (the grid spans 360 degrees).
        let posts = u64::from(width + 1) * u64::from(height);
        rows.push(import(&format!("world {width} x {height}"), &[path], 0, posts));
    }
    let one = rows.first().map_or(1.0, |r| r.peak_rss_mb);
    for row in &mut rows {
        row.peak_over_one_tile = row.peak_rss_mb / one;
    }
    rows
}

/// The tiles of a `k x k` square (`count = k^2`), generated if missing.
fn tiles(dir: &Path, count: usize) -> Vec<PathBuf> {
    let k = (count as f64).sqrt().round() as i32;
    let mut paths = Vec::new();
    for dy in 0..k {
        for dx in 0..k {
            let (lat, lon) = (FIRST.0 + dy, FIRST.1 + dx);
            let path = dir.join(format!("N{lat:02}E{lon:03}.hgt"));
            if std::fs::metadata(&path).map(|m| m.len()).ok() != Some((2 * SIDE * SIDE) as u64) {
                write_tile(&path, dx, dy);
            }
            paths.push(path);
        }
    }
    paths
}

/// Writes tile `(dx, dy)` of the square: rows north first, big-endian.
fn write_tile(path: &Path, dx: i32, dy: i32) {
    let mut bytes = vec![0u8; 2 * SIDE * SIDE];
    bytes.par_chunks_mut(2 * SIDE).enumerate().for_each(|(file_row, row)| {
        let j = (SIDE - 1 - file_row) as i64 + dy as i64 * (SIDE as i64 - 1);
        for (i, out) in row.chunks_exact_mut(2).enumerate() {
            let x = i as i64 + dx as i64 * (SIDE as i64 - 1);
            out.copy_from_slice(&height(x, j).to_be_bytes());
        }
    });
    let temporary = path.with_extension("tmp");
    std::fs::write(&temporary, bytes).expect("write a tile");
    std::fs::rename(&temporary, path).expect("name a tile");
}

/// Height at lattice post `(x, y)` (1" posts): hills, ridges and a hash
/// jitter, so no two neighbours are collinear and the maps are not trivial.
fn height(x: i64, y: i64) -> i16 {
    let (xf, yf) = (x as f64 * 30.0, y as f64 * 30.0);
    let hills = 900.0 * (xf / 21_000.0).sin() * (yf / 17_000.0).cos();
    let ridges = 350.0 * ((xf + 0.6 * yf) / 4_100.0).sin().abs();
    let rough = 40.0 * (xf / 610.0).sin() * (yf / 530.0).sin();
    let mut h =
        (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (y as u64).wrapping_mul(0xC2B2_AE3D);
    h ^= h >> 29;
    let jitter = (h % 7) as f64 - 3.0;
    (1200.0 + hills + ridges + rough + jitter) as i16
}

/// Imports `paths` (`posts` level-0 posts) with the release binary into a
/// fresh cache.
fn import(input: &str, paths: &[PathBuf], tiles: usize, posts: u64) -> ScaleRow {
    let cache = support::out_dir().join("import-scale");
    let _ = std::fs::remove_dir_all(&cache);
    let started = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_ridgeline"))
        .arg("import")
        .args(paths)
        .arg("--out")
        .arg(&cache)
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("run ridgeline import");
    let status_file = format!("/proc/{}/status", child.id());
    let mut peak_kb = 0u64;
    let status = loop {
        if let Some(kb) = std::fs::read_to_string(&status_file).ok().and_then(|s| vm_hwm_kb(&s)) {
            peak_kb = peak_kb.max(kb);
        }
        if let Some(status) = child.try_wait().expect("wait for ridgeline") {
            break status;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let seconds = started.elapsed().as_secs_f64();
    assert!(status.success(), "ridgeline import of {input} failed");
    let size = |name: &str| std::fs::metadata(cache.join(name)).map(|m| m.len()).unwrap_or(0);
    let (pyramid, meshes) = (size("pyramid.rlp"), size("meshes.rlm"));
    let _ = std::fs::remove_dir_all(&cache);
    ScaleRow {
        input: input.to_string(),
        tiles,
        posts,
        seconds,
        posts_per_s: posts as f64 / seconds,
        peak_rss_mb: peak_kb as f64 / 1024.0,
        pyramid_mb: pyramid as f64 / 1e6,
        meshes_mb: meshes as f64 / 1e6,
        bytes_per_post: (pyramid + meshes) as f64 / posts as f64,
        peak_over_one_tile: 1.0,
    }
}

/// The `VmHWM` line of a `/proc/PID/status`, kB.
fn vm_hwm_kb(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Prints the rows and the targets met or not.
pub fn print_scale_rows(rows: &[ScaleRow]) {
    let header = [
        "input",
        "M posts",
        "time s",
        "M posts/s",
        "peak MB",
        "peak/1 tile",
        "pyramid MB",
        "meshes MB",
        "B/post",
    ];
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.input.clone(),
                format!("{:.0}", r.posts as f64 / 1e6),
                format!("{:.1}", r.seconds),
                format!("{:.2}", r.posts_per_s / 1e6),
                format!("{:.0}", r.peak_rss_mb),
                format!("{:.2}", r.peak_over_one_tile),
                format!("{:.0}", r.pyramid_mb),
                format!("{:.0}", r.meshes_mb),
                format!("{:.1}", r.bytes_per_post),
            ]
        })
        .collect();
    let title = "import scale: SRTM1-sized tiles and world grids through `ridgeline import`";
    print_table(title, &header, &cells);
    let met = |ok: bool| if ok { "met" } else { "NOT met" };
    if let Some(r) = rows.iter().find(|r| r.tiles == 16) {
        println!(
            "  targets at 16 tiles: peak {:.0} MB <= 1536 ({}), {:.2} x the 1-tile peak <= 1.25 ({}), \
             {:.2} M posts/s >= 2 ({}), {:.1} B/post <= 10 ({})",
            r.peak_rss_mb,
            met(r.peak_rss_mb <= 1536.0),
            r.peak_over_one_tile,
            met(r.peak_over_one_tile <= 1.25),
            r.posts_per_s / 1e6,
            met(r.posts_per_s >= 2e6),
            r.bytes_per_post,
            met(r.bytes_per_post <= 10.0)
        );
    }
    for r in rows.iter().filter(|r| r.tiles == 0 || r.tiles > 16) {
        println!(
            "  {}: peak {:.0} MB <= 1536 ({}), {:.2} x the 1-tile peak <= 1.25 ({})",
            r.input,
            r.peak_rss_mb,
            met(r.peak_rss_mb <= 1536.0),
            r.peak_over_one_tile,
            met(r.peak_over_one_tile <= 1.25)
        );
    }
}

/// Peak memory and throughput against the input's posts.
pub fn scale_panel(rows: &[ScaleRow]) -> Panel {
    let series = |label: &str, value: fn(&ScaleRow) -> f64| Series {
        label: label.to_string(),
        points: rows.iter().map(|r| (r.posts as f64 / 1e6, value(r))).collect(),
    };
    Panel {
        title: "import scale (release binary, child process)".into(),
        x_label: "level-0 posts (millions)".into(),
        y_label: "peak MB, M posts/s x 100, B/post x 100".into(),
        log_x: true,
        log_y: true,
        series: vec![
            series("peak resident MB", |r| r.peak_rss_mb),
            series("M posts/s x 100", |r| r.posts_per_s / 1e4),
            series("bytes per post x 100", |r| r.bytes_per_post * 100.0),
        ],
    }
}
