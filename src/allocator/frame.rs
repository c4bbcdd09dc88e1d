//! Pass 2: the placed requests' byte ranges, handed to their generators to fill.

use super::{ContiguousAllocator, Request};
use std::ops::Range;

/// The result of a successful pass 1. It borrows the allocator until the
/// generators have written their bytes; the dirty ranges stay readable through
/// [`ContiguousAllocator::dirty_ranges`] afterwards for the upload.
pub struct FramePlan<'a> {
    allocator: &'a mut ContiguousAllocator,
    requests: &'a [Request],
}

impl std::fmt::Debug for FramePlan<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FramePlan")
            .field("requests", &self.requests.len())
            .field("dirty_ranges", &self.dirty_ranges())
            .finish()
    }
}

impl<'a> FramePlan<'a> {
    pub(super) fn new(allocator: &'a mut ContiguousAllocator, requests: &'a [Request]) -> Self {
        FramePlan { allocator, requests }
    }

    /// The byte range placed for `requests[index]`.
    pub fn range(&self, index: usize) -> Range<u32> {
        let slot = self.allocator.scratch.placed[index];
        let block = self.allocator.blocks.get(slot);
        block.offset..block.end()
    }

    /// Calls `fill(index, request, bytes)` for every request, in address order,
    /// with exactly that request's bytes of the staging copy.
    pub fn fill(&mut self, mut fill: impl FnMut(usize, &Request, &mut [u8])) {
        for k in 0..self.allocator.scratch.order.len() {
            let index = self.allocator.scratch.order[k] as usize;
            let range = self.range(index);
            let bytes = &mut self.allocator.staging[range.start as usize..range.end as usize];
            fill(index, &self.requests[index], bytes);
        }
    }

    /// One range per run piece: each is one transfer to the GPU.
    pub fn dirty_ranges(&self) -> &[Range<u32>] {
        self.allocator.dirty_ranges()
    }

    /// The staging copy, to upload the dirty ranges from.
    pub fn staging(&self) -> &[u8] {
        self.allocator.staging()
    }
}
