//! The paper's count of cluster shapes (Judnich & Ling, Figs. 3, 5 and 6):
//! a cluster's shape is which of its slots hold a member, and whether each
//! is a fine member (two levels below the root) or a coarse one. Rotating a
//! shape by 90° about the root's centre gives a shape of the same batch.
//!
//! Ridgeline draws clusters from their members' own vertices, so it needs
//! no template per shape; the count says how many the paper's GPU holds.

use super::slot_quadrant;

/// A shape: bit `slot` for a fine member at `slot` (0..16), bit `16 + q`
/// for a coarse member filling quadrant `q` (0..4).
pub type Shape = u32;

/// Whether a quadrant of a two-level cluster is empty, one coarse tile or
/// four fine tiles (the paper's 3 states a quadrant).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quadrant {
    /// No member there.
    Empty,
    /// One tile a level below the root.
    One,
    /// Four tiles two levels below the root.
    Four,
}

/// The shape of a two-level cluster from its quadrants (south-west,
/// south-east, north-west, north-east).
pub fn shape_of(quadrants: [Quadrant; 4]) -> Shape {
    let mut shape = 0;
    for (q, state) in quadrants.iter().enumerate() {
        match state {
            Quadrant::Empty => {}
            Quadrant::One => shape |= 1 << (16 + q),
            Quadrant::Four => {
                for slot in 0..16u8 {
                    if slot_quadrant(slot) as usize == q {
                        shape |= 1 << slot;
                    }
                }
            }
        }
    }
    shape
}

/// `shape` turned 90° counter-clockwise about the root's centre.
pub fn rotate(shape: Shape) -> Shape {
    let mut turned = 0;
    for slot in 0..16u32 {
        if shape & (1 << slot) != 0 {
            let (x, y) = (slot % 4, slot / 4);
            // (x, y) -> (3 - y, x) on the 4 x 4 lattice.
            turned |= 1 << ((3 - y) + 4 * x);
        }
    }
    for q in 0..4u32 {
        if shape & (1 << (16 + q)) != 0 {
            let (x, y) = (q % 2, q / 2);
            turned |= 1 << (16 + (1 - y) + 2 * x);
        }
    }
    turned
}

/// The smallest of `shape`'s four rotations: one name per batch.
pub fn canonical(shape: Shape) -> Shape {
    let mut best = shape;
    let mut turned = shape;
    for _ in 0..3 {
        turned = rotate(turned);
        best = best.min(turned);
    }
    best
}

/// The shape of a cluster from its members' slots and whether each is coarse.
pub fn shape_of_members(members: impl Iterator<Item = (u8, bool)>) -> Shape {
    members.fold(0, |shape, (slot, coarse)| {
        shape | if coarse { 1 << (16 + slot_quadrant(slot)) } else { 1 << slot }
    })
}

/// Every two-level state (3^4 = 81, the empty one included).
pub fn two_level_states() -> impl Iterator<Item = [Quadrant; 4]> {
    const STATES: [Quadrant; 3] = [Quadrant::Empty, Quadrant::One, Quadrant::Four];
    (0..81usize).map(|n| [0, 1, 2, 3].map(|q| STATES[n / 3usize.pow(q) % 3]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    #[test]
    fn the_papers_23_batches_and_its_5_single_level_geometries() {
        let two_level: BTreeSet<Shape> =
            two_level_states().map(|q| canonical(shape_of(q))).filter(|&s| s != 0).collect();
        assert_eq!(two_level.len(), 23, "Fig. 6: 23 batches");
        // Single-level clusters (Fig. 3): each quadrant a leaf or not, 16
        // states; 6 seeds up to rotation (Fig. 5), 5 without the blank one.
        let single: BTreeSet<Shape> = two_level_states()
            .filter(|q| !q.contains(&Quadrant::Four))
            .map(|q| canonical(shape_of(q)))
            .collect();
        assert_eq!(single.len(), 6);
        assert_eq!(single.iter().filter(|&&s| s != 0).count(), 5);
        // Burnside: (81 + 3 + 9 + 3) / 4 = 24 orbits, the empty one among them.
        assert_eq!(two_level_states().count(), 81);
    }

    #[test]
    fn four_turns_are_the_identity() {
        for q in two_level_states() {
            let shape = shape_of(q);
            assert_eq!(rotate(rotate(rotate(rotate(shape)))), shape);
            assert_eq!(rotate(shape).count_ones(), shape.count_ones());
        }
    }
}
