//! Pass 1: release the callers' old blocks, sort the requests by format and
//! place them as one contiguous run (cut into pieces at the transfer cap), or
//! undo everything and report why not.

use super::block_list::{BlockState, Slot, NIL};
use super::{AllocError, ContiguousAllocator, FramePlan, GeneratorId, Request};
use std::ops::Range;

/// Per-call tables, sized for `max_generators` requests at construction.
pub(crate) struct Scratch {
    /// Request indices in placement order (by format, then request order).
    pub order: Vec<u32>,
    /// Aligned size of each request.
    pub sizes: Vec<u32>,
    /// The block each request held before the call: slot, offset, size.
    pub old: Vec<(Slot, u32, u32)>,
    /// The block each request received, `NIL` until placed.
    pub placed: Vec<Slot>,
    /// One range per run piece.
    pub pieces: Vec<Range<u32>>,
}

impl Scratch {
    pub fn new(max_requests: usize) -> Self {
        Scratch {
            order: Vec::with_capacity(max_requests),
            sizes: Vec::with_capacity(max_requests),
            old: Vec::with_capacity(max_requests),
            placed: Vec::with_capacity(max_requests),
            pieces: Vec::with_capacity(max_requests),
        }
    }
}

impl ContiguousAllocator {
    /// Pass 1 for the generators in `requests`: see the module documentation.
    /// On success the returned plan hands out the ranges for pass 2; on failure
    /// the allocator is exactly as it was before the call.
    pub fn allocate<'a>(
        &'a mut self,
        requests: &'a [Request],
    ) -> Result<FramePlan<'a>, AllocError> {
        self.allocate_within(requests, 0..self.config.capacity)
    }

    /// [`Self::allocate`] with every run piece placed in a free block that
    /// starts inside `within`, wholly inside it: the lowest such block that
    /// holds the piece. A caller that keeps blocks inside fixed windows
    /// reserves a fence between them ([`Self::reserve`]), so no free block
    /// reaches across, and names one window here.
    pub fn allocate_within<'a>(
        &'a mut self,
        requests: &'a [Request],
        within: Range<u32>,
    ) -> Result<FramePlan<'a>, AllocError> {
        self.validate(requests)?;
        self.release_old(requests);
        self.sort_by_format(requests);
        if let Err(piece) = self.place_run(requests, within) {
            self.free_placed();
            // What a retry would see: this call's old blocks released, nothing placed.
            let largest_gap = self.free.largest();
            self.rollback(requests);
            self.debug_check();
            return Err(AllocError::OutOfSpace {
                asked: self.scratch.sizes.iter().map(|&s| s as u64).sum(),
                piece,
                blocks: requests.len(),
                largest_gap,
                capacity: self.config.capacity,
            });
        }
        for (i, request) in requests.iter().enumerate() {
            let slot = self.scratch.placed[i];
            self.owner[request.generator.0 as usize] = slot;
            self.live_blocks += 1;
            self.live_bytes += self.scratch.sizes[i] as u64;
        }
        self.debug_check();
        Ok(FramePlan::new(self, requests))
    }

    /// Checks every request before anything changes. Fills `sizes`.
    fn validate(&mut self, requests: &[Request]) -> Result<(), AllocError> {
        let max_generators = self.config.max_generators;
        if requests.len() > max_generators as usize {
            return Err(AllocError::TooManyRequests { requests: requests.len(), max_generators });
        }
        self.calls += 1;
        self.scratch.sizes.clear();
        let mut replacing = 0;
        for request in requests {
            let generator = request.generator;
            self.check_generator(generator)?;
            let g = generator.0 as usize;
            if self.seen[g] == self.calls {
                return Err(AllocError::DuplicateGenerator(generator.0));
            }
            self.seen[g] = self.calls;
            if request.size == 0 {
                return Err(AllocError::ZeroSize(generator.0));
            }
            let capacity = self.config.capacity;
            let aligned = align_up(request.size, self.config.alignment).filter(|&s| s <= capacity);
            let Some(aligned) = aligned else {
                return Err(AllocError::TooLarge {
                    generator: generator.0,
                    size: request.size,
                    capacity,
                });
            };
            self.scratch.sizes.push(aligned);
            replacing += usize::from(self.owner[g] != NIL);
        }
        let waiting = self.retiring.len();
        if self.config.frames_in_flight > 0 && waiting + replacing > self.retiring.max_len() {
            let max = self.retiring.max_len();
            return Err(AllocError::RetireQueueFull { waiting, more: replacing, max });
        }
        Ok(())
    }

    /// Frees (or retires) each requester's current block, remembering it for
    /// rollback. When many blocks go at once the free index is rebuilt from
    /// the list afterwards instead of being updated block by block.
    fn release_old(&mut self, requests: &[Request]) {
        self.scratch.old.clear();
        self.scratch.placed.clear();
        let freeing = requests.len() as u64 * u64::from(self.config.frames_in_flight == 0);
        // A treap update touches about log2 F nodes at random, a rebuild walks
        // every listed block once in order, which costs a few times less per
        // node: measured on the allocator bench, the crossover sits near 4.
        let per_update = (self.free.len() as u64 + 2).ilog2() as u64;
        let bulk = 4 * freeing * per_update > self.blocks.len() as u64;
        for request in requests {
            let slot = self.owner[request.generator.0 as usize];
            let old = match slot {
                NIL => (NIL, 0, 0),
                _ => {
                    let block = self.blocks.get(slot);
                    (slot, block.offset, block.size)
                }
            };
            self.scratch.old.push(old);
            self.scratch.placed.push(NIL);
            if slot != NIL {
                self.detach(request.generator, bulk);
            }
        }
        if bulk {
            self.rebuild_free_index();
        }
    }

    fn sort_by_format(&mut self, requests: &[Request]) {
        let order = &mut self.scratch.order;
        order.clear();
        order.extend(0..requests.len() as u32);
        // The index breaks ties, so the order is deterministic.
        order.sort_unstable_by_key(|&i| (requests[i as usize].format, i));
    }

    /// Places the sorted requests piece by piece, each at the lowest fit.
    /// Fails with the byte length of the first piece that finds no gap.
    fn place_run(&mut self, requests: &[Request], within: Range<u32>) -> Result<(), u64> {
        self.scratch.pieces.clear();
        let cap = self.config.transfer_cap.unwrap_or(u32::MAX) as u64;
        let mut start = 0;
        while start < self.scratch.order.len() {
            let (end, bytes) = self.next_piece(start, cap);
            let gap = u32::try_from(bytes).ok().and_then(|len| {
                let gap = self.free.first_fit_from(within.start, len)?;
                let ends_inside = self.blocks.get(gap).offset as u64 + bytes <= within.end as u64;
                // Any other fit starts higher, so ends higher still.
                ends_inside.then_some(gap)
            });
            let Some(gap) = gap else { return Err(bytes) };
            self.place_piece(gap, start..end, requests);
            start = end;
        }
        Ok(())
    }

    /// The end of the piece starting at `start` in `order` and its byte length:
    /// blocks are added while the piece stays within `cap` (one block always fits).
    fn next_piece(&self, start: usize, cap: u64) -> (usize, u64) {
        let Scratch { order, sizes, .. } = &self.scratch;
        let mut end = start;
        let mut bytes = 0u64;
        while end < order.len() {
            let size = sizes[order[end] as usize] as u64;
            if end > start && bytes + size > cap {
                break;
            }
            bytes += size;
            end += 1;
        }
        (end, bytes)
    }

    /// Links the piece's blocks in front of `gap`, then shrinks the gap once.
    fn place_piece(&mut self, gap: Slot, piece: Range<usize>, requests: &[Request]) {
        let start = self.blocks.get(gap).offset;
        let mut cursor = start;
        for k in piece {
            let i = self.scratch.order[k] as usize;
            let size = self.scratch.sizes[i];
            let state = BlockState::Live { generator: requests[i].generator.0 };
            self.scratch.placed[i] = self.blocks.insert_before(gap, cursor, size, state);
            cursor += size;
        }
        self.take_front(gap, cursor - start);
        self.scratch.pieces.push(start..cursor);
    }

    /// Frees the blocks this call placed before it failed.
    fn free_placed(&mut self) {
        for i in 0..self.scratch.placed.len() {
            let slot = std::mem::replace(&mut self.scratch.placed[i], NIL);
            if slot != NIL {
                self.free_block(slot);
            }
        }
    }

    /// Gives every requester its old block back, at its old offset.
    fn rollback(&mut self, requests: &[Request]) {
        self.scratch.pieces.clear();
        // Retired blocks were pushed in request order: take them back in reverse.
        for i in (0..requests.len()).rev() {
            let (slot, offset, size) = self.scratch.old[i];
            if slot == NIL {
                continue;
            }
            let generator = requests[i].generator.0;
            let restored = if self.config.frames_in_flight == 0 {
                self.carve_exact(offset, size, generator)
            } else {
                let (back, _) = self.retiring.pop_back().expect("retired in this call");
                debug_assert_eq!(back, slot);
                self.retiring_bytes -= size as u64;
                self.blocks.get_mut(slot).state = BlockState::Live { generator };
                slot
            };
            self.owner[generator as usize] = restored;
            self.live_blocks += 1;
            self.live_bytes += size as u64;
        }
    }

    /// Gives `generator`, which owns no block, the bytes `range` for good
    /// (until it releases them): a fence, say, that no placed block may
    /// cross. Fails unless the whole range is free.
    pub fn reserve(&mut self, generator: GeneratorId, range: Range<u32>) -> Result<(), AllocError> {
        self.check_generator(generator)?;
        let not_free =
            AllocError::NotFree { generator: generator.0, start: range.start, end: range.end };
        let aligned = range.start % self.config.alignment == 0
            && range.len() as u32 % self.config.alignment == 0;
        if range.is_empty() || !aligned || self.owner[generator.0 as usize] != NIL {
            return Err(not_free);
        }
        let free = self.free.at_or_below(range.start).map(|gap| *self.blocks.get(gap));
        if free.is_none_or(|gap| gap.end() < range.end) {
            return Err(not_free);
        }
        let size = range.end - range.start;
        let slot = self.carve_exact(range.start, size, generator.0);
        self.owner[generator.0 as usize] = slot;
        self.live_blocks += 1;
        self.live_bytes += size as u64;
        self.debug_check();
        Ok(())
    }

    /// Makes `[offset, offset + size)`, which lies inside one free block, a live
    /// block of `generator` again.
    fn carve_exact(&mut self, offset: u32, size: u32, generator: u32) -> Slot {
        let gap = self.free.at_or_below(offset).expect("rollback range lies in free space");
        let block = *self.blocks.get(gap);
        debug_assert!(block.state == BlockState::Free && block.end() >= offset + size);
        let state = BlockState::Live { generator };
        if block.offset == offset {
            let slot = self.blocks.insert_before(gap, offset, size, state);
            self.take_front(gap, size);
            return slot;
        }
        let left = offset - block.offset;
        let right = block.end() - offset - size;
        self.blocks.get_mut(gap).size = left;
        self.free.resize(gap, block.offset, left);
        let slot = self.blocks.insert_after(gap, offset, size, state);
        if right > 0 {
            let rest = self.blocks.insert_after(slot, offset + size, right, BlockState::Free);
            self.free.insert(rest, offset + size, right);
        }
        slot
    }
}

/// `size` rounded up to a multiple of the power of two `alignment`, if it fits.
fn align_up(size: u32, alignment: u32) -> Option<u32> {
    Some(size.checked_add(alignment - 1)? & !(alignment - 1))
}
