//! Blocks waiting out the GPU frames in flight before their bytes may be reused.
//!
//! A replaced or released block is pushed with the frame at which it becomes
//! free. Frames only move forward, so the queue is in expiry order and a fixed
//! ring buffer is enough: push and expire are O(1) per block. A failed
//! allocation takes back what it pushed from the back, in reverse order.

use super::block_list::Slot;

pub(crate) struct RetireQueue {
    ring: Vec<(Slot, u64)>,
    head: usize,
    len: usize,
}

impl RetireQueue {
    pub fn new(max_len: usize) -> Self {
        RetireQueue { ring: vec![(0, 0); max_len], head: 0, len: 0 }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn max_len(&self) -> usize {
        self.ring.len()
    }

    /// Queues `slot` to become free at frame `until`. The caller has checked room.
    pub fn push(&mut self, slot: Slot, until: u64) {
        debug_assert!(self.len < self.ring.len(), "retire queue overflow");
        debug_assert!(self.back().is_none_or(|(_, last)| last <= until), "retire order");
        let tail = (self.head + self.len) % self.ring.len();
        self.ring[tail] = (slot, until);
        self.len += 1;
    }

    /// Takes back the most recent push.
    pub fn pop_back(&mut self) -> Option<(Slot, u64)> {
        let entry = self.back()?;
        self.len -= 1;
        Some(entry)
    }

    /// Removes and returns the oldest entry if it has expired by `frame`.
    pub fn pop_expired(&mut self, frame: u64) -> Option<Slot> {
        if self.len == 0 {
            return None;
        }
        let (slot, until) = self.ring[self.head];
        if until > frame {
            return None;
        }
        self.head = (self.head + 1) % self.ring.len();
        self.len -= 1;
        Some(slot)
    }

    fn back(&self) -> Option<(Slot, u64)> {
        if self.len == 0 {
            return None;
        }
        Some(self.ring[(self.head + self.len - 1) % self.ring.len()])
    }
}
