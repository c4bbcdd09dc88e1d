//! The contiguous two-pass buffer allocator (Polok et al., DASC 2012, "System
//! architecture" and "Results"). It owns one linear address space of fixed
//! capacity, its CPU staging copy, and the table of which geometry generator
//! holds which bytes. A GPU vertex buffer of the same size mirrors the staging
//! copy at the same offsets; this module never touches GL.
//!
//! # One frame
//! 1. [`begin_frame`](ContiguousAllocator::begin_frame) returns to the free
//!    space the blocks whose frames in flight have passed.
//! 2. Pass 1, [`allocate`](ContiguousAllocator::allocate): generators announce
//!    `(format, bytes)`; their old blocks are released (merged with free
//!    neighbours, or held back for the frames in flight); the requests are
//!    sorted by format and placed as one contiguous run at the lowest address
//!    where it fits. A run longer than the transfer cap is cut, between blocks,
//!    into pieces that are placed one after another, each at the lowest fit.
//! 3. Pass 2, [`FramePlan::fill`]: each generator writes its bytes into its
//!    range of the staging copy; [`FramePlan::dirty_ranges`] lists one range
//!    per run piece, each uploaded in one transfer.
//!
//! # Cost (N requests, F free gaps, E blocks expiring)
//! | step | cost | why |
//! |---|---|---|
//! | `begin_frame` | O(E log F) | each expiring block merges with its neighbours in O(1) through the address-ordered list, then one index update |
//! | validate | O(N) | generator stamps catch duplicates without a set |
//! | release old blocks | O(min(N log F, B)) | O(1) merge each, then one index update each, or one O(B) rebuild of the index from the B listed blocks when that is cheaper |
//! | sort by format | O(N log N) | in place, on a table sized at construction |
//! | find a gap | O(log F) per piece | the free index is a treap keyed by address that keeps the largest size of each subtree |
//! | place | O(1) per block + O(log F) per piece | blocks are linked in front of the gap, which shrinks once |
//! | failure and rollback | O(N log F) | the placed blocks are freed and the old ones carved back exactly |
//!
//! So a call costs O(N log N + min(N log F, B)); the paper's bound is
//! O(N) + O(N log N) + O(log M) on average with a linear worst case for the gap
//! search, which the augmented index removes. No call allocates on the heap:
//! every table is sized in [`ContiguousAllocator::new`].

mod block_list;
mod error;
mod frame;
mod free_index;
mod place;
mod retire;
pub mod worst_case;

use block_list::{BlockList, BlockState, Slot, NIL};
use free_index::FreeIndex;
use retire::RetireQueue;
use std::ops::Range;

pub use error::{AllocError, ConfigError};
pub use frame::FramePlan;

/// Names a geometry generator (a tile): an index into the allocator's table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GeneratorId(pub u32);

/// Names a vertex layout; requests of one format are placed next to each other
/// so that the renderer changes attribute pointers as rarely as possible.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct VertexFormat(pub u16);

/// One generator's announcement in pass 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// The generator (tile) that will own the block.
    pub generator: GeneratorId,
    /// The block's vertex layout; runs are sorted by it.
    pub format: VertexFormat,
    /// Bytes it will write in pass 2 (rounded up to the alignment).
    pub size: u32,
}

/// Fixed parameters; every table is sized from these once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AllocatorConfig {
    /// Bytes in the address space (and in the GPU buffer that mirrors it).
    pub capacity: u32,
    /// Generators the table can name: `GeneratorId(0..max_generators)`.
    pub max_generators: u32,
    /// Every block starts on a multiple of this (a power of two).
    pub alignment: u32,
    /// Longest run piece in bytes; `None` places each call's run in one piece.
    pub transfer_cap: Option<u32>,
    /// Frames a released block stays out of reuse (0: reusable at once).
    pub frames_in_flight: u32,
}

impl AllocatorConfig {
    /// A configuration with 4-byte alignment, no transfer cap and no frames in flight.
    pub fn new(capacity: u32, max_generators: u32) -> Self {
        AllocatorConfig {
            capacity,
            max_generators,
            alignment: 4,
            transfer_cap: None,
            frames_in_flight: 0,
        }
    }
}

