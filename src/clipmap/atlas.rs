//! The node atlas (Kühnert 4.5.1): a fixed number of slots holding the
//! resident nodes, shared by every view. Each slot is empty, pinned (the root
//! level, never evicted), used (wanted by a view this frame) or unused (still
//! resident as a cache, listed least recently used first and reused in that
//! order once the empty slots are gone).
//!
//! Counted in slots, all memory is taken at construction: every slot's
//! height buffer holds a whole node, the id -> slot map has room for twice
//! the slots (so removals' tombstones never make it grow), and the LRU list
//! is intrusive.
//!
//! Counted in bytes (a memory budget), slots start without buffers and the
//! atlas holds at most its byte budget of node buffers, each counted at its
//! own size ([`NodeData::heap_bytes`]): a node is refused when the resident
//! nodes no view wants cannot make room for it, and as many of those as it
//! takes are evicted, least recently used first, their buffers freed. Node
//! meshes differ threefold in size, so counting every slot at the largest
//! would hold a third of the nodes the same memory can.

use super::hash::{node_map, NodeMap};
use super::lru::SlotList;
use crate::node::{NodeData, NodeId, NodeLayout};

/// What a slot holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotState {
    /// No node: free for the next load.
    Empty,
    /// A root-level node: resident for the atlas's whole life.
    Pinned,
    /// Wanted by at least one view in the frame `last_used`.
    Used,
    /// Resident but wanted by no view since `last_used`; on the LRU list.
    Unused,
}

#[derive(Debug)]
struct Slot {
    node: Option<NodeId>,
    data: NodeData,
    state: SlotState,
    /// The last frame a view wanted the node.
    last_used: u64,
    /// Heap of `data` while resident, bytes (0 when empty).
    bytes: u64,
}

/// Where [`NodeAtlas::insert`] put a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Insertion {
    pub slot: u32,
    /// The unused node whose slot was reused, if any.
    pub evicted: Option<NodeId>,
}

/// The shared node store. Invariants (checked by [`NodeAtlas::check`]):
/// `index` maps exactly the resident nodes to their slots; `free` lists
/// exactly the empty slots; `unused` lists exactly the unused slots.
#[derive(Debug)]
pub struct NodeAtlas {
    slots: Vec<Slot>,
    index: NodeMap<u32>,
    free: Vec<u32>,
    unused: SlotList,
    /// Nodes inserted or evicted since the last [`NodeAtlas::clear_changes`].
    changes: Vec<NodeId>,
    /// The most bytes the resident nodes may take; `None`: counted in slots.
    byte_budget: Option<u64>,
    /// Bytes of the resident nodes (pinned, used and unused).
    resident_bytes: u64,
    /// Bytes of the unused ones: what eviction can free.
    unused_bytes: u64,
    /// Bytes of the pinned ones.
    pinned_bytes: u64,
}

impl NodeAtlas {
    /// The heap an atlas of `slot_count` slots takes for its tables alone
    /// (slots with empty buffers, the node index, the free and unused lists,
    /// the change list when bytes evict), bytes: it grows with the slots,
    /// not with the nodes read into them, so the memory budget plans it
    /// beside the nodes (1.45 MB of slots alone on the cruise over the
    /// procedural earth, past the 4 MB the budget keeps for the rest).
    pub fn table_bytes(slot_count: u32, changes_per_frame: usize) -> u64 {
        use std::mem::size_of;
        let slots = slot_count as u64;
        // hashbrown: buckets a power of two at most 7/8 full, a control
        // byte each.
        let buckets = ((2 * slots * 8).div_ceil(7)).next_power_of_two();
        let index = buckets * (size_of::<(NodeId, u32)>() as u64 + 1);
        let lists = slots * (size_of::<u32>() as u64 + SlotList::bytes_per_slot());
        let changes = (changes_per_frame as u64 + slots) * size_of::<NodeId>() as u64;
        slots * size_of::<Slot>() as u64 + index + lists + changes
    }

