//! Exhaustive check of the paper's worst-case claim: "the worst-case space
//! needed to hold k blocks of size S is (2k - 2) S" (Polok et al., eq. 2).
//!
//! With equal blocks every offset is a multiple of S, so a state is the set of
//! occupied slots, a bit mask. Breadth-first search visits every reachable
//! state; the workspace of a state is its highest occupied slot + 1. The worst
//! state's path is then replayed on the real [`ContiguousAllocator`], so the
//! figure is the allocator's, not only the model's. Two move sets:
//! - [`Moves::Any`]: from the empty buffer, any call the allocator accepts:
//!   reallocate any subset of the live blocks together with any number of new
//!   blocks (one run, lowest fit), or release one block;
//! - [`Moves::ReallocateOnly`]: the paper's setting, all k blocks placed first,
//!   then only reallocations of any subset.
//!
//! Both reach floor((k + 1)^2 / 4) S for every k searched, which exceeds the
//! paper's bound from k = 5 on (and at k = 1, where (2k - 2) S = 0): the waste
//! grows quadratically, not linearly, because a pivot can hold free space on
//! both sides and each round strands one block more than the last.

use super::{AllocatorConfig, ContiguousAllocator, GeneratorId, Request, VertexFormat};
use std::collections::{HashMap, VecDeque};

/// One move of the search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Move {
    /// Reallocate the blocks at the slots in `mask` and place `new` new blocks,
    /// all in one call.
    Allocate {
        /// Occupied slots reallocated, one bit per slot of S bytes.
        mask: u64,
        /// New blocks placed in the same run.
        new: u32,
    },
    /// Release the block at `slot`.
    Release {
        /// Slot (offset in units of S) of the released block.
        slot: u32,
    },
}

/// The result for one `k`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WorstCase {
    /// Number of equal blocks searched.
    pub k: u32,
    /// The paper's bound, (2k - 2) S, in units of S.
    pub paper_bound: u32,
    /// The largest workspace reachable, in units of S.
    pub found: u32,
    /// Number of distinct reachable states.
    pub states: usize,
    /// Moves from the empty buffer to a worst state.
    pub witness: Vec<Move>,
    /// Occupied slots of that worst state.
    pub worst_state: u64,
}

/// Which calls the search may make.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Moves {
    /// Any allocation or release with at most k live blocks.
    Any,
    /// k blocks placed first, then only reallocations.
    ReallocateOnly,
}

/// Searches every state reachable with at most `k` equal blocks (k <= 16).
pub fn search(k: u32, allowed: Moves) -> WorstCase {
    assert!((1..=16).contains(&k), "the search keeps slots in a 64-bit mask");
    let start = match allowed {
        Moves::Any => 0u64,
        Moves::ReallocateOnly => (1u64 << k) - 1,
    };
    let mut parent: HashMap<u64, (u64, Move)> = HashMap::new();
    let mut queue = VecDeque::from([start]);
    parent.insert(start, (start, Move::Allocate { mask: 0, new: k }));
    let mut worst = 0u64;
    while let Some(state) = queue.pop_front() {
        if workspace(state) > workspace(worst) {
            worst = state;
        }
        for (next, mv) in moves(state, k, allowed) {
            if let std::collections::hash_map::Entry::Vacant(e) = parent.entry(next) {
                e.insert((state, mv));
                queue.push_back(next);
            }
        }
    }
    let witness = path_to(start, worst, &parent);
    let replayed = replay(&witness, k);
    assert_eq!(replayed, worst, "the allocator disagrees with the search model");
    WorstCase {
        k,
        paper_bound: 2 * k - 2,
        found: workspace(worst),
        states: parent.len(),
        witness,
        worst_state: worst,
    }
}

fn workspace(state: u64) -> u32 {
    64 - state.leading_zeros()
}

/// Every state one move away from `state`.
fn moves(state: u64, k: u32, allowed: Moves) -> impl Iterator<Item = (u64, Move)> {
    let live = state.count_ones();
    let max_new = if allowed == Moves::Any { k - live } else { 0 };
    let slots: Vec<u32> = (0..64).filter(|s| state & (1 << s) != 0).collect();
    let subsets = 1u64 << slots.len();
    let allocations = (0..subsets).flat_map(move |bits| {
        let mask: u64 = slots
            .iter()
            .enumerate()
            .filter(|(i, _)| bits & (1 << i) != 0)
            .map(|(_, s)| 1u64 << s)
            .sum();
        (0..=max_new).filter_map(move |new| {
            let run = mask.count_ones() + new;
            (run > 0).then(|| (place(state & !mask, run), Move::Allocate { mask, new }))
        })
    });
    let releases = (0..64u32)
        .filter(move |s| allowed == Moves::Any && state & (1 << s) != 0)
        .map(move |slot| (state & !(1 << slot), Move::Release { slot }));
    allocations.chain(releases).collect::<Vec<_>>().into_iter()
}

/// Places a run of `run` slots at the lowest free position.
fn place(occupied: u64, run: u32) -> u64 {
    let block = (1u64 << run) - 1;
    let at = (0..=64 - run).find(|&at| occupied & (block << at) == 0).expect("64 slots suffice");
    occupied | (block << at)
}

/// The moves from the empty buffer to `target` (through `start`).
fn path_to(start: u64, target: u64, parent: &HashMap<u64, (u64, Move)>) -> Vec<Move> {
    let mut path = Vec::new();
    let mut state = target;
    while state != start {
        let (prev, mv) = parent[&state];
        path.push(mv);
        state = prev;
    }
    if start != 0 {
        path.push(parent[&start].1);
    }
    path.reverse();
    path
}

/// Plays `moves` on the real allocator with blocks of one unit and returns the
/// occupied slots it ends with.
pub fn replay(moves: &[Move], k: u32) -> u64 {
    let config = AllocatorConfig { alignment: 1, ..AllocatorConfig::new(64, k) };
    let mut allocator = ContiguousAllocator::new(config).expect("valid configuration");
    let mut at_slot: [Option<GeneratorId>; 64] = [None; 64];
    let mut requests = Vec::new();
    for &mv in moves {
        match mv {
            Move::Allocate { mask, new } => {
                requests.clear();
                let moved =
                    (0..64).filter(|s| mask & (1 << s) != 0).map(|s| at_slot[s].expect("occupied"));
                let idle = (0..k).map(GeneratorId).filter(|g| allocator.block_range(*g).is_none());
                for generator in moved.chain(idle.take(new as usize)) {
                    requests.push(Request { generator, format: VertexFormat(0), size: 1 });
                }
                allocator.allocate(&requests).expect("64 slots hold any reachable run");
            }
            Move::Release { slot } => {
                let generator = at_slot[slot as usize].expect("occupied");
                allocator.release(generator).expect("known generator");
            }
        }
        at_slot = [None; 64];
        for g in (0..k).map(GeneratorId) {
            if let Some(range) = allocator.block_range(g) {
                at_slot[range.start as usize] = Some(g);
            }
        }
    }
    (0..64).filter(|&s| at_slot[s].is_some()).map(|s| 1u64 << s).sum()
}
