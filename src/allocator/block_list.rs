//! The allocation table: every byte of the address space belongs to exactly
//! one block, and the blocks form a doubly linked list in address order.
//!
//! Block records live in a slab sized at construction; a record is named by its
//! [`Slot`]. Linking, unlinking and neighbour lookup are O(1), which is what the
//! paper's "O(1) lookup to the neighbour residing at lower address" needs for
//! merging. Finding a free block *by size* is the job of
//! [`FreeIndex`](super::free_index::FreeIndex), which is keyed by address.
//!
//! Invariants (checked by [`BlockList::check`] in debug builds and by the
//! property tests):
//! - the list starts at offset 0, each block starts where its predecessor ends,
//!   and the last one ends at `capacity`;
//! - no block is empty;
//! - no two free blocks are neighbours (free space is fully merged).

/// Index of a block record in the slab.
pub(crate) type Slot = u32;

/// The "no block" link.
pub(crate) const NIL: Slot = Slot::MAX;

/// What a block holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BlockState {
    /// Unused space, reusable now.
    Free,
    /// The current vertex data of a generator.
    Live { generator: u32 },
    /// Data a generator replaced or released, kept out of reuse until the GPU
    /// can no longer be reading it (frames in flight).
    Retiring { until_frame: u64 },
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Block {
    pub offset: u32,
    pub size: u32,
    pub prev: Slot,
    pub next: Slot,
    pub state: BlockState,
}

impl Block {
    pub fn end(&self) -> u32 {
        self.offset + self.size
    }
}

/// Slab of block records linked in address order.
pub(crate) struct BlockList {
    blocks: Vec<Block>,
    /// Slots not in the list, ready for reuse (a stack).
    spare: Vec<Slot>,
    head: Slot,
    tail: Slot,
    capacity: u32,
}

impl BlockList {
    /// A list holding one free block that covers `[0, capacity)`, with room for
    /// `max_blocks` records. Both tables are allocated here and never grow.
    pub fn new(capacity: u32, max_blocks: u32) -> Self {
        debug_assert!(capacity > 0 && max_blocks > 0);
        let empty = Block { offset: 0, size: 0, prev: NIL, next: NIL, state: BlockState::Free };
        let mut blocks = vec![empty; max_blocks as usize];
        blocks[0].size = capacity;
        let spare = (1..max_blocks).rev().collect();
        BlockList { blocks, spare, head: 0, tail: 0, capacity }
    }

    /// Blocks in the list.
    pub fn len(&self) -> usize {
        self.blocks.len() - self.spare.len()
    }

    pub fn tail(&self) -> Slot {
        self.tail
    }

    pub fn get(&self, slot: Slot) -> &Block {
        &self.blocks[slot as usize]
    }

    pub fn get_mut(&mut self, slot: Slot) -> &mut Block {
        &mut self.blocks[slot as usize]
    }

    /// Links a new record covering `[offset, offset + size)` just before `at`.
    /// The caller shrinks `at` so that the list stays a partition. O(1).
    pub fn insert_before(&mut self, at: Slot, offset: u32, size: u32, state: BlockState) -> Slot {
        let prev = self.get(at).prev;
        let slot = self.take_spare();
        self.blocks[slot as usize] = Block { offset, size, prev, next: at, state };
        self.get_mut(at).prev = slot;
        match prev {
            NIL => self.head = slot,
            p => self.get_mut(p).next = slot,
        }
        slot
    }

    /// Links a new record just after `at`. O(1).
    pub fn insert_after(&mut self, at: Slot, offset: u32, size: u32, state: BlockState) -> Slot {
        let next = self.get(at).next;
        let slot = self.take_spare();
        self.blocks[slot as usize] = Block { offset, size, prev: at, next, state };
        self.get_mut(at).next = slot;
        match next {
            NIL => self.tail = slot,
            n => self.get_mut(n).prev = slot,
        }
        slot
    }

    /// Unlinks `slot` and returns its record to the slab. The caller gives its
    /// bytes to a neighbour first. O(1).
    pub fn remove(&mut self, slot: Slot) {
        let Block { prev, next, .. } = *self.get(slot);
        match prev {
            NIL => self.head = next,
            p => self.get_mut(p).next = next,
        }
        match next {
            NIL => self.tail = prev,
            n => self.get_mut(n).prev = prev,
        }
        self.spare.push(slot);
    }

    fn take_spare(&mut self) -> Slot {
        // The allocator checks before every call that the slab cannot run out
        // (see `ContiguousAllocator::max_blocks`), so this is a bug if it fails.
        self.spare.pop().expect("block slab exhausted: the allocator's slot bound is wrong")
    }

    /// Iterates the blocks in address order.
    pub fn iter(&self) -> impl Iterator<Item = (Slot, &Block)> + '_ {
        let mut slot = self.head;
        std::iter::from_fn(move || {
            if slot == NIL {
                return None;
            }
            let current = slot;
            let block = self.get(current);
            slot = block.next;
            Some((current, block))
        })
    }

    /// Verifies the partition and merge invariants. O(blocks).
    pub fn check(&self) -> Result<(), String> {
        let mut expected_offset = 0u32;
        let mut prev = NIL;
        let mut prev_free = false;
        let mut count = 0usize;
        for (slot, block) in self.iter() {
            count += 1;
            if count > self.blocks.len() {
                return Err("block list has a cycle".into());
            }
            if block.prev != prev {
                return Err(format!("block {slot}: prev link {} != {prev}", block.prev));
            }
            if block.offset != expected_offset {
                return Err(format!(
                    "block {slot} starts at {} not {expected_offset}",
                    block.offset
                ));
            }
            if block.size == 0 {
                return Err(format!("block {slot} is empty"));
            }
            let free = block.state == BlockState::Free;
            if free && prev_free {
                return Err(format!("free block {slot} at {} follows a free block", block.offset));
            }
            expected_offset = block.end();
            prev = slot;
            prev_free = free;
        }
        if prev != self.tail {
            return Err("tail link does not name the last block".into());
        }
        if expected_offset != self.capacity {
            return Err(format!("blocks end at {expected_offset}, capacity {}", self.capacity));
        }
        if count + self.spare.len() != self.blocks.len() {
            return Err("slab records lost".into());
        }
        Ok(())
    }
}