    /// An atlas of `slot_count` empty slots, holding at most `byte_budget`
    /// bytes of nodes when one is given; `changes_per_frame` sizes the
    /// change list (two per insertion: the node and the one it evicts).
    pub(crate) fn new(
        slot_count: u32,
        layout: &NodeLayout,
        changes_per_frame: usize,
        byte_budget: Option<u64>,
    ) -> Self {
        let buffer = || match byte_budget {
            None => NodeData::with_capacity(layout),
            // Buffers come with the nodes read into them.
            Some(_) => NodeData::default(),
        };
        let slots = (0..slot_count)
            .map(|_| Slot {
                node: None,
                data: buffer(),
                state: SlotState::Empty,
                last_used: 0,
                bytes: 0,
            })
            .collect();
        // Bytes evict as many nodes as it takes, each a change.
        let changes = changes_per_frame + byte_budget.map_or(0, |_| slot_count as usize);
        NodeAtlas {
            slots,
            index: node_map(2 * slot_count as usize),
            free: (0..slot_count).rev().collect(),
            unused: SlotList::new(slot_count),
            changes: Vec::with_capacity(changes),
            byte_budget,
            resident_bytes: 0,
            unused_bytes: 0,
            pinned_bytes: 0,
        }
    }

    /// The most bytes the resident nodes may take, when counted in bytes.
    pub fn byte_budget(&self) -> Option<u64> {
        self.byte_budget
    }

    /// Bytes the resident nodes' buffers take.
    pub fn resident_bytes(&self) -> u64 {
        self.resident_bytes
    }

    /// Bytes the pinned nodes take: never evicted, always counted.
    pub fn pinned_bytes(&self) -> u64 {
        self.pinned_bytes
    }

    /// Bytes the node in `slot` takes (0 when empty).
    pub fn bytes_in(&self, slot: u32) -> u64 {
        self.slots[slot as usize].bytes
    }

    /// Bytes a new node may take now, evicting unused ones: `None` when
    /// counted in slots.
    pub fn byte_room(&self) -> Option<u64> {
        let budget = self.byte_budget?;
        Some((budget + self.unused_bytes).saturating_sub(self.resident_bytes))
    }

    /// Slots in the atlas, resident or not.
    pub fn slot_count(&self) -> u32 {
        self.slots.len() as u32
    }

    /// Slots holding a node (pinned, in use or unused).
    pub fn resident_count(&self) -> u32 {
        self.index.len() as u32
    }

    /// Slots that a new node can take: empty ones and unused ones.
    pub fn available(&self) -> u32 {
        self.free.len() as u32 + self.unused.len()
    }

    /// The slot holding `id`, if it is resident.
    pub fn slot_of(&self, id: NodeId) -> Option<u32> {
        self.index.get(&id).copied()
    }

    /// The node in `slot`, if any.
    pub fn node_in(&self, slot: u32) -> Option<NodeId> {
        self.slots[slot as usize].node
    }

    /// The posts of the node in `slot` (stale when the slot is empty).
    pub fn data(&self, slot: u32) -> &NodeData {
        &self.slots[slot as usize].data
    }

    /// Whether `slot` is empty, pinned, in use or unused.
    pub fn state(&self, slot: u32) -> SlotState {
        self.slots[slot as usize].state
    }

    /// The last frame in which a view used `slot`.
    pub fn last_used(&self, slot: u32) -> u64 {
        self.slots[slot as usize].last_used
    }

