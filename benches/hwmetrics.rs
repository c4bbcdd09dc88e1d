//! Polok's hardware-metric benchmark ("Hardware Metrics", Table 1) on the
//! local GL driver: 32 x 32 tiles of 64 x 64 vertices drawn in one call as
//! the baseline, then each per-tile operation's cost as the rise in mean
//! frame time, judged against the baseline's standard deviation, beside the
//! paper's Tegra 2 column. The tile-upload rows pick the allocator's transfer
//! cap: the smallest run beyond which longer runs gain nothing significant,
//! on this driver and in the paper's column, whichever is larger; the local
//! pick counts only where run length moves the upload time by more than 1 %
//! of the frame (on llvmpipe it does not, and the paper's column decides).
//!
//! On a software rasteriser the 800 x 600 frame is raster-bound (the paper's
//! 2 x 2 check fails), so every row is also measured at 2 x 2; and the frame
//! noise of a shared machine swamps per-tile costs of microseconds, so the
//! time inside glBufferSubData is timed directly as well.
//!
//! `cargo bench --bench hwmetrics [-- --quick] [--frames N] [--pairs N] [--side N]`
//! prints the tables and writes `target/bench/hwmetrics.json` and `.svg`.

mod support;

#[path = "hwmetrics/measure.rs"]
mod measure;
#[path = "hwmetrics/scene.rs"]
mod scene;

use glam::UVec2;
use measure::{Pairs, RunLength};
use ridgeline::gl::{ContextRequest, GlBackend, GlContext, GlesVersion};
use scene::{Operation, Scene, GRID, TILE_BYTES};
use serde_json::{json, Value};
use support::{mean_sd, print_table, BenchArgs, Panel, Series};

/// The paper's viewport.
const VIEWPORT: UVec2 = UVec2::new(800, 600);
/// Upload run lengths of Table 1, in tiles.
const BATCHES: [u32; 11] = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024];
/// Table 1 (NVIDIA Tegra 2), ms per frame of 1024 tiles.
const PAPER_OPERATIONS: [(Operation, &str, Option<f64>); 6] = [
    (Operation::SplitDraws, "one draw per tile, no change", None),
    (Operation::VertexBufferSwap, "Vertex buffer swap", Some(3.52)),
    (Operation::IndexBufferSwap, "Index buffer swap", Some(4.01)),
    (Operation::UniformUpdate, "Shader reconfig (uniform)", Some(2.90)),
    (Operation::ConstantAttribute, "Vertex attrib reconfig (constant)", Some(7.54)),
    (Operation::AttributePointer, "Vertex attrib pointer reconfig", Some(23.38)),
];
const PAPER_UPLOADS: [f64; 11] =
    [185.78, 152.96, 138.12, 159.77, 167.38, 167.63, 156.29, 155.50, 154.46, 153.44, 150.62];
const PAPER_SD_MS: f64 = 0.314375;

/// Run length and terrain size from the command line.
struct Settings {
    quick: bool,
    side: u32,
    length: RunLength,
}

impl Settings {
    fn parse() -> Settings {
        let quick = BenchArgs::parse().quick;
        let args: Vec<String> = std::env::args().collect();
        let value = |flag: &str, default: u32| {
            args.iter()
                .position(|a| a == flag)
                .and_then(|i| args.get(i + 1))
                .map(|v| {
                    v.parse().unwrap_or_else(|_| panic!("{flag} takes a positive whole number"))
                })
                .unwrap_or(default)
                .max(1)
        };
        // Quick mode draws 16 x 16 tiles (a quarter of the work) so a run
        // stays under a minute on a 2-core software rasteriser.
        let (side, frames, pairs) = if quick { (16, 2, 1) } else { (32, 2, 2) };
        Settings {
            quick,
            side: value("--side", side),
            length: RunLength { frames: value("--frames", frames), pairs: value("--pairs", pairs) },
        }
    }
}

/// Every row measured at one viewport, with that viewport's significance level.
struct Suite {
    viewport: [i32; 2],
    baseline_ms: f64,
    sd_ms: f64,
    blocks: usize,
    /// The 2 x 2 check, measured only at the full viewport.
    raster: Option<Pairs>,
    operations: Vec<Pairs>,
    uploads: Vec<Pairs>,
}

