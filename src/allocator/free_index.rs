//! The index of free blocks: a treap keyed by address, each node also carrying
//! the largest free size in its subtree.
//!
//! That augmentation answers the allocator's one question, "the lowest address
//! whose free block holds at least `len` bytes", in O(log F) for F free blocks,
//! where the paper's list walk is linear in the worst case. The largest gap (for
//! error messages and statistics) is the root's value, O(1).
//!
//! Nodes are named by the same [`Slot`] as the block records and live in tables
//! sized at construction. Heap priorities are a fixed hash of the slot, so the
//! tree shape, and with it every run, is deterministic.
//!
//! Invariants (checked by [`FreeIndex::check`]): keys increase in in-order
//! traversal, every parent's priority is at least its children's, and each
//! node's `max_size` is the maximum of its own size and its children's.

use super::block_list::{Slot, NIL};

/// One node, kept together so that a step down the tree is one cache line.
#[derive(Clone, Copy)]
struct Node {
    left: Slot,
    right: Slot,
    offset: u32,
    size: u32,
    max_size: u32,
    priority: u32,
}

pub(crate) struct FreeIndex {
    nodes: Vec<Node>,
    root: Slot,
    len: usize,
    /// Right spine while rebuilding; sized at construction.
    spine: Vec<Slot>,
}

/// A well-mixed, fixed priority per slot (splitmix64 finaliser). Equal
/// priorities are harmless: the heap order is "parent at least child".
fn priority(slot: Slot) -> u32 {
    let mut z = (slot as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 32) as u32
}

impl FreeIndex {
    pub fn new(max_blocks: u32) -> Self {
        let n = max_blocks as usize;
        let empty = Node { left: NIL, right: NIL, offset: 0, size: 0, max_size: 0, priority: 0 };
        let mut nodes = vec![empty; n];
        for (slot, node) in nodes.iter_mut().enumerate() {
            node.priority = priority(slot as Slot);
        }
        FreeIndex { nodes, root: NIL, len: 0, spine: Vec::with_capacity(n) }
    }

    /// Number of free blocks indexed.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Size of the largest free block, 0 when there is none. O(1).
    pub fn largest(&self) -> u32 {
        self.subtree_max(self.root)
    }

    /// Adds the free block `slot` at `[offset, offset + size)`. O(log F).
    pub fn insert(&mut self, slot: Slot, offset: u32, size: u32) {
        self.reset(slot, offset, size);
        self.root = self.insert_at(self.root, slot);
        self.len += 1;
    }

    /// Removes the free block `slot`, which starts at the key it was given. O(log F).
    pub fn remove(&mut self, slot: Slot) {
        let key = self.node(slot).offset;
        self.root = self.remove_at(self.root, key);
        self.len -= 1;
    }

    /// Changes the extent of an indexed block whose position among the free
    /// blocks stays the same (it grew into a merged neighbour, or the allocator
    /// carved bytes off its front). O(log F).
    pub fn resize(&mut self, slot: Slot, offset: u32, size: u32) {
        let node = self.node_mut(slot);
        node.offset = offset;
        node.size = size;
        self.refresh_path(self.root, offset);
    }

    /// Replaces the whole index with `blocks`, given in address order, in
    /// O(F): the treap is built as a Cartesian tree along its right spine.
    pub fn rebuild(&mut self, blocks: impl Iterator<Item = (Slot, u32, u32)>) {
        let mut spine = std::mem::take(&mut self.spine);
        spine.clear();
        self.len = 0;
        for (slot, offset, size) in blocks {
            self.reset(slot, offset, size);
            let priority = self.node(slot).priority;
            let mut below = NIL;
            while let Some(&top) = spine.last() {
                if self.node(top).priority >= priority {
                    break;
                }
                // `top`'s subtree is complete once it leaves the spine.
                self.update(top);
                below = top;
                spine.pop();
            }
            self.node_mut(slot).left = below;
            if let Some(&top) = spine.last() {
                self.node_mut(top).right = slot;
            }
            spine.push(slot);
            self.len += 1;
        }
        self.root = spine.first().copied().unwrap_or(NIL);
        while let Some(top) = spine.pop() {
            self.update(top);
        }
        self.spine = spine;
    }