    /// Unused slots, the next to be reused first.
    pub fn lru(&self) -> impl Iterator<Item = u32> + '_ {
        self.unused.iter()
    }

    /// A view wants the node in `slot` in `frame`.
    pub(crate) fn mark_used(&mut self, slot: u32, frame: u64) {
        let entry = &mut self.slots[slot as usize];
        match entry.state {
            SlotState::Pinned => return,
            SlotState::Unused => {
                self.unused.remove(slot);
                self.unused_bytes -= entry.bytes;
            }
            SlotState::Used => {}
            SlotState::Empty => unreachable!("slot {slot} is empty but indexed"),
        }
        entry.state = SlotState::Used;
        entry.last_used = frame;
    }

    /// Every used slot no view wanted in `frame` becomes unused, appended to
    /// the LRU list in slot order (they were all last used in `frame - 1`).
    pub(crate) fn release_unused(&mut self, frame: u64) {
        for slot in 0..self.slot_count() {
            let entry = &mut self.slots[slot as usize];
            if entry.state == SlotState::Used && entry.last_used < frame {
                entry.state = SlotState::Unused;
                self.unused.push_back(slot);
                self.unused_bytes += entry.bytes;
            }
        }
    }

    /// Makes `id` resident with the heights in `data`, taking an empty slot,
    /// else the least recently used unused one. The slot's previous buffer is
    /// swapped into `data` for reuse. `None` when every slot is in use, or
    /// when counted in bytes and the unused nodes cannot make room (pinned
    /// nodes are always taken: without the root level there is no display).
    pub(crate) fn insert(
        &mut self,
        id: NodeId,
        data: &mut NodeData,
        state: SlotState,
        frame: u64,
    ) -> Option<Insertion> {
        debug_assert!(matches!(state, SlotState::Pinned | SlotState::Used));
        debug_assert!(!self.index.contains_key(&id), "{id:?} is already resident");
        let bytes = data.heap_bytes();
        let fits = self.byte_room().is_none_or(|room| bytes <= room);
        if !fits && state != SlotState::Pinned {
            return None;
        }
        let slot = match self.free.pop() {
            Some(slot) => slot,
            None => {
                let slot = self.unused.pop_front()?;
                self.unused_bytes -= self.slots[slot as usize].bytes;
                slot
            }
        };
        let entry = &mut self.slots[slot as usize];
        let evicted = entry.node.replace(id);
        self.resident_bytes = self.resident_bytes - entry.bytes + bytes;
        entry.bytes = bytes;
        if let Some(old) = evicted {
            self.index.remove(&old);
            self.changes.push(old);
        }
        let entry = &mut self.slots[slot as usize];
        std::mem::swap(&mut entry.data, data);
        entry.state = state;
        entry.last_used = frame;
        if state == SlotState::Pinned {
            self.pinned_bytes += bytes;
        }
        self.index.insert(id, slot);
        self.changes.push(id);
        self.evict_over_budget();
        Some(Insertion { slot, evicted })
    }

    /// Counted in bytes: evicts unused nodes, least recently used first,
    /// freeing their buffers, until the resident ones fit the budget.
    fn evict_over_budget(&mut self) {
        let Some(budget) = self.byte_budget else { return };
        while self.resident_bytes > budget {
            let Some(slot) = self.unused.pop_front() else { return };
            let entry = &mut self.slots[slot as usize];
            let old = entry.node.take().expect("unused slots hold a node");
            self.resident_bytes -= entry.bytes;
            self.unused_bytes -= entry.bytes;
            entry.bytes = 0;
            entry.data = NodeData::default();
            entry.state = SlotState::Empty;
            self.index.remove(&old);
            self.free.push(slot);
            self.changes.push(old);
        }
    }

    /// Orders the changes coarsest first (so refreshing their footprints in
    /// this order reads fresh parents).
    pub(crate) fn sort_changes(&mut self) {
        self.changes.sort_unstable_by(|a, b| b.level.cmp(&a.level).then(a.cmp(b)));
    }

    /// Nodes whose residency changed since the last clear.
    pub(crate) fn changes(&self) -> &[NodeId] {
        &self.changes
    }

    pub(crate) fn clear_changes(&mut self) {
        self.changes.clear();
    }

    /// Checks the invariants, naming the first one broken.
    pub fn check(&self) -> Result<(), String> {
        let mut counts = [0u32; 4];
        for (slot, entry) in self.slots.iter().enumerate() {
            let slot = slot as u32;
            counts[entry.state as usize] += 1;
            let listed = self.unused.contains(slot);
            if listed != (entry.state == SlotState::Unused) {
                return Err(format!("slot {slot} is {:?} but listed={listed}", entry.state));
            }
            match (entry.state, entry.node) {
                (SlotState::Empty, None) => {}
                (SlotState::Empty, Some(id)) => {
                    return Err(format!("empty slot {slot} holds {id:?}"))
                }
                (_, None) => return Err(format!("{:?} slot {slot} holds nothing", entry.state)),
                (_, Some(id)) if self.index.get(&id) != Some(&slot) => {
                    return Err(format!("slot {slot} holds {id:?} but the index disagrees"));
                }
                _ => {}
            }
        }
        let resident = self.slot_count() - counts[SlotState::Empty as usize];
        if resident != self.resident_count()
            || counts[SlotState::Empty as usize] != self.free.len() as u32
        {
            return Err(format!(
                "{resident} resident slots, index {}, free {}",
                self.index.len(),
                self.free.len()
            ));
        }
        if counts[SlotState::Unused as usize] != self.unused.len() {
            return Err("the LRU list's length disagrees with the unused slots".into());
        }
        let held = |unused_only: bool| -> u64 {
            let counted =
                |e: &&Slot| e.node.is_some() && (!unused_only || e.state == SlotState::Unused);
            self.slots.iter().filter(counted).map(|e| e.bytes).sum()
        };
        if held(false) != self.resident_bytes || held(true) != self.unused_bytes {
            return Err(format!(
                "resident bytes {} (counted {}), unused {} (counted {})",
                held(false),
                self.resident_bytes,
                held(true),
                self.unused_bytes
            ));
        }
        let in_order =
            self.lru().zip(self.lru().skip(1)).all(|(a, b)| self.last_used(a) <= self.last_used(b));
        if !in_order {
            return Err("the LRU list is not ordered by last use".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> NodeLayout {
        NodeLayout { levels: 4, node_size: 2, border: 0, posts: [17, 17], spacing_m: [1.0, 1.0] }
    }

    fn node(marker: f32) -> NodeData {
        NodeData { heights: vec![marker; 9], ..NodeData::default() }
    }

    #[test]
    fn reuses_empty_slots_then_the_least_recently_used() {
        let mut atlas = NodeAtlas::new(4, &layout(), 8, None);
        let root = NodeId::new(3, 0, 0);
        let ids: Vec<NodeId> = (0..5).map(|x| NodeId::new(0, x, 0)).collect();
        atlas.insert(root, &mut node(9.0), SlotState::Pinned, 0).unwrap();
        // Frame 1: ids 0..3 arrive; the buffers handed back are the slots' empty ones.
        for (k, &id) in ids[..3].iter().enumerate() {
            let mut data = node(k as f32);
            assert_eq!(atlas.insert(id, &mut data, SlotState::Used, 1).unwrap().evicted, None);
            assert!(data.heights.is_empty());
        }
        assert_eq!(
            atlas.insert(ids[3], &mut node(3.0), SlotState::Used, 1),
            None,
            "all slots in use"
        );
        // Frame 2 wants only ids 0 and 2; frame 3 only id 2 (and the pinned root, always).
        for (frame, wanted) in [(2, vec![ids[0], ids[2]]), (3, vec![ids[2]])] {
            for id in wanted {
                atlas.mark_used(atlas.slot_of(id).unwrap(), frame);
            }
            atlas.release_unused(frame);
            atlas.check().unwrap();
        }
        let order: Vec<NodeId> = atlas.lru().map(|s| atlas.node_in(s).unwrap()).collect();
        assert_eq!(order, vec![ids[1], ids[0]], "id 1 was last used in frame 1, id 0 in frame 2");
        let mut data = node(3.0);
        let first = atlas.insert(ids[3], &mut data, SlotState::Used, 3).unwrap();
        assert_eq!(
            (first.evicted, data.heights[0]),
            (Some(ids[1]), 1.0),
            "the old buffer comes back"
        );
        let second = atlas.insert(ids[4], &mut node(4.0), SlotState::Used, 3).unwrap();
        assert_eq!(second.evicted, Some(ids[0]));
        assert_eq!(atlas.insert(ids[1], &mut node(1.0), SlotState::Used, 3), None);
        assert_eq!(atlas.data(atlas.slot_of(root).unwrap()).heights[0], 9.0);
        assert_eq!(atlas.resident_count(), 4);
        let (n0, n1, n3, n4) = (ids[0], ids[1], ids[3], ids[4]);
        atlas.sort_changes();
        assert_eq!(atlas.changes()[..], [root, n0, n0, n1, n1, ids[2], n3, n4]);
        atlas.clear_changes();
        assert!(atlas.changes().is_empty());
        atlas.check().unwrap();
    }

    fn sized(bytes: usize) -> NodeData {
        let mut data = NodeData { heights: Vec::with_capacity(bytes / 4), ..NodeData::default() };
        data.heights.resize(bytes / 4, 0.0);
        data
    }

    #[test]
    fn a_byte_budget_evicts_unused_nodes_until_a_new_one_fits() {
        let mut atlas = NodeAtlas::new(8, &layout(), 8, Some(1000));
        let ids: Vec<NodeId> = (0..4).map(|x| NodeId::new(0, x, 0)).collect();
        for &id in &ids[..3] {
            atlas.insert(id, &mut sized(300), SlotState::Used, 1).unwrap();
        }
        assert_eq!(atlas.resident_bytes(), 900);
        // All in use: a fourth does not fit, though slots are free.
        assert_eq!(atlas.insert(ids[3], &mut sized(300), SlotState::Used, 1), None);
        // Frame 2 wants only the last two: the first is evicted for the fourth.
        for &id in &ids[1..3] {
            atlas.mark_used(atlas.slot_of(id).unwrap(), 2);
        }
        atlas.release_unused(2);
        assert_eq!(atlas.byte_room(), Some(400));
        let mut big = sized(400);
        assert!(atlas.insert(ids[3], &mut big, SlotState::Used, 2).is_some());
        assert_eq!(atlas.slot_of(ids[0]), None, "evicted for room");
        assert_eq!(atlas.resident_bytes(), 1000);
        atlas.check().unwrap();
    }

    proptest::proptest! {
        /// Against a model of what is resident and wanted: the byte budget
        /// is never exceeded, a node is refused exactly when the unused
        /// nodes cannot make room, only unused nodes are evicted, and the
        /// invariants hold after every step.
        #[test]
        fn a_byte_budget_holds_against_a_model(
            steps in proptest::collection::vec((0u32..12, 1usize..100, proptest::bool::ANY), 1..80),
        ) {
            const BUDGET: u64 = 1000;
            let mut atlas = NodeAtlas::new(6, &layout(), 16, Some(BUDGET));
            let mut frame = 1;
            for (x, words, next_frame) in steps {
                let id = NodeId::new(0, x, 0);
                if next_frame {
                    // A new frame wants the nodes of even x.
                    frame += 1;
                    for x in (0..12).step_by(2) {
                        if let Some(slot) = atlas.slot_of(NodeId::new(0, x, 0)) {
                            atlas.mark_used(slot, frame);
                        }
                    }
                    atlas.release_unused(frame);
                }
                if atlas.slot_of(id).is_some() {
                    continue;
                }
                let used: Vec<NodeId> = (0..12)
                    .map(|x| NodeId::new(0, x, 0))
                    .filter(|&n| atlas.slot_of(n).is_some_and(|s| atlas.state(s) == SlotState::Used))
                    .collect();
                let bytes = words as u64 * 4 * 4;
                let room = BUDGET + unused_bytes(&atlas) - atlas.resident_bytes();
                let slots = atlas.available() > 0;
                let inserted = atlas.insert(id, &mut sized(bytes as usize), SlotState::Used, frame);
                proptest::prop_assert_eq!(inserted.is_some(), bytes <= room && slots);
                proptest::prop_assert!(atlas.resident_bytes() <= BUDGET);
                for n in used {
                    proptest::prop_assert!(atlas.slot_of(n).is_some(), "{:?} was in use", n);
                }
                proptest::prop_assert_eq!(atlas.check(), Ok(()));
            }
        }
    }

    fn unused_bytes(atlas: &NodeAtlas) -> u64 {
        atlas.lru().map(|slot| atlas.bytes_in(slot)).sum()
    }
}
