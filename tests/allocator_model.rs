//! The contiguous allocator against a shadow model, in the manner of rlsf's
//! tests of its TLSF: random sequences of calls go to both, and after every
//! call the two must agree on every block's offset, on failures, and on the
//! free space; the allocator's own invariants must hold; and no live block's
//! bytes in the staging copy may have changed.
//!
//! The model is deliberately naive: live and retiring blocks in plain vectors,
//! free gaps recomputed by sorting every time.

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use ridgeline::allocator::{
    AllocError, AllocatorConfig, ContiguousAllocator, GeneratorId, Request, VertexFormat,
};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

/// Calls made and placements that failed for lack of space, over the whole run.
static CALLS: AtomicUsize = AtomicUsize::new(0);
static OUT_OF_SPACE: AtomicUsize = AtomicUsize::new(0);

#[derive(Clone, Debug)]
enum Op {
    /// (generator, format, size) triples; duplicates are removed before the call.
    Allocate(Vec<(u32, u16, u32)>),
    Release(u32),
    BeginFrame,
}

/// Naive reference: what the allocator should do, computed the slow way.
struct Model {
    config: AllocatorConfig,
    live: BTreeMap<u32, (u32, u32)>,
    retiring: Vec<(u32, u32, u64)>,
    frame: u64,
}

impl Model {
    fn occupied(&self) -> Vec<(u32, u32)> {
        let mut spans: Vec<(u32, u32)> = self.live.values().copied().collect();
        spans.extend(self.retiring.iter().map(|&(o, s, _)| (o, s)));
        spans.sort_unstable();
        spans
    }

    /// Maximal free gaps in address order.
    fn gaps(&self, extra: &[(u32, u32)]) -> Vec<(u32, u32)> {
        let mut spans = self.occupied();
        spans.extend_from_slice(extra);
        spans.sort_unstable();
        let mut gaps = Vec::new();
        let mut cursor = 0;
        for (offset, size) in spans {
            if offset > cursor {
                gaps.push((cursor, offset - cursor));
            }
            cursor = offset + size;
        }
        if cursor < self.config.capacity {
            gaps.push((cursor, self.config.capacity - cursor));
        }
        gaps
    }

    fn detach(&mut self, generator: u32) {
        if let Some((offset, size)) = self.live.remove(&generator) {
            if self.config.frames_in_flight > 0 {
                let until = self.frame + self.config.frames_in_flight as u64;
                self.retiring.push((offset, size, until));
            }
        }
    }

    fn begin_frame(&mut self) {
        self.frame += 1;
        let frame = self.frame;
        self.retiring.retain(|&(_, _, until)| until > frame);
    }

    /// Returns each request's offset, or the failing piece's byte count.
    fn allocate(&mut self, requests: &[Request]) -> Result<Vec<u32>, (u64, u32)> {
        let align = self.config.alignment;
        let sizes: Vec<u32> = requests.iter().map(|r| r.size.div_ceil(align) * align).collect();
        let saved = (self.live.clone(), self.retiring.clone());
        for r in requests {
            self.detach(r.generator.0);
        }
        let mut order: Vec<usize> = (0..requests.len()).collect();
        order.sort_by_key(|&i| (requests[i].format, i));
        let cap = self.config.transfer_cap.unwrap_or(u32::MAX) as u64;
        let mut placed: Vec<(u32, u32)> = Vec::new();
        let mut offsets = vec![0; requests.len()];
        let mut k = 0;
        while k < order.len() {
            let mut end = k;
            let mut bytes = 0u64;
            while end < order.len() && (end == k || bytes + sizes[order[end]] as u64 <= cap) {
                bytes += sizes[order[end]] as u64;
                end += 1;
            }
            let fit = self.gaps(&placed).into_iter().find(|&(_, len)| len as u64 >= bytes);
            let Some((mut cursor, _)) = fit else {
                let largest = self.gaps(&[]).iter().map(|g| g.1).max().unwrap_or(0);
                (self.live, self.retiring) = saved;
                return Err((bytes, largest));
            };
            for &i in &order[k..end] {
                offsets[i] = cursor;
                placed.push((cursor, sizes[i]));
                cursor += sizes[i];
            }
            k = end;
        }
        for (i, r) in requests.iter().enumerate() {
            self.live.insert(r.generator.0, (offsets[i], sizes[i]));
        }
        Ok(offsets)
    }
}

/// Byte pattern a generator writes in its `version`th block.
fn pattern(generator: u32, version: u32, index: usize) -> u8 {
    (generator.wrapping_mul(31) ^ version.wrapping_mul(7) ^ index as u32) as u8
}

struct Harness {
    real: ContiguousAllocator,
    model: Model,
    version: BTreeMap<u32, u32>,
    requests: Vec<Request>,
}

impl Harness {
    fn new(config: AllocatorConfig) -> Self {
        let real = ContiguousAllocator::new(config).expect("valid config");
        let model = Model { config, live: BTreeMap::new(), retiring: Vec::new(), frame: 0 };
        Harness { real, model, version: BTreeMap::new(), requests: Vec::new() }
    }

    fn apply(&mut self, op: &Op) -> Result<(), TestCaseError> {
        CALLS.fetch_add(1, Relaxed);
        match op {
            Op::BeginFrame => {
                self.real.begin_frame();
                self.model.begin_frame();
            }
            Op::Release(g) => {
                let had = self.real.release(GeneratorId(*g)).map_err(|e| fail(&e))?;
                prop_assert_eq!(had, self.model.live.contains_key(g));
                self.model.detach(*g);
            }
            Op::Allocate(list) => self.allocate(list)?,
        }
        self.check()
    }

