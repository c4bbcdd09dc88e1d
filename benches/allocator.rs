//! The contiguous allocator measured: Polok's Table 2 (workspace of 1000
//! blocks under random reallocation), the paper's worst-case claim, what the
//! transfer cap and the frames in flight cost, and speed against the
//! `offset-allocator` and `range-alloc` crates on the same workload.
//!
//! `cargo bench --bench allocator [-- --quick]` prints the tables and writes
//! `target/bench/allocator.json` and `target/bench/allocator.svg`.

mod support;

use rand::prelude::*;
use rand_distr::{Distribution as _, Normal};
use ridgeline::allocator::worst_case::{self, Moves};
use ridgeline::allocator::{
    AllocatorConfig, ContiguousAllocator, GeneratorId, Request, VertexFormat,
};
use serde_json::{json, Value};
use std::time::Instant;
use support::{mean_sd, print_table, BenchArgs, Panel, Series};

/// Bytes in one unit S of the Table 2 experiment.
const S: u32 = 1024;
/// Blocks in the Table 2 experiment.
const BLOCKS: u32 = 1000;
/// Standard deviation of the Gaussian sizes, in units of S. The paper does not
/// state it; 0.8 S is the value at which the protocol that matches the other
/// two rows (k = 3 per step) also matches the Gaussian row, so it is fitted,
/// and the sensitivity table prints what other choices give.
const GAUSSIAN_SIGMA: f64 = 0.8;

/// Block size distributions of Table 2.
#[derive(Clone, Copy, Debug)]
enum Distribution {
    Constant,
    /// Normal(S, sigma * S) with sigma in units of S; draws below one byte
    /// are drawn again (a truncated normal, so the mean is slightly above S).
    Gaussian(f64),
    /// Uniform over whole bytes in (0, S].
    Uniform,
}

impl Distribution {
    const ALL: [Distribution; 3] =
        [Distribution::Constant, Distribution::Gaussian(GAUSSIAN_SIGMA), Distribution::Uniform];

    fn name(self) -> &'static str {
        match self {
            Distribution::Constant => "constant",
            Distribution::Gaussian(_) => "gaussian",
            Distribution::Uniform => "uniform",
        }
    }

    /// The paper's average workspace for this distribution, in S.
    fn paper(self) -> f64 {
        match self {
            Distribution::Constant => 1542.31,
            Distribution::Gaussian(_) => 1866.08,
            Distribution::Uniform => 825.73,
        }
    }

    fn draw(self, rng: &mut StdRng) -> u32 {
        match self {
            Distribution::Constant => S,
            Distribution::Gaussian(sigma) => {
                let normal = Normal::new(S as f64, sigma * S as f64).expect("valid sigma");
                loop {
                    let x = normal.sample(rng).round();
                    if x >= 1.0 {
                        return x as u32;
                    }
                }
            }
            Distribution::Uniform => rng.random_range(1..=S),
        }
    }
}

/// How many blocks one step reallocates.
#[derive(Clone, Copy, Debug)]
enum Pick {
    /// Exactly k distinct blocks, uniformly at random.
    Count(u32),
    /// Each block independently with this probability.
    Chance(f64),
}

impl Pick {
    fn name(self) -> String {
        match self {
            Pick::Count(k) => format!("k={k}/step"),
            Pick::Chance(p) => format!("p={}%/step", p * 100.0),
        }
    }

    fn expected_blocks(self) -> f64 {
        match self {
            Pick::Count(k) => k as f64,
            Pick::Chance(p) => p * BLOCKS as f64,
        }
    }

    fn choose(self, rng: &mut StdRng, out: &mut Vec<u32>) {
        out.clear();
        match self {
            Pick::Count(k) => out.extend(
                rand::seq::index::sample(rng, BLOCKS as usize, k as usize).iter().map(|i| i as u32),
            ),
            Pick::Chance(p) => out.extend((0..BLOCKS).filter(|_| rng.random_bool(p))),
        }
    }
}

/// Parameters of one simulated run.
#[derive(Clone, Copy)]
struct Experiment {
    distribution: Distribution,
    pick: Pick,
    transfer_cap_blocks: Option<u32>,
    frames_in_flight: u32,
    /// Blocks reallocated before measuring, then blocks reallocated while measuring.
    warmup_blocks: u64,
    measured_blocks: u64,
}

/// What one run measured.
struct Outcome {
    mean_workspace_s: f64,
    peak_workspace_s: f64,
    transfers_per_step: f64,
    blocks_per_step: f64,
    ns_per_block: f64,
}

