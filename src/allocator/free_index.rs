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

pub(crate) struct FreeIndex {
    left: Vec<Slot>,
    right: Vec<Slot>,
    offset: Vec<u32>,
    size: Vec<u32>,
    max_size: Vec<u32>,
    root: Slot,
    len: usize,
}

/// A well-mixed, fixed priority per slot (splitmix64 finaliser).
fn priority(slot: Slot) -> u64 {
    let mut z = (slot as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl FreeIndex {
    pub fn new(max_blocks: u32) -> Self {
        let n = max_blocks as usize;
        FreeIndex {
            left: vec![NIL; n],
            right: vec![NIL; n],
            offset: vec![0; n],
            size: vec![0; n],
            max_size: vec![0; n],
            root: NIL,
            len: 0,
        }
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
        let i = slot as usize;
        self.left[i] = NIL;
        self.right[i] = NIL;
        self.offset[i] = offset;
        self.size[i] = size;
        self.max_size[i] = size;
        self.root = self.insert_at(self.root, slot);
        self.len += 1;
    }

    /// Removes the free block `slot`, which starts at the key it was given. O(log F).
    pub fn remove(&mut self, slot: Slot) {
        let key = self.offset[slot as usize];
        self.root = self.remove_at(self.root, key);
        self.len -= 1;
    }

    /// Changes the extent of an indexed block whose position among the free
    /// blocks stays the same (it grew into a merged neighbour, or the allocator
    /// carved bytes off its front). O(log F).
    pub fn resize(&mut self, slot: Slot, offset: u32, size: u32) {
        self.offset[slot as usize] = offset;
        self.size[slot as usize] = size;
        self.refresh_path(self.root, offset);
    }

    /// The free block at the lowest address holding at least `len` bytes. O(log F).
    pub fn first_fit(&self, len: u32) -> Option<Slot> {
        let mut node = self.root;
        if self.subtree_max(node) < len {
            return None;
        }
        loop {
            let i = node as usize;
            if self.subtree_max(self.left[i]) >= len {
                node = self.left[i];
            } else if self.size[i] >= len {
                return Some(node);
            } else {
                // The subtree holds a fit and it is neither left nor here.
                node = self.right[i];
            }
        }
    }

    /// The free block with the greatest offset not above `offset`. O(log F).
    pub fn at_or_below(&self, offset: u32) -> Option<Slot> {
        let mut node = self.root;
        let mut best = None;
        while node != NIL {
            let i = node as usize;
            if self.offset[i] <= offset {
                best = Some(node);
                node = self.right[i];
            } else {
                node = self.left[i];
            }
        }
        best
    }

    fn subtree_max(&self, node: Slot) -> u32 {
        if node == NIL {
            0
        } else {
            self.max_size[node as usize]
        }
    }

    fn update(&mut self, node: Slot) {
        let i = node as usize;
        let children = self.subtree_max(self.left[i]).max(self.subtree_max(self.right[i]));
        self.max_size[i] = self.size[i].max(children);
    }

    fn insert_at(&mut self, root: Slot, node: Slot) -> Slot {
        if root == NIL {
            return node;
        }
        let key = self.offset[node as usize];
        if priority(node) > priority(root) {
            let (l, r) = self.split(root, key);
            self.left[node as usize] = l;
            self.right[node as usize] = r;
            self.update(node);
            return node;
        }
        let r = root as usize;
        if key < self.offset[r] {
            self.left[r] = self.insert_at(self.left[r], node);
        } else {
            self.right[r] = self.insert_at(self.right[r], node);
        }
        self.update(root);
        root
    }

    fn remove_at(&mut self, root: Slot, key: u32) -> Slot {
        debug_assert!(root != NIL, "free index: key {key} not found");
        let r = root as usize;
        if key == self.offset[r] {
            return self.join(self.left[r], self.right[r]);
        }
        if key < self.offset[r] {
            self.left[r] = self.remove_at(self.left[r], key);
        } else {
            self.right[r] = self.remove_at(self.right[r], key);
        }
        self.update(root);
        root
    }

    fn refresh_path(&mut self, root: Slot, key: u32) {
        debug_assert!(root != NIL, "free index: key {key} not found");
        let r = root as usize;
        if key < self.offset[r] {
            self.refresh_path(self.left[r], key);
        } else if key > self.offset[r] {
            self.refresh_path(self.right[r], key);
        }
        self.update(root);
    }

    /// Splits into keys below `key` and keys at or above it.
    fn split(&mut self, root: Slot, key: u32) -> (Slot, Slot) {
        if root == NIL {
            return (NIL, NIL);
        }
        let r = root as usize;
        if self.offset[r] < key {
            let (l, rest) = self.split(self.right[r], key);
            self.right[r] = l;
            self.update(root);
            (root, rest)
        } else {
            let (rest, g) = self.split(self.left[r], key);
            self.left[r] = g;
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
        if priority(a) > priority(b) {
            let ai = a as usize;
            self.right[ai] = self.join(self.right[ai], b);
            self.update(a);
            a
        } else {
            let bi = b as usize;
            self.left[bi] = self.join(a, self.left[bi]);
            self.update(b);
            b
        }
    }

    /// In-order list of `(slot, offset, size)`; for checks and tests only.
    pub fn entries(&self) -> Vec<(Slot, u32, u32)> {
        let mut out = Vec::with_capacity(self.len);
        let mut stack = Vec::new();
        let mut node = self.root;
        while node != NIL || !stack.is_empty() {
            while node != NIL {
                stack.push(node);
                node = self.left[node as usize];
            }
            let top = stack.pop().expect("stack is non-empty here");
            let i = top as usize;
            out.push((top, self.offset[i], self.size[i]));
            node = self.right[i];
        }
        out
    }

    /// Verifies ordering, heap priority and the size augmentation. O(F).
    pub fn check(&self) -> Result<(), String> {
        let entries = self.entries();
        if entries.len() != self.len {
            return Err(format!("free index holds {} nodes, counts {}", entries.len(), self.len));
        }
        if entries.windows(2).any(|w| w[0].1 >= w[1].1) {
            return Err("free index keys out of order".into());
        }
        for &(slot, _, _) in &entries {
            let i = slot as usize;
            for child in [self.left[i], self.right[i]] {
                if child != NIL && priority(child) > priority(slot) {
                    return Err(format!("free index heap order broken at {slot}"));
                }
            }
            let expected = self.size[i]
                .max(self.subtree_max(self.left[i]))
                .max(self.subtree_max(self.right[i]));
            if self.max_size[i] != expected {
                return Err(format!("free index max_size stale at {slot}"));
            }
        }
        Ok(())
    }
}