impl Suite {
    fn run(scene: &mut Scene, viewport: [i32; 2], batches: &[u32], length: RunLength) -> Suite {
        scene.set_viewport(viewport);
        let mut measure = |operation| measure::pairs(scene, operation, length).expect("GL frame");
        let raster = (viewport[0] > 2).then(|| measure(Operation::TinyViewport));
        let operations: Vec<Pairs> =
            PAPER_OPERATIONS.iter().map(|(op, _, _)| measure(*op)).collect();
        let uploads: Vec<Pairs> =
            batches.iter().map(|&batch| measure(Operation::TileUpload { batch })).collect();
        let baselines: Vec<f64> = raster
            .iter()
            .chain(&operations)
            .chain(&uploads)
            .flat_map(|p| blocks_ms(&p.baseline))
            .collect();
        let (baseline_ms, sd_ms) = mean_sd(&baselines);
        Suite { viewport, baseline_ms, sd_ms, blocks: baselines.len(), raster, operations, uploads }
    }

    fn significant(&self, cost_ms: f64) -> &'static str {
        if cost_ms.abs() > self.sd_ms {
            "yes"
        } else {
            "no"
        }
    }

    fn name(&self) -> String {
        format!("{}x{}", self.viewport[0], self.viewport[1])
    }

    fn print_baseline(&self) {
        println!(
            "baseline at {} (one draw of everything): {:.2} ms per frame, sd {:.3} ms over {} blocks (paper sd {PAPER_SD_MS} ms)",
            self.name(),
            self.baseline_ms,
            self.sd_ms,
            self.blocks
        );
        if let Some(raster) = &self.raster {
            let tiny_ms = raster.cost_secs() * 1e3;
            let bound = tiny_ms < 0.0 && tiny_ms.abs() > self.sd_ms;
            println!(
                "raster check: a 2 x 2 viewport changes the frame by {tiny_ms:+.2} ms ({:+.1} %): {}",
                100.0 * tiny_ms / self.baseline_ms,
                if bound { "raster-bound at this viewport" } else { "not raster-bound" }
            );
        }
    }

    fn to_json(&self, batches: &[u32]) -> Value {
        let ms = |p: &Pairs| p.cost_secs() * 1e3;
        let op_rows: Vec<Value> = self
            .operations
            .iter()
            .zip(PAPER_OPERATIONS)
            .map(|(p, (_, name, paper))| json!({"operation": name, "cost_ms": ms(p), "paper_ms": paper,
                "baseline_blocks_ms": blocks_ms(&p.baseline), "operation_blocks_ms": blocks_ms(&p.measured)}))
            .collect();
        let upload_rows: Vec<Value> = batches
            .iter()
            .zip(&self.uploads)
            .enumerate()
            .map(|(i, (b, p))| {
                json!({"batch_tiles": b, "cost_ms": ms(p), "in_subdata_ms": p.upload_secs() * 1e3,
                "paper_ms": PAPER_UPLOADS.get(i), "baseline_blocks_ms": blocks_ms(&p.baseline),
                "operation_blocks_ms": blocks_ms(&p.measured)})
            })
            .collect();
        json!({"viewport": self.viewport, "baseline_ms": self.baseline_ms, "baseline_sd_ms": self.sd_ms,
            "tiny_viewport_cost_ms": self.raster.as_ref().map(ms), "operations": op_rows, "uploads": upload_rows})
    }
}

fn main() {
    let settings = Settings::parse();
    let started = std::time::Instant::now();
    let request = ContextRequest::new(GlBackend::Egl, GlesVersion::Es3, VIEWPORT);
    let context = GlContext::new(&request).expect("open a headless EGL ES 3 context");
    let info = context.info();
    println!("hwmetrics on {} ({}), {}", info.renderer, info.version, info.platform);
    let mut scene = Scene::new(&context, settings.side).expect("build the benchmark terrain");
    let (tiles, length) = (scene.tiles(), settings.length);
    // A 2 x 2 frame is several times cheaper on a software rasteriser, so
    // that suite affords twice the frames and one more pair (two at least,
    // for the spread of the upload timings).
    let small = RunLength { frames: length.frames * 2, pairs: length.pairs + 1 };
    println!(
        "{tiles} tiles of {GRID} x {GRID} vertices; {} x {}: {} frames per block, {} pairs per row; 2 x 2: {} and {}{}",
        VIEWPORT.x,
        VIEWPORT.y,
        length.frames,
        length.pairs,
        small.frames,
        small.pairs,
        if settings.quick { " (quick)" } else { "" }
    );
    let batches: Vec<u32> = BATCHES.iter().copied().filter(|&b| b <= tiles).collect();
    let full = Suite::run(&mut scene, [VIEWPORT.x as i32, VIEWPORT.y as i32], &batches, length);
    let tiny = Suite::run(&mut scene, [2, 2], &batches, small);
    let report = Report { tiles, quarter: scene.uploads_per_frame(), suites: [full, tiny] };
    println!();
    report.suites.iter().for_each(Suite::print_baseline);
    report.print_operations();
    let cap = report.print_uploads(&batches);
    let elapsed = started.elapsed().as_secs_f64();
    println!("\nrun took {elapsed:.1} s");
    report.write(&settings, &batches, cap, elapsed);
}