/// A snapshot of how the address space is used.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct AllocatorStats {
    /// Bytes in the address space.
    pub capacity: u32,
    /// Blocks owned by a generator.
    pub live_blocks: usize,
    /// Bytes in live blocks.
    pub live_bytes: u64,
    /// Released blocks still waiting out their frames in flight.
    pub retiring_blocks: usize,
    /// Bytes in retiring blocks.
    pub retiring_bytes: u64,
    /// Free gaps (free blocks; neighbouring free space is always merged).
    pub free_gaps: usize,
    /// Bytes neither live nor retiring.
    pub free_bytes: u64,
    /// Bytes in the largest free gap.
    pub largest_gap: u32,
    /// End of the highest block that is not free: the buffer size this state needs.
    pub workspace_end: u32,
}

/// What merging a freed block did to the list.
struct Merge {
    /// The record that now holds the merged free space.
    keep: Slot,
    /// `keep` was a free block already (and is in the index under its offset).
    keep_was_free: bool,
    /// A free neighbour folded into `keep`, or `NIL`.
    absorbed: Slot,
}

/// The allocator: see the module documentation.
pub struct ContiguousAllocator {
    config: AllocatorConfig,
    blocks: BlockList,
    free: FreeIndex,
    retiring: RetireQueue,
    /// Live block of each generator, or `NIL`.
    owner: Vec<Slot>,
    /// Call number in which each generator was last seen (duplicate check).
    seen: Vec<u64>,
    calls: u64,
    frame: u64,
    live_blocks: usize,
    live_bytes: u64,
    retiring_bytes: u64,
    staging: Vec<u8>,
    scratch: place::Scratch,
}

impl ContiguousAllocator {
    /// Builds the allocator and every table it will ever use.
    pub fn new(config: AllocatorConfig) -> Result<Self, ConfigError> {
        let AllocatorConfig { capacity, max_generators, alignment, transfer_cap, frames_in_flight } =
            config;
        if capacity == 0 {
            return Err(ConfigError::ZeroCapacity);
        }
        if max_generators == 0 {
            return Err(ConfigError::NoGenerators);
        }
        if !alignment.is_power_of_two() {
            return Err(ConfigError::BadAlignment(alignment));
        }
        if capacity % alignment != 0 {
            return Err(ConfigError::UnalignedCapacity { capacity, alignment });
        }
        if transfer_cap == Some(0) {
            return Err(ConfigError::ZeroTransferCap);
        }
        let too_large = ConfigError::TableTooLarge { generators: max_generators, frames_in_flight };
        let max_retiring = (max_generators as u64) * (frames_in_flight as u64);
        // Free blocks never touch each other, so there is at most one more free
        // block than non-free ones: records <= 2 * (live + retiring) + 1.
        let max_blocks = 2 * (max_generators as u64 + max_retiring) + 1;
        if max_blocks >= NIL as u64 {
            return Err(too_large);
        }
        let generators = max_generators as usize;
        Ok(ContiguousAllocator {
            config,
            blocks: BlockList::new(capacity, max_blocks as u32),
            free: {
                let mut free = FreeIndex::new(max_blocks as u32);
                free.insert(0, 0, capacity);
                free
            },
            retiring: RetireQueue::new(max_retiring as usize),
            owner: vec![NIL; generators],
            seen: vec![0; generators],
            calls: 0,
            frame: 0,
            live_blocks: 0,
            live_bytes: 0,
            retiring_bytes: 0,
            staging: vec![0; capacity as usize],
            scratch: place::Scratch::new(generators),
        })
    }

    /// The configuration the allocator was built with.
    pub fn config(&self) -> &AllocatorConfig {
        &self.config
    }

    /// Frames begun so far.
    pub fn frame(&self) -> u64 {
        self.frame
    }

    /// Starts a frame: blocks whose frames in flight have passed become free.
    pub fn begin_frame(&mut self) {
        self.frame += 1;
        while let Some(slot) = self.retiring.pop_expired(self.frame) {
            self.retiring_bytes -= self.blocks.get(slot).size as u64;
            self.free_block(slot);
        }
        self.debug_check();
    }

