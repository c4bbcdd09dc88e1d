//! The node atlas (Kühnert 4.5.1): a fixed number of slots holding the
//! resident nodes, shared by every view. Each slot is empty, pinned (the root
//! level, never evicted), used (wanted by a view this frame) or unused (still
//! resident as a cache, listed least recently used first and reused in that
//! order once the empty slots are gone).
//!
//! All memory is taken at construction: every slot's height buffer holds a
//! whole node, the id -> slot map has room for twice the slots (so removals'
//! tombstones never make it grow), and the LRU list is intrusive.

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
}

impl NodeAtlas {
    /// An atlas of `slot_count` empty slots; `changes_per_frame` sizes the
    /// change list (two per insertion: the node and the one it evicts).
    pub(crate) fn new(slot_count: u32, layout: &NodeLayout, changes_per_frame: usize) -> Self {
        let slots = (0..slot_count)
            .map(|_| Slot {
                node: None,
                data: NodeData::with_capacity(layout),
                state: SlotState::Empty,
                last_used: 0,
            })
            .collect();
        NodeAtlas {
            slots,
            index: node_map(2 * slot_count as usize),
            free: (0..slot_count).rev().collect(),
            unused: SlotList::new(slot_count),
            changes: Vec::with_capacity(changes_per_frame),
        }
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
            SlotState::Unused => self.unused.remove(slot),
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
            }
        }
    }

    /// Makes `id` resident with the heights in `data`, taking an empty slot,
    /// else the least recently used unused one. The slot's previous buffer is
    /// swapped into `data` for reuse. `None` when every slot is in use.
    pub(crate) fn insert(
        &mut self,
        id: NodeId,
        data: &mut NodeData,
        state: SlotState,
        frame: u64,
    ) -> Option<Insertion> {
        debug_assert!(matches!(state, SlotState::Pinned | SlotState::Used));
        debug_assert!(!self.index.contains_key(&id), "{id:?} is already resident");
        let slot = self.free.pop().or_else(|| self.unused.pop_front())?;
        let entry = &mut self.slots[slot as usize];
        let evicted = entry.node.replace(id);
        if let Some(old) = evicted {
            self.index.remove(&old);
            self.changes.push(old);
        }
        let entry = &mut self.slots[slot as usize];
        std::mem::swap(&mut entry.data, data);
        entry.state = state;
        entry.last_used = frame;
        self.index.insert(id, slot);
        self.changes.push(id);
        Some(Insertion { slot, evicted })
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
        let mut atlas = NodeAtlas::new(4, &layout(), 8);
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
}