/// Both suites, printed side by side with the paper.
struct Report {
    tiles: u32,
    quarter: u32,
    /// The paper's viewport, then 2 x 2.
    suites: [Suite; 2],
}

impl Report {
    /// Cost and significance of row `row` in both suites.
    fn cells(&self, pick: impl Fn(&Suite) -> &Pairs, per: u32) -> Vec<String> {
        self.suites
            .iter()
            .flat_map(|suite| {
                let cost = pick(suite).cost_secs() * 1e3;
                [
                    format!("{cost:+.2}"),
                    format!("{:+.2}", cost * 1e3 / per as f64),
                    suite.significant(cost).to_owned(),
                ]
            })
            .collect()
    }

    fn header(&self, first: &[&str], last: &[&str]) -> Vec<String> {
        let mut header: Vec<String> = first.iter().map(|s| s.to_string()).collect();
        for suite in &self.suites {
            let name = suite.name();
            header.extend([format!("{name} ms"), format!("{name} us/tile"), format!("{name} >sd")]);
        }
        header.extend(last.iter().map(|s| s.to_string()));
        header
    }

    fn print_operations(&self) {
        let rows: Vec<Vec<String>> = PAPER_OPERATIONS
            .iter()
            .enumerate()
            .map(|(i, (_, name, paper))| {
                let mut row = vec![name.to_string()];
                row.extend(self.cells(|s| &s.operations[i], self.tiles));
                row.push(paper.map_or("-".to_owned(), |p| format!("{p:.2}")));
                row
            })
            .collect();
        let header = self.header(&["operation"], &["paper ms"]);
        print_table(
            &format!(
                "Per-tile operations on {} tiles: frame time minus paired baseline",
                self.tiles
            ),
            &header.iter().map(String::as_str).collect::<Vec<_>>(),
            &rows,
        );
    }