    /// The free block at the lowest address at or above `start` holding at
    /// least `len` bytes. O(log F): one walk down the path to `start`, and
    /// one plain first fit in the subtree where the answer lies.
    pub fn first_fit_from(&self, start: u32, len: u32) -> Option<Slot> {
        let mut slot = self.root;
        // Every candidate met lies below the ones met before it (the walk
        // only turns left at nodes above `start`): the last one wins. A
        // candidate is a node that fits, or a right subtree wholly at or
        // above `start` that holds a fit (`whole`).
        let mut best: Option<(Slot, bool)> = None;
        while slot != NIL {
            let node = self.node(slot);
            if node.offset < start {
                slot = node.right;
                continue;
            }
            if self.subtree_max(node.right) >= len {
                best = Some((node.right, true));
            }
            if node.size >= len {
                best = Some((slot, false));
            }
            slot = node.left;
        }
        let (slot, whole) = best?;
        if whole {
            self.first_fit_under(slot, len)
        } else {
            Some(slot)
        }
    }

    /// The largest free block starting in `range`, 0 when there is none. O(log F).
    pub fn largest_in(&self, range: std::ops::Range<u32>) -> u32 {
        let mut largest = 0;
        // Walk to the node where the paths to both ends split, then take the
        // subtrees wholly inside the range on each path.
        let mut slot = self.root;
        while slot != NIL {
            let node = self.node(slot);
            if node.offset < range.start {
                slot = node.right;
            } else if node.offset >= range.end {
                slot = node.left;
            } else {
                largest = node.size;
                largest = largest.max(self.largest_from(node.left, range.start));
                largest = largest.max(self.largest_below(node.right, range.end));
                break;
            }
        }
        largest
    }

    /// The largest free block of subtree `slot` at or above `start`.
    fn largest_from(&self, mut slot: Slot, start: u32) -> u32 {
        let mut largest = 0;
        while slot != NIL {
            let node = self.node(slot);
            if node.offset >= start {
                largest = largest.max(node.size).max(self.subtree_max(node.right));
                slot = node.left;
            } else {
                slot = node.right;
            }
        }
        largest
    }

    /// The largest free block of subtree `slot` below `end`.
    fn largest_below(&self, mut slot: Slot, end: u32) -> u32 {
        let mut largest = 0;
        while slot != NIL {
            let node = self.node(slot);
            if node.offset < end {
                largest = largest.max(node.size).max(self.subtree_max(node.left));
                slot = node.right;
            } else {
                slot = node.left;
            }
        }
        largest
    }

    /// The lowest free block of subtree `slot` holding at least `len` bytes.
    fn first_fit_under(&self, mut slot: Slot, len: u32) -> Option<Slot> {
        if self.subtree_max(slot) < len {
            return None;
        }
        loop {
            let node = self.node(slot);
            if self.subtree_max(node.left) >= len {
                slot = node.left;
            } else if node.size >= len {
                return Some(slot);
            } else {
                // The subtree holds a fit and it is neither left nor here.
                slot = node.right;
            }
        }
    }

    /// The free block with the greatest offset not above `offset`. O(log F).
    pub fn at_or_below(&self, offset: u32) -> Option<Slot> {
        let mut slot = self.root;
        let mut best = None;
        while slot != NIL {
            let node = self.node(slot);
            if node.offset <= offset {
                best = Some(slot);
                slot = node.right;
            } else {
                slot = node.left;
            }
        }
        best
    }

    fn node(&self, slot: Slot) -> &Node {
        &self.nodes[slot as usize]
    }

    fn node_mut(&mut self, slot: Slot) -> &mut Node {
        &mut self.nodes[slot as usize]
    }

    fn reset(&mut self, slot: Slot, offset: u32, size: u32) {
        let node = self.node_mut(slot);
        (node.left, node.right) = (NIL, NIL);
        (node.offset, node.size, node.max_size) = (offset, size, size);
    }

    fn subtree_max(&self, slot: Slot) -> u32 {
        if slot == NIL {
            0
        } else {
            self.node(slot).max_size
        }
    }

    fn update(&mut self, slot: Slot) {
        let Node { left, right, size, .. } = *self.node(slot);
        let children = self.subtree_max(left).max(self.subtree_max(right));
        self.node_mut(slot).max_size = size.max(children);
    }

    fn insert_at(&mut self, root: Slot, slot: Slot) -> Slot {
        if root == NIL {
            return slot;
        }
        let key = self.node(slot).offset;
        if self.node(slot).priority > self.node(root).priority {
            let (l, r) = self.split(root, key);
            let node = self.node_mut(slot);
            (node.left, node.right) = (l, r);
            self.update(slot);
            return slot;
        }
        let Node { left, right, offset, .. } = *self.node(root);
        if key < offset {
            self.node_mut(root).left = self.insert_at(left, slot);
        } else {
            self.node_mut(root).right = self.insert_at(right, slot);
        }
        self.update(root);
        root
    }