    fn allocate(&mut self, list: &[(u32, u16, u32)]) -> Result<(), TestCaseError> {
        self.requests.clear();
        for &(g, format, size) in list {
            if self.requests.iter().all(|r| r.generator.0 != g) {
                let request =
                    Request { generator: GeneratorId(g), format: VertexFormat(format), size };
                self.requests.push(request);
            }
        }
        let requests = self.requests.clone();
        let expected = self.model.allocate(&requests);
        match (self.real.allocate(&requests), expected) {
            (Ok(mut plan), Ok(offsets)) => {
                for (i, r) in requests.iter().enumerate() {
                    prop_assert_eq!(plan.range(i).start, offsets[i], "request {:?}", r);
                }
                let pieces = plan.dirty_ranges().to_vec();
                let covered: u64 = pieces.iter().map(|p| (p.end - p.start) as u64).sum();
                let asked: u64 = (0..requests.len()).map(|i| plan.range(i).len() as u64).sum();
                prop_assert_eq!(covered, asked, "dirty ranges cover exactly the run");
                let version = &mut self.version;
                plan.fill(|_, request, bytes| {
                    let v = version.entry(request.generator.0).or_default();
                    *v += 1;
                    for (j, b) in bytes.iter_mut().enumerate() {
                        *b = pattern(request.generator.0, *v, j);
                    }
                });
            }
            (Err(AllocError::OutOfSpace { piece, largest_gap, .. }), Err((bytes, largest))) => {
                OUT_OF_SPACE.fetch_add(1, Relaxed);
                prop_assert_eq!(piece, bytes);
                prop_assert_eq!(largest_gap, largest);
            }
            (real, model) => {
                return Err(TestCaseError::fail(format!(
                    "real {:?} vs model {:?}",
                    real.err(),
                    model
                )));
            }
        }
        Ok(())
    }

    fn check(&self) -> Result<(), TestCaseError> {
        if let Err(problem) = self.real.check_invariants() {
            return Err(TestCaseError::fail(problem));
        }
        let staging = self.real.staging();
        for (&g, &(offset, size)) in &self.model.live {
            let range = self.real.block_range(GeneratorId(g));
            prop_assert_eq!(range, Some(offset..offset + size), "generator {}", g);
            let v = self.version[&g];
            for j in 0..size as usize {
                let byte = staging[offset as usize + j];
                prop_assert_eq!(byte, pattern(g, v, j), "generator {} byte {} changed", g, j);
            }
        }
        let stats = self.real.stats();
        let gaps = self.model.gaps(&[]);
        prop_assert_eq!(stats.free_gaps, gaps.len());
        prop_assert_eq!(stats.largest_gap, gaps.iter().map(|g| g.1).max().unwrap_or(0));
        let end = self.model.occupied().iter().map(|&(o, s)| o + s).max().unwrap_or(0);
        prop_assert_eq!(stats.workspace_end, end);
        Ok(())
    }
}

fn fail(error: &AllocError) -> TestCaseError {
    TestCaseError::fail(error.to_string())
}

fn config_strategy() -> impl Strategy<Value = AllocatorConfig> {
    (
        prop_oneof![Just(1u32), Just(4), Just(16)],
        8u32..200,
        1u32..24,
        prop_oneof![Just(None), (1u32..64).prop_map(Some)],
        0u32..3,
    )
        .prop_map(|(alignment, units, generators, cap, frames)| AllocatorConfig {
            capacity: units * 16,
            max_generators: generators,
            alignment,
            transfer_cap: cap.map(|c| c * 4),
            frames_in_flight: frames,
        })
}

/// A frame-shaped sequence: each frame begins, allocates once, and may release.
fn ops_strategy(generators: u32) -> impl Strategy<Value = Vec<Op>> {
    let request = (0..generators, 0u16..3, 1u32..80);
    let frame = (prop::collection::vec(request, 0..8), prop::option::of(0..generators));
    prop::collection::vec(frame, 1..200).prop_map(|frames| {
        let mut ops = Vec::new();
        for (requests, release) in frames {
            ops.push(Op::BeginFrame);
            // Releasing before allocating keeps every generator to one retirement per frame.
            if let Some(g) = release {
                if requests.iter().all(|r| r.0 != g) {
                    ops.push(Op::Release(g));
                }
            }
            ops.push(Op::Allocate(requests));
        }
        ops
    })
}

fn config_and_ops() -> impl Strategy<Value = (AllocatorConfig, Vec<Op>)> {
    config_strategy().prop_flat_map(|config| (Just(config), ops_strategy(config.max_generators)))
}

proptest! {
    // 600 cases of 1..200 frames, about 2.5 calls a frame: ~1.5 * 10^5 calls.
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    #[test]
    fn allocator_matches_shadow_model((config, ops) in config_and_ops()) {
        let mut harness = Harness::new(config);
        for op in &ops {
            harness.apply(op)?;
        }
    }
}

/// Runs after the property test in the same process only by chance, so it
/// checks its own share: the generated sequences exercise both outcomes.
#[test]
fn shadow_model_runs_enough_calls() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let (mut calls, mut failures) = (0, 0);
    for _ in 0..50 {
        let (config, ops) = config_and_ops().new_tree(&mut runner).unwrap().current();
        let mut harness = Harness::new(config);
        let before = OUT_OF_SPACE.load(Relaxed);
        for op in &ops {
            harness.apply(op).unwrap();
        }
        calls += ops.len();
        failures += OUT_OF_SPACE.load(Relaxed) - before;
    }
    println!(
        "50 sequences: {calls} calls, {failures} out-of-space (total so far {})",
        CALLS.load(Relaxed)
    );
    assert!(calls > 50 * 100, "sequences are long enough");
    assert!(failures > 0, "some calls run out of space, so rollback is exercised");
}
