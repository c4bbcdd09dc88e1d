//! Valid life (Wu et al. section 5): a tile's split test is re-evaluated only
//! once the camera, moving at most a declared distance per frame, can have
//! changed its outcome.
//!
//! Ridgeline's split test is Ulrich's: a tile of level `l` splits while the
//! distance `d` from the eye to its bounding box is below the ring `s_l`
//! ([`super::LevelRings`]). Its split zone is therefore the box grown by
//! `s_l`, and the outcome cannot change while `|d - s_l|` (the *slack*)
//! exceeds what `d` and `s_l` can have moved since the test:
//! - `d` is 1-Lipschitz in the eye, so it moves at most the camera's travel,
//!   at most the declared `max_travel_m` per frame. On the ellipsoid the eye
//!   is its ECEF point, so the travel is the earth's, not the chart's (which
//!   understates it wherever the chart's scale is below the earth's: north
//!   and south away from the equator over a global grid, 0.8 % at 60 N);
//! - on the ellipsoid the boxes are in the camera's axes (east, north, up at
//!   the eye), which turn as the eye moves: a box's faces move by at most
//!   the turn (the axes' change, `|M' - M|`, bounded by its Frobenius norm)
//!   times the distance to its farthest corner, so `d` by `sqrt 3` times
//!   that. A test made at `far` metres from that corner with slack `S`
//!   spends the turn at `sqrt 3 (far + 2 S)` metres a radian (its far
//!   corner moves by less than `sqrt 3 S` while it lives);
//! - `s_l` moves when tau (the budget) or the viewport changes; the rings are
//!   known every frame, so their change is added exactly.
//!
//! Each level keeps a *drift*: the sum, over frames, of `max_travel_m` plus
//! the change of its ring. A test made when the drift was `D` with slack
//! `S` stays valid while the drift is below `D + S`: its life in frames is
//! `S / max_travel_m` while the rings hold still, Wu's `(d − 2r) / v_h`
//! with our split zone (see [`super::split_zone`] for his); the turn since
//! the test, weighted as above, is spent from the same slack. A test is also
//! redone when the tile's height bounds change (paging brings a finer node,
//! or evicts one), and every test is redone (a *full re-evaluation*) when the
//! camera moved farther than declared, on the first frame, when the display
//! moves between the chart and the ellipsoid, or when the number of levels
//! changes: a jump or a paused window never leaves a stale
//! decision.
//!
//! Tests are kept in a fixed set-associative table (4 ways a set, least
//! recently seen replaced): a tile whose entry was replaced is simply tested
//! again, so the table's size trades re-evaluations, never correctness, and
//! a frame allocates nothing.

use super::TileKey;
use glam::{DMat3, DVec3};

/// Levels a table tracks; rings with more levels are tested every frame.
pub const MAX_LEVELS: usize = 32;
/// Ways per set of the table.
const WAYS: usize = 4;
/// `sqrt 3`: a box's faces each moving by `m` move its distance by at most
/// `sqrt 3 m`.
const SQRT_3: f64 = 1.732_050_807_568_877_2;
/// Metres of slack given up against rounding in the distance and the rings.
const SLACK_MARGIN_M: f64 = 1e-6;

/// What the valid life did in one selection.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LifeStats {
    /// Split tests a full re-evaluation makes this frame: tiles of level
    /// above 0 the traversal reaches and the frustum keeps.
    pub candidates: u32,
    /// Of those, the tests actually made (life run out, bounds changed,
    /// never tested, or a full re-evaluation).
    pub re_evaluated: u32,
    /// Whether every test was made this frame, and why not otherwise.
    pub full: bool,
}