fn run(experiment: Experiment, seed: u64) -> Outcome {
    let mut rng = StdRng::seed_from_u64(seed);
    let config = AllocatorConfig {
        capacity: 16 * BLOCKS * S,
        max_generators: BLOCKS,
        alignment: 1,
        transfer_cap: experiment.transfer_cap_blocks.map(|c| c * S),
        frames_in_flight: experiment.frames_in_flight,
    };
    let mut alloc = ContiguousAllocator::new(config).expect("bench configuration");
    let draw = |rng: &mut StdRng, g: u32| Request {
        generator: GeneratorId(g),
        format: VertexFormat(0),
        size: experiment.distribution.draw(rng),
    };
    let initial: Vec<Request> = (0..BLOCKS).map(|g| draw(&mut rng, g)).collect();
    alloc.allocate(&initial).expect("initial fill fits");
    let (mut chosen, mut requests) = (Vec::new(), Vec::new());
    let (mut done, mut steps, mut transfers, mut placed) = (0u64, 0u64, 0u64, 0u64);
    let (mut sum, mut peak, mut busy) = (0.0, 0.0f64, 0.0);
    while done < experiment.warmup_blocks + experiment.measured_blocks {
        experiment.pick.choose(&mut rng, &mut chosen);
        requests.clear();
        requests.extend(chosen.iter().map(|&g| draw(&mut rng, g)));
        // Expiring held-back blocks is part of the cost of frames in flight.
        let start = Instant::now();
        alloc.begin_frame();
        let pieces =
            alloc.allocate(&requests).expect("capacity is 16x the data").dirty_ranges().len();
        let elapsed = start.elapsed().as_secs_f64();
        done += requests.len() as u64;
        if done <= experiment.warmup_blocks {
            continue;
        }
        let workspace = alloc.stats().workspace_end as f64 / S as f64;
        sum += workspace;
        peak = peak.max(workspace);
        steps += 1;
        transfers += pieces as u64;
        placed += requests.len() as u64;
        busy += elapsed;
    }
    Outcome {
        mean_workspace_s: sum / steps as f64,
        peak_workspace_s: peak,
        transfers_per_step: transfers as f64 / steps as f64,
        blocks_per_step: placed as f64 / steps as f64,
        ns_per_block: busy * 1e9 / placed.max(1) as f64,
    }
}

/// Mean and spread over seeds of one experiment.
struct Summary {
    mean: (f64, f64),
    peak: (f64, f64),
    transfers_per_step: f64,
    blocks_per_step: f64,
    ns_per_block: f64,
}

fn summarise(experiment: Experiment, seeds: u64) -> Summary {
    let outcomes: Vec<Outcome> = (0..seeds).map(|seed| run(experiment, 0x5eed + seed)).collect();
    let collect = |f: fn(&Outcome) -> f64| outcomes.iter().map(f).collect::<Vec<_>>();
    Summary {
        mean: mean_sd(&collect(|o| o.mean_workspace_s)),
        peak: mean_sd(&collect(|o| o.peak_workspace_s)),
        transfers_per_step: mean_sd(&collect(|o| o.transfers_per_step)).0,
        blocks_per_step: mean_sd(&collect(|o| o.blocks_per_step)).0,
        ns_per_block: mean_sd(&collect(|o| o.ns_per_block)).0,
    }
}

struct Scale {
    warmup_blocks: u64,
    measured_blocks: u64,
    seeds: u64,
}

