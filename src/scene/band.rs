//! Holding a frame's triangles inside a budget's band within the frame: the
//! budget's controller moves tau from one frame to the next, but the view
//! can change by more than the band between two frames. After selecting,
//! the scene estimates the frame's triangles (each resident tile's own
//! count, the last frame's mean per tile of its level for tiles not yet
//! made) and, when that leaves the band, selects again at a corrected tau,
//! at most [`MAX_RESELECTIONS`] times, never below the requested tau nor
//! past the ceiling.
//!
//! The count is a step function of tau: it changes only when a tile crosses
//! a ring, and one tile splitting into four adds several per cent. A
//! correction sized for a smooth plant (the square root of the miss, as
//! triangles fall about as `tau^-2`) can then land on the same step again
//! and again; each try that changes nothing doubles the next move, and once
//! taus on both sides of the target are known the search bisects between
//! them.

/// Most selections a frame redoes to keep the band. One tile crossing its
/// ring can split down several levels at once, a step of 9-16 % of the
/// count on the default flight at 240k triangles, so a ±4 % band is often
/// a narrow gap between two steps: bracketing it takes up to four tries,
/// bisecting to it up to eight more. A selection costs about 0.1 ms.
pub const MAX_RESELECTIONS: u32 = 12;

/// A triangle budget's band.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleBand {
    /// Triangles a frame aimed at.
    pub target: f64,
    /// Relative half-width of the band, e.g. 0.04.
    pub tolerance: f64,
}

/// Levels whose mean triangles per tile are kept.
const LEVELS: usize = 32;

/// The band and what the last frame's tiles drew.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct BandState {
    pub band: Option<TriangleBand>,
    /// Mean triangles per tile of the last frame, and per level (0: none).
    per_tile: f64,
    per_level: [f64; LEVELS],
}

impl BandState {
    /// Triangles a frame of `tiles` (level, and the count of a resident one).
    pub fn estimate(&self, tiles: impl Iterator<Item = (u8, Option<u64>)>) -> f64 {
        let guess = |level: u8| match self.per_level.get(level as usize) {
            Some(&n) if n > 0.0 => n,
            _ => self.per_tile,
        };
        tiles.map(|(level, t)| t.map_or_else(|| guess(level), |n| n as f64)).sum()
    }

    /// A search for this frame's tau between `floor` and `ceiling`; `None`
    /// without a band or before a frame has been learnt from.
    pub fn search(&self, floor: f64, ceiling: f64) -> Option<BandSearch> {
        let band = self.band?;
        (self.per_tile > 0.0).then_some(BandSearch {
            band,
            low: floor,
            high: ceiling.max(floor),
            best: (f64::INFINITY, floor),
            last: None,
            exponent: SMOOTH_EXPONENT,
            tries: 0,
        })
    }

    /// Learns triangles per tile, overall and per level, from a frame's
    /// tiles (level, triangles).
    pub fn learn(&mut self, tiles: impl Iterator<Item = (u8, u64)>) {
        let mut sums = [(0.0f64, 0u32); LEVELS];
        for (level, triangles) in tiles {
            let sum = &mut sums[(level as usize).min(LEVELS - 1)];
            *sum = (sum.0 + triangles as f64, sum.1 + 1);
        }
        let (all, count) = sums.iter().fold((0.0, 0), |(a, c), s| (a + s.0, c + s.1));
        if count > 0 {
            self.per_tile = all / count as f64;
        }
        for (mean, (sum, n)) in self.per_level.iter_mut().zip(sums) {
            *mean = if n > 0 { sum / n as f64 } else { 0.0 };
        }
    }
}

/// The first correction's exponent: triangles fall about as `tau^-2`.
const SMOOTH_EXPONENT: f64 = 0.5;

/// One frame's search for a tau whose selection lands in the band: each
/// try corrects tau by the miss to the power `exponent`, which doubles
/// after a try whose estimate did not move (a step of the plant), kept
/// inside the bracket the earlier tries set (bisected when it leaves it);
/// after [`MAX_RESELECTIONS`] tries the best one is taken.
#[derive(Clone, Copy, Debug)]
pub(super) struct BandSearch {
    band: TriangleBand,
    /// Taus known to draw too many (`low`) and too few (`high`) triangles.
    low: f64,
    high: f64,
    /// The smallest miss so far and its tau.
    best: (f64, f64),
    /// The last try's estimate.
    last: Option<f64>,
    exponent: f64,
    tries: u32,
}