impl LifeStats {
    /// `re_evaluated / candidates` (0 without candidates).
    pub fn fraction(&self) -> f64 {
        if self.candidates == 0 {
            0.0
        } else {
            self.re_evaluated as f64 / self.candidates as f64
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    key: Option<TileKey>,
    /// Table epoch the entry was made in; older epochs are void.
    epoch: u32,
    /// Frame the entry was last used (replacement).
    seen: u32,
    /// Valid while the level's drift plus `turn_m` times the turn so far
    /// is below this.
    until: f64,
    /// Metres of slack a radian of the camera's axes' turn spends.
    turn_m: f64,
    split: bool,
    bounds: (f32, f32),
}

/// The valid-life state of one selector.
#[derive(Clone, Debug)]
pub struct ValidLife {
    max_travel_m: f64,
    entries: Vec<Entry>,
    sets: usize,
    epoch: u32,
    frame: u32,
    drift: [f64; MAX_LEVELS],
    last_split: [f64; MAX_LEVELS],
    last_levels: usize,
    last_eye: Option<DVec3>,
    /// The camera's axes at the last selection (on the ellipsoid).
    last_axes: Option<DMat3>,
    /// The camera's axes' turn, summed over frames, radians (a bound).
    turned: f64,
    stats: LifeStats,
}

impl ValidLife {
    /// A table for about `tiles` tested tiles a frame, the camera declared
    /// to move at most `max_travel_m` metres a frame (finite, above 0).
    pub fn new(max_travel_m: f64, tiles: usize) -> Self {
        debug_assert!(max_travel_m.is_finite() && max_travel_m > 0.0);
        let sets = (tiles.max(16) * 4 / WAYS).next_power_of_two();
        ValidLife {
            max_travel_m,
            entries: vec![Entry::default(); sets * WAYS],
            sets,
            epoch: 0,
            frame: 0,
            drift: [0.0; MAX_LEVELS],
            last_split: [0.0; MAX_LEVELS],
            last_levels: 0,
            last_eye: None,
            last_axes: None,
            turned: 0.0,
            stats: LifeStats::default(),
        }
    }

    /// The declared travel per frame, metres.
    pub fn max_travel_m(&self) -> f64 {
        self.max_travel_m
    }

    /// What the last selection did.
    pub fn stats(&self) -> LifeStats {
        self.stats
    }

    /// Starts a selection from `eye` (ECEF on the ellipsoid, whose camera
    /// axes are `axes`; else the chart's point, `axes` `None`) with the
    /// rings' split distances `split(level)` for `levels` levels: ages every
    /// test by one frame, or voids them all when the camera moved farther
    /// than declared.
    pub fn begin(
        &mut self,
        eye: DVec3,
        axes: Option<DMat3>,
        levels: usize,
        split: impl Fn(u8) -> f64,
    ) {
        self.frame = self.frame.wrapping_add(1);
        let jumped = self.last_eye.is_none_or(|last| last.distance(eye) > self.max_travel_m);
        let reframed = axes.is_some() != self.last_axes.is_some();
        let full = jumped || reframed || levels != self.last_levels || levels > MAX_LEVELS;
        for level in 0..levels.min(MAX_LEVELS) {
            let now = split(level as u8);
            let moved = (now - self.last_split[level]).abs();
            self.drift[level] += if full { 0.0 } else { self.max_travel_m + moved };
            self.last_split[level] = now;
        }
        if let (Some(now), Some(last), false) = (axes, self.last_axes, full) {
            let change = now - last;
            let squares = [change.x_axis, change.y_axis, change.z_axis].map(|c| c.length_squared());
            self.turned += squares.iter().sum::<f64>().sqrt();
        }
        if full {
            self.epoch = self.epoch.wrapping_add(1);
        }
        self.last_eye = Some(eye);
        self.last_axes = axes;
        self.last_levels = levels;
        self.stats = LifeStats { full, ..LifeStats::default() };
    }

    /// Whether `key`, whose box has height `bounds`, splits against its ring
    /// `split_m`: the kept outcome while its life lasts, else tested again
    /// (and kept) on `distance()`: the distance to the box and to its
    /// farthest corner.
    pub fn splits(
        &mut self,
        key: TileKey,
        bounds: (f32, f32),
        split_m: f64,
        distance: impl FnOnce() -> (f64, f64),
    ) -> bool {
        self.stats.candidates += 1;
        let level = key.level as usize;
        if level >= MAX_LEVELS {
            self.stats.re_evaluated += 1;
            return distance().0 < split_m;
        }
        let set = self.set_of(key);
        let (frame, epoch, drift, turned) =
            (self.frame, self.epoch, self.drift[level], self.turned);
        let ways = &mut self.entries[set * WAYS..(set + 1) * WAYS];
        if let Some(entry) = ways.iter_mut().find(|e| e.key == Some(key) && e.epoch == epoch) {
            if entry.bounds == bounds && drift + turned * entry.turn_m < entry.until {
                entry.seen = frame;
                return entry.split;
            }
        }
        self.stats.re_evaluated += 1;
        let (d, far) = distance();
        let split = d < split_m;
        let slack = (d - split_m).abs() - SLACK_MARGIN_M * (1.0 + 1e-3 * (d + split_m));
        let turn_m = SQRT_3 * (far + 2.0 * slack.max(0.0));
        let until = drift + turned * turn_m + slack;
        let slot = replace_slot(ways, key, epoch);
        *slot = Entry { key: Some(key), epoch, seen: frame, until, turn_m, split, bounds };
        split
    }

    fn set_of(&self, key: TileKey) -> usize {
        let h = (key.x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (key.y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (key.level as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
        ((h ^ (h >> 29)) as usize) & (self.sets - 1)
    }
}

/// The way to write `key` into: its own entry, else a void one, else the
/// least recently seen.
fn replace_slot(ways: &mut [Entry], key: TileKey, epoch: u32) -> &mut Entry {
    let index = ways
        .iter()
        .position(|e| e.key == Some(key) || e.key.is_none() || e.epoch != epoch)
        .unwrap_or_else(|| (0..ways.len()).min_by_key(|&i| ways[i].seen).expect("a set has ways"));
    &mut ways[index]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(level: u8, x: u32) -> TileKey {
        TileKey::new(level, x, 0)
    }

    #[test]
    fn a_test_lives_its_slack_over_the_declared_travel() {
        let mut life = ValidLife::new(10.0, 64);
        let rings = |_: u8| 1000.0;
        let mut tested = 0;
        for frame in 0..12 {
            life.begin(DVec3::new(frame as f64, 0.0, 0.0), None, 3, rings);
            // 1045 m from a 1000 m ring: 45 m of slack, four frames of 10 m.
            let split = life.splits(key(1, 0), (0.0, 1.0), 1000.0, || {
                tested += 1;
                (1045.0, 1100.0)
            });
            assert!(!split);
        }
        assert_eq!(tested, 3, "tested on frames 0, 5 and 10");
    }

    #[test]
    fn a_jump_or_new_bounds_test_again() {
        let mut life = ValidLife::new(10.0, 64);
        life.begin(DVec3::ZERO, None, 3, |_| 1000.0);
        assert!(life.splits(key(1, 0), (0.0, 1.0), 1000.0, || (10.0, 10.0)));
        life.begin(DVec3::new(5.0, 0.0, 0.0), None, 3, |_| 1000.0);
        assert!(life.splits(key(1, 0), (0.0, 1.0), 1000.0, || panic!("still valid")));
        life.begin(DVec3::new(5000.0, 0.0, 0.0), None, 3, |_| 1000.0);
        assert!(life.stats().full);
        assert!(!life.splits(key(1, 0), (0.0, 1.0), 1000.0, || (4000.0, 4000.0)));
        life.begin(DVec3::new(5001.0, 0.0, 0.0), None, 3, |_| 1000.0);
        assert!(life.splits(key(1, 0), (0.0, 2.0), 1000.0, || (900.0, 900.0)), "bounds changed");
    }

    #[test]
    fn a_moving_ring_uses_up_the_slack() {
        let mut life = ValidLife::new(1.0, 64);
        life.begin(DVec3::ZERO, None, 3, |_| 1000.0);
        assert!(!life.splits(key(2, 0), (0.0, 1.0), 1000.0, || (1100.0, 1100.0)));
        // The ring grows by 150 m (tau came down): the outcome may have changed.
        life.begin(DVec3::ZERO, None, 3, |_| 1150.0);
        assert!(life.splits(key(2, 0), (0.0, 1.0), 1150.0, || (1100.0, 1100.0)));
        assert_eq!(life.stats().re_evaluated, 1);
    }

    /// On the ellipsoid the camera's axes turn with the eye: a far box's
    /// faces move by the turn times its distance, spent from the slack.
    #[test]
    fn a_turn_of_the_axes_spends_the_slack() {
        let tests_over = |turn_per_frame: f64| {
            let mut life = ValidLife::new(1.0, 64);
            let mut tested = 0;
            for frame in 0..10 {
                let axes = DMat3::from_rotation_z(frame as f64 * turn_per_frame);
                life.begin(DVec3::new(frame as f64, 0.0, 0.0), Some(axes), 3, |_| 1000.0);
                // 100 m of slack, the far corner 10 km away.
                life.splits(key(1, 0), (0.0, 1.0), 1000.0, || {
                    tested += 1;
                    (1100.0, 10_000.0)
                });
            }
            tested
        };
        assert_eq!(tests_over(0.0), 1, "no turn: 100 frames of life");
        // 1.4e-3 of axes change a frame at 17.7 km a radian: 26 m a frame.
        assert_eq!(tests_over(1e-3), 3, "tested on frames 0, 4 and 8");
    }
}
