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
#[derive(Clone, Copy, Debug)]
pub(super) struct BandState {
    pub band: Option<TriangleBand>,
    /// Mean triangles per tile of the last frame, and per level (0: none).
    per_tile: f64,
    per_level: [f64; LEVELS],
    /// The mean error the level's tiles were extracted at when learnt
    /// (NaN for grids, whose triangles do not follow tau).
    error_per_level: [f64; LEVELS],
    /// What the frames drew over what their selections were estimated at,
    /// smoothed: the estimate's own bias, taken out of the next ones.
    bias: f64,
    /// The last selection's estimate, unbiased.
    last_estimate: f64,
}

impl Default for BandState {
    fn default() -> Self {
        BandState {
            band: None,
            per_tile: 0.0,
            per_level: [0.0; LEVELS],
            error_per_level: [f64::NAN; LEVELS],
            bias: 1.0,
            last_estimate: f64::NAN,
        }
    }
}

/// One selected tile, as the band's estimate sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileEstimate {
    /// Its level.
    pub level: u8,
    /// Resident: its triangles and the error it was extracted at (NaN for
    /// a grid).
    pub resident: Option<(u64, f64)>,
    /// The error it would be extracted at with the tau being tried (NaN
    /// for a grid).
    pub error_m: f64,
}

/// How a mesh's triangles scale from error `made` to error `wanted`:
/// about as their ratio on real relief (the lod bench: 4 times the error,
/// 3.8 times fewer triangles), within 16 either way; 1 where either is
/// unknown (grids).
fn rescale(made: f64, wanted: f64) -> f64 {
    if made > 0.0 && wanted > 0.0 {
        (made / wanted).clamp(1.0 / 16.0, 16.0)
    } else {
        1.0
    }
}

impl BandState {
    /// Triangles a frame of `tiles` (level, and the count of a resident one).
    pub fn estimate(&mut self, tiles: impl Iterator<Item = TileEstimate>) -> f64 {
        let guess = |level: u8| match self.per_level.get(level as usize) {
            Some(&n) if n > 0.0 => (n, self.error_per_level[level as usize]),
            _ => (self.per_tile, f64::NAN),
        };
        let estimate = tiles
            .map(|tile| {
                let (triangles, made) = match tile.resident {
                    Some((n, made)) => (n as f64, made),
                    None => guess(tile.level),
                };
                triangles * rescale(made, tile.error_m)
            })
            .sum::<f64>();
        self.last_estimate = estimate;
        estimate * self.bias
    }

    /// Learns the estimate's bias from a frame that drew `triangles` for
    /// the selection last estimated: tiles remade at another error have
    /// counts the map's histogram only foretells.
    pub fn observe(&mut self, triangles: u64) {
        if self.last_estimate > 0.0 && triangles > 0 {
            let ratio = (triangles as f64 / self.last_estimate).clamp(0.5, 2.0);
            self.bias = (self.bias * ratio).sqrt();
        }
        self.last_estimate = f64::NAN;
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
            bracket: (floor, ceiling.max(floor)),
            last: None,
            exponent: SMOOTH_EXPONENT,
            tries: 0,
        })
    }

    /// Learns triangles per tile, overall and per level, from a frame's
    /// tiles (level, triangles).
    pub fn learn(&mut self, tiles: impl Iterator<Item = (u8, u64, f64)>) {
        let mut sums = [(0.0f64, 0u32, 0.0f64); LEVELS];
        for (level, triangles, error_m) in tiles {
            let sum = &mut sums[(level as usize).min(LEVELS - 1)];
            *sum = (sum.0 + triangles as f64, sum.1 + 1, sum.2 + error_m);
        }
        let (all, count) = sums.iter().fold((0.0, 0), |(a, c), s| (a + s.0, c + s.1));
        if count > 0 {
            self.per_tile = all / count as f64;
        }
        for (level, (sum, n, errors)) in sums.into_iter().enumerate() {
            self.per_level[level] = if n > 0 { sum / n as f64 } else { 0.0 };
            self.error_per_level[level] = if n > 0 { errors / n as f64 } else { f64::NAN };
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
    /// The tau range it started from.
    bracket: (f64, f64),
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
    /// The budget, triangles.
    pub fn target(&self) -> f64 {
        self.band.target
    }

    /// The tau to select again with, once a selection at `tau` made
    /// `drawn` triangles: the search from there, its tries reset (the real
    /// count is worth a fresh bracket's worth).
    pub fn correct(&mut self, drawn: f64, tau: f64) -> Option<f64> {
        (self.low, self.high) = self.bracket;
        self.best = (f64::INFINITY, tau);
        self.tries = 0;
        self.last = None;
        self.exponent = SMOOTH_EXPONENT;
        self.next(drawn, tau)
    }

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
        // The counts are not monotone in tau (a tile remade at another
        // error moves them both ways): a bracket that closed or crossed
        // has no tau left inside, so the best seen is kept.
        if self.low >= self.high || self.low.is_nan() || self.high.is_nan() {
            let best = self.best.1;
            return (best != tau).then_some(best);
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
        state.learn((0..200).map(|i| (if i < 100 { 0 } else { 1 }, 1000, f64::NAN)));
        let tile = |i: usize| TileEstimate {
            level: 1,
            resident: (i % 2 == 0).then_some((1000, f64::NAN)),
            error_m: f64::NAN,
        };
        let tiles = |n: usize| state.clone().estimate((0..n).map(tile));
        let (e102, e121, e50, e400) = (tiles(102), tiles(121), tiles(50), tiles(400));
        let mut search = state.search(1.0, 8.0).unwrap();
        assert_eq!(search.next(e102, 2.0), None, "in the band");
        let mut search2 = state.search(1.0, 8.0).unwrap();
        assert_eq!(search2.next(e121, 2.0), Some(2.0 * 1.21f64.sqrt()));
        assert_eq!(state.search(1.0, 8.0).unwrap().next(e50, 1.0), None, "at the floor");
        assert_eq!(state.search(1.0, 8.0).unwrap().next(e400, 8.0), None, "at the ceiling");
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
        state.learn(std::iter::once((0, 3000, f64::NAN)));
        let mut search = state.search(1.0, 6.0).unwrap();
        let mut tau = 2.146;
        while let Some(next) = search.next(plant(tau), tau) {
            tau = next;
        }
        assert!((plant(tau) / band.target - 1.0).abs() <= band.tolerance, "ended at {tau}");
    }
}