impl BandSearch {
    /// The tau to select with next, given that the selection at `tau` would
    /// draw `estimate` triangles; `None` to keep it.
    pub fn next(&mut self, estimate: f64, tau: f64) -> Option<f64> {
        let miss = estimate / self.band.target;
        let off = (miss - 1.0).abs();
        if off < self.best.0 {
            self.best = (off, tau);
        }
        if off <= self.band.tolerance || self.tries > MAX_RESELECTIONS {
            return None;
        }
        self.tries += 1;
        if self.tries > MAX_RESELECTIONS {
            let best = self.best.1;
            return (best != tau).then_some(best);
        }
        if miss > 1.0 {
            self.low = self.low.max(tau);
        } else {
            self.high = self.high.min(tau);
        }
        // The same count as the last try: tau moved within one step.
        let stuck = self.last.is_some_and(|last| (last - estimate).abs() < 0.5);
        self.exponent = if stuck { self.exponent * 2.0 } else { SMOOTH_EXPONENT };
        self.last = Some(estimate);
        let mut next = tau * miss.powf(self.exponent);
        if !(next > self.low && next < self.high) {
            next = (self.low * self.high).sqrt();
        }
        let next = next.clamp(self.low, self.high);
        ((next - tau).abs() > 1e-9 * tau).then_some(next)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn searches_inside_the_bracket_and_keeps_the_best() {
        let mut state = BandState {
            band: Some(TriangleBand { target: 100_000.0, tolerance: 0.04 }),
            ..BandState::default()
        };
        assert!(state.search(1.0, 8.0).is_none(), "nothing learnt yet");
        state.learn((0..200).map(|i| (if i < 100 { 0 } else { 1 }, 1000)));
        let tiles = |n: usize| state.estimate((0..n).map(|i| (1, (i % 2 == 0).then_some(1000))));
        let mut search = state.search(1.0, 8.0).unwrap();
        assert_eq!(search.next(tiles(102), 2.0), None, "in the band");
        let mut search2 = state.search(1.0, 8.0).unwrap();
        assert_eq!(search2.next(tiles(121), 2.0), Some(2.0 * 1.21f64.sqrt()));
        assert_eq!(state.search(1.0, 8.0).unwrap().next(tiles(50), 1.0), None, "at the floor");
        assert_eq!(state.search(1.0, 8.0).unwrap().next(tiles(400), 8.0), None, "at the ceiling");
        // A step plant: 130k below tau 3, 70k from 3 on; no tau hits the band.
        let plant = |tau: f64| if tau < 3.0 { 130_000.0 } else { 70_000.0 };
        let mut tau = 2.0;
        let mut tries = 0;
        while let Some(next) = search.next(plant(tau), tau) {
            assert!((1.0..=8.0).contains(&next));
            tau = next;
            tries += 1;
        }
        assert!(tries <= MAX_RESELECTIONS + 1);
        let _ = &mut search;
    }

    #[test]
    fn a_wide_step_is_crossed_within_the_frame() {
        // The count holds from tau 1.8 up (as over frames 45-48 of the default
        // flight at 240k): a square-root correction moves 2.7 % a try and
        // would stay on this step for seven tries.
        let plant = |tau: f64| match tau {
            t if t >= 1.8 => 227_000.0,
            t if t >= 1.6 => 239_000.0,
            _ => 262_000.0,
        };
        let band = TriangleBand { target: 240_000.0, tolerance: 0.04 };
        let mut state = BandState { band: Some(band), ..BandState::default() };
        state.learn(std::iter::once((0, 3000)));
        let mut search = state.search(1.0, 6.0).unwrap();
        let mut tau = 2.146;
        while let Some(next) = search.next(plant(tau), tau) {
            tau = next;
        }
        assert!((plant(tau) / band.target - 1.0).abs() <= band.tolerance, "ended at {tau}");
    }
}
