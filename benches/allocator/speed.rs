//! Speed: nanoseconds per placed block against `offset-allocator` (a TLSF-style
//! O(1) allocator) and `range-alloc` (a first-fit free list), on one workload:
//! N live blocks, and every step a random quarter of them is replaced with a
//! new size (Polok's Table 1 updates 25% of the tiles per frame). Ridgeline
//! places each step as one run in one call; the baselines free and allocate
//! block by block. All three see the same precomputed steps, so only the
//! allocators' own work is timed.
//!
//! Growth with N is judged against `offset-allocator`, whose work per block
//! does not depend on N: what it gains in time from 10^3 to 10^5 is the
//! machine's caches, and the ratio to it must grow no faster than log N.

use super::support::{print_table, Panel, Series};
use rand::prelude::*;
use ridgeline::allocator::{
    AllocatorConfig, ContiguousAllocator, GeneratorId, Request, VertexFormat,
};
use serde_json::{json, Value};
use std::time::Instant;

/// Largest block in bytes; sizes are uniform in [UNIT, MAX_BLOCK] in UNIT steps.
const MAX_BLOCK: u32 = 256;
const UNIT: u32 = 4;

struct Workload {
    n: u32,
    initial: Vec<u32>,
    /// Per step: (generator, new size).
    steps: Vec<Vec<(u32, u32)>>,
}

impl Workload {
    fn new(n: u32, placements: u64, seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed);
        let size = |rng: &mut StdRng| rng.random_range(1..=MAX_BLOCK / UNIT) * UNIT;
        let initial = (0..n).map(|_| size(&mut rng)).collect();
        let per_step = (n / 4).max(1);
        let step_count = (placements / per_step as u64).max(3);
        let steps = (0..step_count)
            .map(|_| {
                let chosen = rand::seq::index::sample(&mut rng, n as usize, per_step as usize);
                chosen.iter().map(|g| (g as u32, size(&mut rng))).collect()
            })
            .collect();
        Workload { n, initial, steps }
    }

    fn placements(&self) -> u64 {
        self.steps.iter().map(|s| s.len() as u64).sum()
    }

    fn capacity(&self) -> u32 {
        16 * self.n * MAX_BLOCK
    }
}

/// Returns (seconds, transfers per step).
fn ridgeline(w: &Workload) -> (f64, f64) {
    let config = AllocatorConfig { alignment: UNIT, ..AllocatorConfig::new(w.capacity(), w.n) };
    let mut alloc = ContiguousAllocator::new(config).expect("bench configuration");
    let request = |(g, size): (u32, u32)| Request {
        generator: GeneratorId(g),
        format: VertexFormat(0),
        size,
    };
    let initial: Vec<Request> =
        w.initial.iter().enumerate().map(|(g, &s)| request((g as u32, s))).collect();
    alloc.allocate(&initial).expect("initial fill fits");
    let steps: Vec<Vec<Request>> =
        w.steps.iter().map(|s| s.iter().copied().map(request).collect()).collect();
    let mut transfers = 0;
    let start = Instant::now();
    for step in &steps {
        transfers += alloc.allocate(step).expect("capacity is 16x the data").dirty_ranges().len();
    }
    (start.elapsed().as_secs_f64(), transfers as f64 / steps.len() as f64)
}

fn offset_allocator(w: &Workload) -> f64 {
    let mut alloc = offset_allocator::Allocator::<u32>::with_max_allocs(w.capacity(), 2 * w.n + 16);
    let mut live: Vec<_> = w.initial.iter().map(|&s| alloc.allocate(s).expect("fits")).collect();
    let start = Instant::now();
    for step in &w.steps {
        for &(g, size) in step {
            alloc.free(live[g as usize]);
            live[g as usize] = alloc.allocate(size).expect("capacity is 16x the data");
        }
    }
    start.elapsed().as_secs_f64()
}

fn range_alloc(w: &Workload) -> f64 {
    let mut alloc = range_alloc::RangeAllocator::new(0..w.capacity());
    let mut live: Vec<_> =
        w.initial.iter().map(|&s| alloc.allocate_range(s).expect("fits")).collect();
    let start = Instant::now();
    for step in &w.steps {
        for &(g, size) in step {
            alloc.free_range(live[g as usize].clone());
            live[g as usize] = alloc.allocate_range(size).expect("capacity is 16x the data");
        }
    }
    start.elapsed().as_secs_f64()
}

/// Best of `repeats` runs of each, interleaved so drift hits all three alike.
pub fn compare(quick: bool) -> (Vec<Value>, Panel) {
    // Many short interleaved runs, keeping each allocator's best: the machines
    // are shared, and a disturbance then hits one run, not one allocator.
    let placements: u64 = if quick { 100_000 } else { 400_000 };
    let repeats = if quick { 7 } else { 15 };
    let mut rows = Vec::new();
    let mut table = Vec::new();
    let mut series: Vec<Series> = ["ridgeline", "offset-allocator", "range-alloc"]
        .iter()
        .map(|&label| Series { label: label.into(), points: Vec::new() })
        .collect();
    for n in [100u32, 1_000, 10_000, 100_000] {
        let w = Workload::new(n, placements, n as u64);
        let blocks = w.placements() as f64;
        let (mut ours, mut offset, mut range, mut transfers) = (f64::MAX, f64::MAX, f64::MAX, 0.0);
        for _ in 0..repeats {
            let (secs, t) = ridgeline(&w);
            ours = ours.min(secs);
            transfers = t;
            offset = offset.min(offset_allocator(&w));
            range = range.min(range_alloc(&w));
        }
        let ns = |secs: f64| secs * 1e9 / blocks;
        let (ours, offset, range) = (ns(ours), ns(offset), ns(range));
        for (s, v) in series.iter_mut().zip([ours, offset, range]) {
            s.points.push((n as f64, v));
        }
        table.push(vec![
            n.to_string(),
            format!("{ours:.1}"),
            format!("{offset:.1}"),
            format!("{range:.1}"),
            format!("{:.2}", ours / offset),
            format!("{:.2}", ours / range),
            format!("{:.2}", (ours / offset) / (n as f64).log2()),
            format!("{transfers:.2}"),
        ]);
        rows.push(json!({
            "n": n,
            "blocks_per_step": n / 4,
            "placements": blocks,
            "ridgeline_ns_per_block": ours,
            "offset_allocator_ns_per_block": offset,
            "range_alloc_ns_per_block": range,
            "ratio_to_offset_allocator": ours / offset,
            "ratio_to_range_alloc": ours / range,
            "ratio_to_offset_allocator_per_log2_n": (ours / offset) / (n as f64).log2(),
            "ridgeline_transfers_per_step": transfers,
        }));
    }
    print_table(
        "Speed: ns per placed block (a quarter of N replaced per step; best of several runs)",
        &[
            "N",
            "ridgeline",
            "offset-alloc",
            "range-alloc",
            "vs offset",
            "vs range",
            "vs offset / log2 N",
            "transfers/step",
        ],
        &table,
    );
    let panel = Panel {
        title: "Speed per placed block".into(),
        x_label: "live blocks N".into(),
        y_label: "ns per block".into(),
        log_x: true,
        log_y: true,
        series,
    };
    (rows, panel)
}