fn table2(scale: &Scale) -> (Vec<Value>, Vec<Value>, Panel) {
    let picks = [
        Pick::Count(1),
        Pick::Count(2),
        Pick::Count(3),
        Pick::Count(4),
        Pick::Count(8),
        Pick::Chance(0.01),
        Pick::Chance(0.10),
    ];
    let mut rows = Vec::new();
    let mut table = Vec::new();
    let mut series = Vec::new();
    for distribution in Distribution::ALL {
        let mut points = Vec::new();
        for pick in picks {
            let experiment = Experiment {
                distribution,
                pick,
                transfer_cap_blocks: None,
                frames_in_flight: 0,
                warmup_blocks: scale.warmup_blocks,
                measured_blocks: scale.measured_blocks,
            };
            let s = summarise(experiment, scale.seeds);
            points.push((pick.expected_blocks(), s.mean.0));
            rows.push((distribution, pick, s));
        }
        series.push(Series { label: distribution.name().into(), points });
    }
    // For each distribution, the protocol whose mean is nearest the paper's figure.
    let mut matches = Vec::new();
    for distribution in Distribution::ALL {
        let best = rows
            .iter()
            .filter(|r| r.0.name() == distribution.name())
            .min_by(|a, b| {
                (a.2.mean.0 - distribution.paper())
                    .abs()
                    .total_cmp(&(b.2.mean.0 - distribution.paper()).abs())
            })
            .expect("rows for every distribution");
        let error = best.2.mean.0 / distribution.paper() - 1.0;
        matches.push(json!({
            "distribution": distribution.name(),
            "paper": distribution.paper(),
            "protocol": best.1.name(),
            "mean_workspace_s": best.2.mean.0,
            "relative_error": error,
        }));
        series.push(Series {
            label: format!("paper {}", distribution.name()),
            points: vec![(1.0, distribution.paper()), (100.0, distribution.paper())],
        });
    }
    let mut json_rows = Vec::new();
    for (distribution, pick, s) in &rows {
        let matched = matches
            .iter()
            .any(|m| m["distribution"] == distribution.name() && m["protocol"] == pick.name());
        let paper = matched.then(|| distribution.paper());
        table.push(vec![
            distribution.name().to_string(),
            pick.name(),
            format!("{:.1}", s.blocks_per_step),
            format!("{:.1} ± {:.1}", s.mean.0, s.mean.1),
            format!("{:.1} ± {:.1}", s.peak.0, s.peak.1),
            paper
                .map(|p| format!("{p:.2} ({:+.1}%)", (s.mean.0 / p - 1.0) * 100.0))
                .unwrap_or_default(),
        ]);
        json_rows.push(json!({
            "distribution": distribution.name(),
            "protocol": pick.name(),
            "blocks_per_step": s.blocks_per_step,
            "mean_workspace_s": s.mean.0,
            "mean_workspace_sd_over_seeds": s.mean.1,
            "peak_workspace_s": s.peak.0,
            "peak_workspace_sd_over_seeds": s.peak.1,
            "paper": paper,
            "seeds": scale.seeds,
            "measured_blocks": scale.measured_blocks,
            "warmup_blocks": scale.warmup_blocks,
        }));
    }
    print_table(
        &format!(
            "Table 2: workspace of {BLOCKS} blocks in units of S (mean ± sd over {} seeds; Gaussian sigma = {GAUSSIAN_SIGMA} S, draws < 1 byte redrawn)",
            scale.seeds
        ),
        &["distribution", "protocol", "blocks/step", "mean workspace", "peak workspace", "paper"],
        &table,
    );
    let panel = Panel {
        title: "Table 2: mean workspace".into(),
        x_label: "blocks reallocated per step".into(),
        y_label: "workspace [S]".into(),
        log_x: true,
        log_y: false,
        series,
    };
    (json_rows, matches, panel)
}

/// How the Gaussian row depends on the unstated sigma, at k = 3 per step.
fn gaussian_sensitivity(scale: &Scale) -> Vec<Value> {
    let mut rows = Vec::new();
    let mut table = Vec::new();
    for sigma in [0.25, 0.5, 0.8, 1.0] {
        let experiment = Experiment {
            distribution: Distribution::Gaussian(sigma),
            pick: Pick::Count(3),
            transfer_cap_blocks: None,
            frames_in_flight: 0,
            warmup_blocks: scale.warmup_blocks,
            measured_blocks: scale.measured_blocks,
        };
        let s = summarise(experiment, scale.seeds);
        let error = s.mean.0 / 1866.08 - 1.0;
        table.push(vec![
            format!("{sigma}"),
            format!("{:.1} ± {:.1}", s.mean.0, s.mean.1),
            format!("{:+.1}%", error * 100.0),
        ]);
        rows.push(json!({ "sigma_s": sigma, "protocol": "k=3/step", "mean_workspace_s": s.mean.0, "relative_error_to_paper": error }));
    }
    print_table(
        "Gaussian row against its unstated sigma (k = 3 per step; paper 1866.08 S)",
        &["sigma [S]", "mean workspace [S]", "vs paper"],
        &table,
    );
    rows
}

fn worst_cases(max_k: u32) -> Vec<Value> {
    let mut rows = Vec::new();
    let mut table = Vec::new();
    for allowed in [Moves::ReallocateOnly, Moves::Any] {
        for k in 1..=max_k {
            let result = worst_case::search(k, allowed);
            table.push(vec![
                format!("{allowed:?}"),
                k.to_string(),
                result.paper_bound.to_string(),
                result.found.to_string(),
                result.states.to_string(),
            ]);
            rows.push(json!({
                "k": k,
                "moves": format!("{allowed:?}"),
                "paper_bound": result.paper_bound,
                "found": result.found,
                "states": result.states,
                "witness": format!("{:?}", result.witness),
            }));
        }
    }
    print_table(
        "Worst case of k equal blocks (exhaustive search, replayed on the allocator), in S",
        &["moves", "k", "paper (2k-2)", "found", "states"],
        &table,
    );
    rows
}