    /// The bytes a generator currently owns, if any.
    pub fn block_range(&self, generator: GeneratorId) -> Option<Range<u32>> {
        let slot = *self.owner.get(generator.0 as usize)?;
        (slot != NIL).then(|| {
            let block = self.blocks.get(slot);
            block.offset..block.end()
        })
    }

    /// Gives up a generator's block (its tile left the scene). Returns whether
    /// it had one.
    pub fn release(&mut self, generator: GeneratorId) -> Result<bool, AllocError> {
        self.check_generator(generator)?;
        let had = self.owner[generator.0 as usize] != NIL;
        if had && self.config.frames_in_flight > 0 && self.retiring.len() >= self.retiring.max_len()
        {
            return Err(AllocError::RetireQueueFull {
                waiting: self.retiring.len(),
                more: 1,
                max: self.retiring.max_len(),
            });
        }
        if had {
            self.detach(generator, false);
        }
        self.debug_check();
        Ok(had)
    }

    /// The CPU staging copy; the GPU buffer mirrors it at the same offsets.
    pub fn staging(&self) -> &[u8] {
        &self.staging
    }

    /// The ranges written by the last successful [`allocate`](Self::allocate),
    /// one per run piece, in placement order.
    pub fn dirty_ranges(&self) -> &[Range<u32>] {
        &self.scratch.pieces
    }

    /// The largest free gap starting in `range`, bytes: what one run piece
    /// placed there by [`Self::allocate_within`] may take (before the
    /// call's own old blocks are released).
    pub fn largest_gap_in(&self, range: Range<u32>) -> u32 {
        self.free.largest_in(range)
    }

    /// How the address space is used now.
    pub fn stats(&self) -> AllocatorStats {
        let tail = self.blocks.get(self.blocks.tail());
        let workspace_end = if tail.state == BlockState::Free { tail.offset } else { tail.end() };
        let capacity = self.config.capacity;
        AllocatorStats {
            capacity,
            live_blocks: self.live_blocks,
            live_bytes: self.live_bytes,
            retiring_blocks: self.retiring.len(),
            retiring_bytes: self.retiring_bytes,
            free_gaps: self.free.len(),
            free_bytes: capacity as u64 - self.live_bytes - self.retiring_bytes,
            largest_gap: self.free.largest(),
            workspace_end,
        }
    }

    fn check_generator(&self, generator: GeneratorId) -> Result<(), AllocError> {
        if generator.0 >= self.config.max_generators {
            return Err(AllocError::UnknownGenerator {
                generator: generator.0,
                max_generators: self.config.max_generators,
            });
        }
        Ok(())
    }

    /// Takes a generator's live block away from it: freed now, or queued until
    /// its frames in flight have passed. The caller has checked queue room.
    /// With `defer_index` the free index is left stale for a later rebuild.
    fn detach(&mut self, generator: GeneratorId, defer_index: bool) {
        let slot = std::mem::replace(&mut self.owner[generator.0 as usize], NIL);
        debug_assert_ne!(slot, NIL);
        let size = self.blocks.get(slot).size as u64;
        self.live_blocks -= 1;
        self.live_bytes -= size;
        if self.config.frames_in_flight > 0 {
            let until = self.frame + self.config.frames_in_flight as u64;
            self.blocks.get_mut(slot).state = BlockState::Retiring { until_frame: until };
            self.retiring.push(slot, until);
            self.retiring_bytes += size;
        } else if defer_index {
            self.merge_free(slot);
        } else {
            self.free_block(slot);
        }
    }

    /// Turns a block into free space, merging it with free neighbours, and
    /// tells the free index. O(log F).
    fn free_block(&mut self, slot: Slot) {
        let merge = self.merge_free(slot);
        if merge.absorbed != NIL {
            self.free.remove(merge.absorbed);
        }
        let block = *self.blocks.get(merge.keep);
        if merge.keep_was_free {
            self.free.resize(merge.keep, block.offset, block.size);
        } else {
            self.free.insert(merge.keep, block.offset, block.size);
        }
    }

