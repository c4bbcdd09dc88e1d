//! Which of an extraction's meshes keep a post, worked out once per post
//! and tile: the tile's own mesh, the coarser sub-level's it morphs toward,
//! and its ancestors'. A leaf tile's meshes judge each post by the view
//! (distance, cone, band), and the walk asks about a post from both
//! triangles of its diamond, its target and the leaves drawn around it:
//! answered once, the walk costs one rule per post, not four to eight.

/// The meshes that keep one post (bits).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KeptBy(u8);

impl KeptBy {
    /// The tile's own map (asked only where no other map keeps the post:
    /// any bit makes it a vertex of the tile).
    pub const OWN: u8 = 1;
    /// The coarser sub-level's map (a leaf tile's target).
    pub const COARSER: u8 = 2;
    /// One of the node's resident ancestors' maps (the parent's surface).
    pub const ANCESTOR: u8 = 4;

    /// The set of `bits`.
    pub fn new(bits: u8) -> Self {
        debug_assert!(bits < 8);
        KeptBy(bits)
    }

    /// Whether the tile's mesh has a vertex there (every map it refines).
    pub fn by_tile(self) -> bool {
        self.0 != 0
    }

    /// Whether the mesh the tile morphs toward has one (the coarser
    /// sub-level's, or the parent's: both keep the ancestors' vertices).
    pub fn by_target(self) -> bool {
        self.0 & (Self::COARSER | Self::ANCESTOR) != 0
    }

    /// Whether the parent's mesh has one.
    pub fn by_parent(self) -> bool {
        self.0 & Self::ANCESTOR != 0
    }
}

/// Answers for the posts of one tile's closed square, worked out on first
/// ask; posts outside it (the midpoints of the few triangles wider than
/// the square) are worked out each time. Reused between tiles: no
/// allocation once the widest square has been seen.
#[derive(Default)]
pub struct KeptTable {
    /// Per post of the square, row by row: 0 not asked yet, else the
    /// answer's bits plus [`Self::ASKED`].
    answers: Vec<u8>,
    origin: [u32; 2],
    side: u32,
}

impl KeptTable {
    const ASKED: u8 = 0x80;

    /// Forgets every answer and covers the square of `width` map posts
    /// from post `origin`.
    pub fn reset(&mut self, origin: [u32; 2], width: u32) {
        self.origin = origin;
        self.side = width + 1;
        self.answers.clear();
        self.answers.resize((self.side as usize).pow(2), 0);
    }

    /// Which meshes keep map post `p`: from the table, or `work_out`'s
    /// answer (kept when `p` lies in the square).
    pub fn get(&mut self, p: [u32; 2], work_out: impl FnOnce() -> KeptBy) -> KeptBy {
        let local = [0, 1].map(|k| p[k].wrapping_sub(self.origin[k]));
        if local[0] >= self.side || local[1] >= self.side {
            return work_out();
        }
        let slot = &mut self.answers[(local[1] * self.side + local[0]) as usize];
        if *slot == 0 {
            *slot = work_out().0 | Self::ASKED;
        }
        KeptBy(*slot & !Self::ASKED)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn a_post_of_the_square_is_worked_out_once_and_one_outside_every_time() {
        let mut table = KeptTable::default();
        table.reset([10, 20], 4);
        let asked = Cell::new(0);
        let work = |bits| {
            asked.set(asked.get() + 1);
            KeptBy::new(bits)
        };
        for _ in 0..3 {
            assert_eq!(table.get([12, 24], || work(KeptBy::OWN)), KeptBy::new(KeptBy::OWN));
        }
        assert_eq!(asked.get(), 1);
        // Nothing kept is an answer too: asked once.
        for _ in 0..2 {
            assert!(!table.get([14, 20], || work(0)).by_tile());
        }
        assert_eq!(asked.get(), 2);
        for p in [[9, 20], [15, 20], [10, 25], [u32::MAX, 0]] {
            table.get(p, || work(KeptBy::ANCESTOR));
            table.get(p, || work(KeptBy::ANCESTOR));
        }
        assert_eq!(asked.get(), 10);
        table.reset([10, 20], 4);
        table.get([12, 24], || work(KeptBy::COARSER));
        assert_eq!(asked.get(), 11, "a reset forgets");
    }

    #[test]
    fn the_meshes_a_post_is_kept_by() {
        let parent = KeptBy::new(KeptBy::ANCESTOR);
        assert!(parent.by_tile() && parent.by_target() && parent.by_parent());
        let coarser = KeptBy::new(KeptBy::COARSER);
        assert!(coarser.by_tile() && coarser.by_target() && !coarser.by_parent());
        let own = KeptBy::new(KeptBy::OWN);
        assert!(own.by_tile() && !own.by_target() && !own.by_parent());
        assert!(!KeptBy::default().by_tile());
    }
}