fn transfer_caps(scale: &Scale) -> (Vec<Value>, Panel) {
    let mut rows = Vec::new();
    let mut table = Vec::new();
    let mut points = Vec::new();
    for cap in [Some(1), Some(4), Some(16), Some(64), None] {
        let experiment = Experiment {
            distribution: Distribution::Constant,
            pick: Pick::Chance(0.10),
            transfer_cap_blocks: cap,
            frames_in_flight: 0,
            warmup_blocks: scale.warmup_blocks,
            measured_blocks: scale.measured_blocks,
        };
        let s = summarise(experiment, scale.seeds);
        let name = cap.map(|c| c.to_string()).unwrap_or_else(|| "none".into());
        points.push((s.transfers_per_step, s.mean.0));
        table.push(vec![
            name.clone(),
            format!("{:.2}", s.transfers_per_step),
            format!("{:.1} ± {:.1}", s.mean.0, s.mean.1),
            format!("{:.1}", s.peak.0),
        ]);
        rows.push(json!({
            "cap_blocks": cap,
            "transfers_per_step": s.transfers_per_step,
            "mean_workspace_s": s.mean.0,
            "peak_workspace_s": s.peak.0,
        }));
    }
    print_table(
        "Transfer cap (constant S, each block with p = 10% per step): transfers against workspace",
        &["cap [blocks]", "transfers/step", "mean workspace [S]", "peak [S]"],
        &table,
    );
    let panel = Panel {
        title: "Transfer cap trade-off".into(),
        x_label: "transfers per step".into(),
        y_label: "mean workspace [S]".into(),
        log_x: true,
        log_y: false,
        series: vec![Series { label: "caps 1, 4, 16, 64, none".into(), points }],
    };
    (rows, panel)
}

fn frames_in_flight(scale: &Scale) -> Vec<Value> {
    let mut rows = Vec::new();
    let mut table = Vec::new();
    let mut base = None;
    for frames in 0..=3 {
        let experiment = Experiment {
            distribution: Distribution::Constant,
            pick: Pick::Chance(0.10),
            transfer_cap_blocks: None,
            frames_in_flight: frames,
            warmup_blocks: scale.warmup_blocks,
            measured_blocks: scale.measured_blocks,
        };
        let s = summarise(experiment, scale.seeds);
        let base_mean = *base.get_or_insert(s.mean.0);
        table.push(vec![
            frames.to_string(),
            format!("{:.1}", s.mean.0),
            format!("{:.1}", s.peak.0),
            format!("{:.2}x", s.mean.0 / base_mean),
            format!("{:.0}", s.ns_per_block),
        ]);
        rows.push(json!({
            "frames_in_flight": frames,
            "mean_workspace_s": s.mean.0,
            "peak_workspace_s": s.peak.0,
            "workspace_ratio_to_none": s.mean.0 / base_mean,
            "ns_per_block": s.ns_per_block,
        }));
    }
    print_table(
        "Frames in flight (constant S, p = 10% per step): what holding released blocks back costs",
        &["frames", "mean workspace [S]", "peak [S]", "vs 0 frames", "ns/block"],
        &table,
    );
    rows
}

fn main() {
    let args = BenchArgs::parse();
    let scale = if args.quick {
        Scale { warmup_blocks: 20_000, measured_blocks: 60_000, seeds: 3 }
    } else {
        Scale { warmup_blocks: 100_000, measured_blocks: 400_000, seeds: 5 }
    };
    let (table2_rows, paper_match, table2_panel) = table2(&scale);
    let sensitivity = gaussian_sensitivity(&scale);
    let worst = worst_cases(if args.quick { 7 } else { 9 });
    let (caps, caps_panel) = transfer_caps(&scale);
    let frames = frames_in_flight(&scale);
    let (speed, speed_panel) = speed::compare(args.quick);
    let report = json!({
        "bench": "allocator",
        "quick": args.quick,
        "s_bytes": S,
        "blocks": BLOCKS,
        "gaussian_sigma_s": GAUSSIAN_SIGMA,
        "table2": table2_rows,
        "paper_match": paper_match,
        "gaussian_sigma_sensitivity": sensitivity,
        "worst_case": worst,
        "transfer_cap": caps,
        "frames_in_flight": frames,
        "speed": speed,
    });
    let json_path = support::write_json("allocator", &report);
    let svg_path = support::write_svg("allocator", &[table2_panel, caps_panel, speed_panel]);
    println!("\nwrote {} and {}", json_path.display(), svg_path.display());
}

#[path = "allocator/speed.rs"]
mod speed;
