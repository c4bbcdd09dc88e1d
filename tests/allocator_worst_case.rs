//! The paper's worst case, (2k - 2) S for k equal blocks, against an exhaustive
//! search of every state the allocator can reach (replayed on the real one).

use ridgeline::allocator::worst_case::{replay, search, Move, Moves};

/// The worst case the search finds, floor((k + 1)^2 / 4).
fn quadratic(k: u32) -> u32 {
    (k + 1) * (k + 1) / 4
}

#[test]
fn exhaustive_worst_case_for_k_up_to_7() {
    for allowed in [Moves::Any, Moves::ReallocateOnly] {
        for k in 1..=7 {
            let result = search(k, allowed);
            println!(
                "{allowed:?} k = {k}: paper (2k-2) = {} S, found {} S over {} states, witness {:?}",
                result.paper_bound, result.found, result.states, result.witness
            );
            assert_eq!(result.found, quadratic(k), "{allowed:?} k = {k}");
            assert_eq!(replay(&result.witness, k), result.worst_state);
        }
    }
}

#[test]
fn paper_bound_is_broken_from_k_5() {
    for k in 2..=4 {
        assert_eq!(search(k, Moves::ReallocateOnly).found, 2 * k - 2, "k = {k}");
    }
    for k in 5..=7 {
        let result = search(k, Moves::ReallocateOnly);
        assert!(result.found > result.paper_bound, "k = {k}");
    }
}

/// A hand-checked counterexample for k = 5 (the paper allows 8 S):
/// fill slots 0..5; reallocate the blocks at 0 and 3, which leaves gaps of one
/// slot each, so the run of two goes to 5..7; then reallocate the blocks at 1,
/// 4 and 6: the gaps [0, 2) and [3, 5) hold two slots each, so the run of three
/// goes to 6..9. The live blocks sit at 2, 5, 6, 7 and 8: nine slots.
#[test]
fn five_blocks_need_nine_slots() {
    let moves = [
        Move::Allocate { mask: 0, new: 5 },
        Move::Allocate { mask: 0b0_1001, new: 0 },
        Move::Allocate { mask: 0b101_0010, new: 0 },
    ];
    assert_eq!(replay(&moves, 5), 0b1_1110_0100);
}
