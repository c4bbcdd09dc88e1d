//! The atlas's unused resident slots in least-recently-used order: an
//! intrusive doubly-linked list over slot indices, sized once, with O(1)
//! append, removal and pop and no allocation afterwards.

const NIL: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Link {
    prev: u32,
    next: u32,
    linked: bool,
}

/// Slots in the order they were appended; the front is the least recently
/// used. Invariant: `len` equals the number of linked slots, and following
/// `next` from `head` visits exactly them and ends at `tail`.
#[derive(Clone, Debug)]
pub(crate) struct SlotList {
    links: Vec<Link>,
    head: u32,
    tail: u32,
    len: u32,
}

impl SlotList {
    /// Heap bytes a slot takes in the list.
    pub(crate) fn bytes_per_slot() -> u64 {
        std::mem::size_of::<Link>() as u64
    }

    pub fn new(slots: u32) -> Self {
        let unlinked = Link { prev: NIL, next: NIL, linked: false };
        SlotList { links: vec![unlinked; slots as usize], head: NIL, tail: NIL, len: 0 }
    }

    pub fn len(&self) -> u32 {
        self.len
    }

    pub fn contains(&self, slot: u32) -> bool {
        self.links[slot as usize].linked
    }

    /// Appends `slot` as the most recently used.
    pub fn push_back(&mut self, slot: u32) {
        debug_assert!(!self.contains(slot), "slot {slot} is already listed");
        self.links[slot as usize] = Link { prev: self.tail, next: NIL, linked: true };
        match self.tail {
            NIL => self.head = slot,
            tail => self.links[tail as usize].next = slot,
        }
        self.tail = slot;
        self.len += 1;
    }

    pub fn remove(&mut self, slot: u32) {
        let Link { prev, next, linked } = self.links[slot as usize];
        debug_assert!(linked, "slot {slot} is not listed");
        match prev {
            NIL => self.head = next,
            prev => self.links[prev as usize].next = next,
        }
        match next {
            NIL => self.tail = prev,
            next => self.links[next as usize].prev = prev,
        }
        self.links[slot as usize] = Link { prev: NIL, next: NIL, linked: false };
        self.len -= 1;
    }

    /// Removes and returns the least recently used slot.
    pub fn pop_front(&mut self) -> Option<u32> {
        let head = self.head;
        (head != NIL).then(|| {
            self.remove(head);
            head
        })
    }

    /// Least recently used first.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        std::iter::successors((self.head != NIL).then_some(self.head), |&slot| {
            let next = self.links[slot as usize].next;
            (next != NIL).then_some(next)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_append_order_through_removals() {
        let mut list = SlotList::new(6);
        for slot in [3, 0, 5, 1] {
            list.push_back(slot);
        }
        list.remove(5);
        list.push_back(5);
        assert_eq!(list.iter().collect::<Vec<_>>(), vec![3, 0, 1, 5]);
        assert_eq!(list.pop_front(), Some(3));
        list.remove(5);
        assert_eq!(list.iter().collect::<Vec<_>>(), vec![0, 1]);
        assert_eq!((list.len(), list.contains(1), list.contains(3)), (2, true, false));
        assert_eq!(
            (list.pop_front(), list.pop_front(), list.pop_front()),
            (Some(0), Some(1), None)
        );
        assert_eq!(list.iter().count(), 0);
    }
}