    /// Prints the upload table and returns the chosen cap in tiles, taken
    /// from the 2 x 2 suite (the one the raster does not dominate).
    fn print_uploads(&self, batches: &[u32]) -> u32 {
        let rows: Vec<Vec<String>> = batches
            .iter()
            .enumerate()
            .map(|(i, &batch)| {
                let mut row = vec![batch.to_string(), format!("{}", batch * TILE_BYTES / 1024)];
                row.extend(self.cells(|s| &s.uploads[i], self.quarter));
                row.push(format!("{:.2}", self.suites[1].uploads[i].upload_secs() * 1e3));
                row.push(PAPER_UPLOADS.get(i).map_or("-".to_owned(), |p| format!("{p:.2}")));
                row
            })
            .collect();
        let header = self.header(&["batch", "KiB/run"], &["in SubData ms", "paper ms"]);
        print_table(
            &format!(
                "Tile upload, {} of {} tiles per frame ({TILE_BYTES} B per tile)",
                self.quarter, self.tiles
            ),
            &header.iter().map(String::as_str).collect::<Vec<_>>(),
            &rows,
        );
        let suite = &self.suites[1];
        let frame_costs: Vec<f64> = suite.uploads.iter().map(|p| p.cost_secs() * 1e3).collect();
        let frame_cap = choose_cap(batches, &frame_costs, suite.sd_ms);
        println!(
            "\npaper's rule on frame time at {}: cap {frame_cap} tiles (gains below the baseline sd {:.3} ms count as none)",
            suite.name(),
            suite.sd_ms
        );
        // The same rule on the time inside glBufferSubData, whose noise is
        // its own spread between blocks (pooled over the batch sizes).
        let subdata: Vec<f64> = suite.uploads.iter().map(|p| p.upload_secs() * 1e3).collect();
        let pooled = suite.uploads.iter().map(Pairs::upload_variance).sum::<f64>()
            / suite.uploads.len() as f64;
        let subdata_sd_ms = pooled.sqrt() * 1e3;
        let local_cap = choose_cap(batches, &subdata, subdata_sd_ms);
        println!("same rule on the time inside glBufferSubData (pooled sd {subdata_sd_ms:.3} ms): cap {local_cap} tiles");
        let paper_cap = choose_cap(&BATCHES, &PAPER_UPLOADS, PAPER_SD_MS);
        println!("same rule on the paper's column (sd {PAPER_SD_MS} ms): cap {paper_cap} tiles");
        // Batching matters on this driver only if the run length can move
        // the upload time by more than 1 % of the paper-sized frame (at
        // 800 x 600); below that the local pick is noise (it moves between
        // runs) and the paper's column decides. Where both matter, runs
        // shorter than either cap lose time on one of the two drivers, and
        // longer ones gain nothing on either.
        let (fastest, slowest) =
            subdata.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let frame_ms = self.suites[0].baseline_ms;
        let local_matters = slowest - fastest > 0.01 * frame_ms;
        let cap = if local_matters { local_cap.max(paper_cap) } else { paper_cap };
        let why = if local_matters {
            "the larger of the two".to_owned()
        } else {
            format!(
                "the paper's: here run length moves glBufferSubData by {:.2} ms, under 1 % of the {frame_ms:.0} ms frame",
                slowest - fastest
            )
        };
        println!(
            "recommended default transfer cap: {cap} tiles = {} bytes ({why})",
            cap * TILE_BYTES
        );
        cap
    }

    fn write(&self, settings: &Settings, batches: &[u32], cap: u32, elapsed: f64) {
        let path = support::write_json(
            "hwmetrics",
            &json!({
                "quick": settings.quick, "tiles": self.tiles, "grid": GRID, "tile_bytes": TILE_BYTES,
                "uploads_per_frame": self.quarter, "frames_per_block": settings.length.frames,
                "pairs": settings.length.pairs, "paper_sd_ms": PAPER_SD_MS,
                "suites": self.suites.iter().map(|s| s.to_json(batches)).collect::<Vec<_>>(),
                "transfer_cap_tiles": cap, "transfer_cap_bytes": cap * TILE_BYTES, "seconds": elapsed,
            }),
        );
        let points = |values: Vec<f64>| batches.iter().map(|&b| b as f64).zip(values).collect();
        let mut series: Vec<Series> = self
            .suites
            .iter()
            .map(|s| Series {
                label: format!("{}: frame minus baseline", s.name()),
                points: points(s.uploads.iter().map(|p| p.cost_secs() * 1e3).collect()),
            })
            .collect();
        series.push(Series {
            label: "inside glBufferSubData".to_owned(),
            points: points(self.suites[1].uploads.iter().map(|p| p.upload_secs() * 1e3).collect()),
        });
        series.push(Series {
            label: "paper (Tegra 2, 1024 tiles)".to_owned(),
            points: points(PAPER_UPLOADS.to_vec()),
        });
        let svg = support::write_svg(
            "hwmetrics",
            &[Panel {
                title: format!(
                    "Tile upload cost per frame ({} of {} tiles)",
                    self.quarter, self.tiles
                ),
                x_label: "batch (tiles per glBufferSubData)".to_owned(),
                y_label: "ms per frame".to_owned(),
                log_x: true,
                log_y: false,
                series,
            }],
        );
        println!("wrote {} and {}", path.display(), svg.display());
    }
}

fn blocks_ms(blocks: &[measure::Block]) -> Vec<f64> {
    blocks.iter().map(|b| b.frame_secs * 1e3).collect()
}

/// The smallest batch from which no longer batch saves more than `sd_ms`.
fn choose_cap(batches: &[u32], costs_ms: &[f64], sd_ms: f64) -> u32 {
    (0..batches.len())
        .find(|&i| costs_ms[i + 1..].iter().all(|&later| costs_ms[i] - later <= sd_ms))
        .map_or(batches[batches.len() - 1], |i| batches[i])
}