    /// Marks `slot` free and merges it with free neighbours in the list only,
    /// leaving the free index stale. O(1).
    fn merge_free(&mut self, slot: Slot) -> Merge {
        let block = *self.blocks.get(slot);
        debug_assert_ne!(block.state, BlockState::Free);
        self.blocks.get_mut(slot).state = BlockState::Free;
        let mut merge = Merge { keep: slot, keep_was_free: false, absorbed: NIL };
        if block.prev != NIL && self.blocks.get(block.prev).state == BlockState::Free {
            self.blocks.get_mut(block.prev).size += block.size;
            self.blocks.remove(slot);
            merge.keep = block.prev;
            merge.keep_was_free = true;
        }
        if block.next != NIL && self.blocks.get(block.next).state == BlockState::Free {
            let next_size = self.blocks.get(block.next).size;
            self.blocks.remove(block.next);
            self.blocks.get_mut(merge.keep).size += next_size;
            merge.absorbed = block.next;
        }
        merge
    }

    /// Rebuilds the free index from the list, O(blocks), after bulk merges.
    fn rebuild_free_index(&mut self) {
        let free_blocks = self.blocks.iter().filter(|(_, b)| b.state == BlockState::Free);
        self.free.rebuild(free_blocks.map(|(slot, b)| (slot, b.offset, b.size)));
    }

    /// Shrinks free block `gap` by `bytes` taken off its front, removing it when
    /// nothing is left. The caller has already linked the new blocks before it.
    fn take_front(&mut self, gap: Slot, bytes: u32) {
        let block = self.blocks.get_mut(gap);
        debug_assert!(block.state == BlockState::Free && block.size >= bytes);
        if block.size == bytes {
            self.free.remove(gap);
            self.blocks.remove(gap);
        } else {
            block.offset += bytes;
            block.size -= bytes;
            let (offset, size) = (block.offset, block.size);
            self.free.resize(gap, offset, size);
        }
    }

    fn debug_check(&self) {
        debug_assert_eq!(self.check_invariants(), Ok(()));
    }

    /// Verifies every invariant of the table, the index, the owners and the
    /// counters. O(blocks + generators); tests call it after every operation.
    pub fn check_invariants(&self) -> Result<(), String> {
        self.blocks.check()?;
        self.free.check()?;
        // The index must hold exactly the list's free blocks, in order.
        let mut listed = self.blocks.iter().filter(|(_, b)| b.state == BlockState::Free);
        let mut matches = true;
        self.free.for_each(&mut |slot, offset, size| {
            let same =
                listed.next().is_some_and(|(s, b)| (s, b.offset, b.size) == (slot, offset, size));
            matches &= same;
        });
        if !matches || listed.next().is_some() {
            return Err("free index does not match the free blocks of the list".into());
        }
        let (mut live, mut live_bytes, mut retiring, mut retiring_bytes) = (0, 0u64, 0, 0u64);
        for (slot, block) in self.blocks.iter() {
            match block.state {
                BlockState::Free => {}
                BlockState::Live { generator } => {
                    if self.owner.get(generator as usize) != Some(&slot) {
                        return Err(format!(
                            "live block {slot} not owned by generator {generator}"
                        ));
                    }
                    if block.offset % self.config.alignment != 0 {
                        return Err(format!("block {slot} at {} is unaligned", block.offset));
                    }
                    live += 1;
                    live_bytes += block.size as u64;
                }
                BlockState::Retiring { until_frame } => {
                    if until_frame <= self.frame {
                        return Err(format!("block {slot} should have expired"));
                    }
                    retiring += 1;
                    retiring_bytes += block.size as u64;
                }
            }
        }
        let owned = self.owner.iter().filter(|&&s| s != NIL).count();
        if owned != live || live != self.live_blocks || live_bytes != self.live_bytes {
            return Err("live blocks, owners and counters disagree".into());
        }
        if retiring != self.retiring.len() || retiring_bytes != self.retiring_bytes {
            return Err("retiring counters disagree with the list".into());
        }
        Ok(())
    }
}