    fn remove_at(&mut self, root: Slot, key: u32) -> Slot {
        debug_assert!(root != NIL, "free index: key {key} not found");
        let Node { left, right, offset, .. } = *self.node(root);
        if key == offset {
            return self.join(left, right);
        }
        if key < offset {
            self.node_mut(root).left = self.remove_at(left, key);
        } else {
            self.node_mut(root).right = self.remove_at(right, key);
        }
        self.update(root);
        root
    }

    fn refresh_path(&mut self, root: Slot, key: u32) {
        debug_assert!(root != NIL, "free index: key {key} not found");
        let Node { left, right, offset, .. } = *self.node(root);
        if key < offset {
            self.refresh_path(left, key);
        } else if key > offset {
            self.refresh_path(right, key);
        }
        self.update(root);
    }

    /// Splits into keys below `key` and keys at or above it.
    fn split(&mut self, root: Slot, key: u32) -> (Slot, Slot) {
        if root == NIL {
            return (NIL, NIL);
        }
        let Node { left, right, offset, .. } = *self.node(root);
        if offset < key {
            let (l, rest) = self.split(right, key);
            self.node_mut(root).right = l;
            self.update(root);
            (root, rest)
        } else {
            let (rest, g) = self.split(left, key);
            self.node_mut(root).left = g;
            self.update(root);
            (rest, root)
        }
    }

    /// Joins two treaps where every key of `a` is below every key of `b`.
    fn join(&mut self, a: Slot, b: Slot) -> Slot {
        if a == NIL {
            return b;
        }
        if b == NIL {
            return a;
        }
        if self.node(a).priority > self.node(b).priority {
            let right = self.node(a).right;
            self.node_mut(a).right = self.join(right, b);
            self.update(a);
            a
        } else {
            let left = self.node(b).left;
            self.node_mut(b).left = self.join(a, left);
            self.update(b);
            b
        }
    }

    /// Calls `visit(slot, offset, size)` for every free block in address
    /// order. Recursive rather than with a stack so that the debug checks
    /// allocate nothing (the frame loop is checked for allocations).
    pub fn for_each(&self, visit: &mut dyn FnMut(Slot, u32, u32)) {
        self.visit_subtree(self.root, visit);
    }

    fn visit_subtree(&self, slot: Slot, visit: &mut dyn FnMut(Slot, u32, u32)) {
        if slot == NIL {
            return;
        }
        let node = *self.node(slot);
        self.visit_subtree(node.left, visit);
        visit(slot, node.offset, node.size);
        self.visit_subtree(node.right, visit);
    }

    /// Verifies ordering, heap priority and the size augmentation. O(F).
    pub fn check(&self) -> Result<(), String> {
        let (mut count, mut last, mut problem) = (0usize, None::<u32>, None::<String>);
        self.for_each(&mut |slot, offset, _| {
            count += 1;
            if last.is_some_and(|l| l >= offset) && problem.is_none() {
                problem = Some("free index keys out of order".into());
            }
            last = Some(offset);
            let node = self.node(slot);
            for child in [node.left, node.right] {
                if child != NIL && self.node(child).priority > node.priority && problem.is_none() {
                    problem = Some(format!("free index heap order broken at {slot}"));
                }
            }
            let expected =
                node.size.max(self.subtree_max(node.left)).max(self.subtree_max(node.right));
            if node.max_size != expected && problem.is_none() {
                problem = Some(format!("free index max_size stale at {slot}"));
            }
        });
        if count != self.len {
            return Err(format!("free index holds {count} nodes, counts {}", self.len));
        }
        problem.map_or(Ok(()), Err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Free blocks of 1..=40 bytes, 8 apart and more, at pseudo-random
    /// places: the range queries against a scan of the same blocks.
    #[test]
    fn range_queries_match_a_scan() {
        let mut index = FreeIndex::new(64);
        let mut blocks = Vec::new();
        let mut offset = 0u32;
        for slot in 0..64u32 {
            let size = 1 + (slot * 37 + 11) % 40;
            offset += 8 + (slot * 53) % 29;
            index.insert(slot, offset, size);
            blocks.push((slot, offset, size));
            offset += size;
        }
        index.check().expect("a valid treap");
        for start in (0..offset + 10).step_by(7) {
            for len in [1, 5, 20, 39, 40, 41] {
                let scan = blocks.iter().find(|b| b.1 >= start && b.2 >= len).map(|b| b.0);
                assert_eq!(index.first_fit_from(start, len), scan, "from {start}, {len} bytes");
            }
            for end in (start..offset + 10).step_by(13) {
                let inside = blocks.iter().filter(|b| (start..end).contains(&b.1));
                let scan = inside.map(|b| b.2).max().unwrap_or(0);
                assert_eq!(index.largest_in(start..end), scan, "in {start}..{end}");
            }
        }
    }
}
