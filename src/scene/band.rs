//! Holding a frame's triangles inside a budget's band within the frame: the
//! budget's controller moves tau from one frame to the next, but the view
//! can change by more than the band between two frames. After selecting,
//! the scene estimates the frame's triangles (tiles selected times the last
//! frame's triangles per tile) and, when that leaves the band, selects again
//! at a tau corrected by the square root of the miss (triangles fall about
//! as `tau^-2`), at most [`MAX_RESELECTIONS`] times, never below the
//! requested tau nor past the ceiling.

/// Most selections a frame redoes to keep the band.
pub const MAX_RESELECTIONS: u32 = 2;

/// A triangle budget's band.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleBand {
    /// Triangles a frame aimed at.
    pub target: f64,
    /// Relative half-width of the band, e.g. 0.04.
    pub tolerance: f64,
}

/// The band and what the last frame's tiles drew.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct BandState {
    pub band: Option<TriangleBand>,
    per_tile: f64,
}

impl BandState {
    /// A corrected tau when `tiles` tiles at `tau` would leave the band;
    /// `None` when they stay in it, or nothing is known yet, or the
    /// correction is clamped to `tau` itself.
    pub fn retarget(&self, tiles: usize, tau: f64, floor: f64, ceiling: f64) -> Option<f64> {
        let band = self.band?;
        if self.per_tile <= 0.0 {
            return None;
        }
        let estimate = tiles as f64 * self.per_tile;
        let miss = estimate / band.target;
        if (miss - 1.0).abs() <= band.tolerance {
            return None;
        }
        let corrected = (tau * miss.sqrt()).clamp(floor, ceiling.max(floor));
        ((corrected - tau).abs() > 1e-9 * tau).then_some(corrected)
    }

    /// Learns triangles per tile from a frame.
    pub fn learn(&mut self, triangles: u64, tiles: usize) {
        if tiles > 0 {
            self.per_tile = triangles as f64 / tiles as f64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corrects_only_outside_the_band_and_within_the_limits() {
        let mut state = BandState {
            band: Some(TriangleBand { target: 100_000.0, tolerance: 0.04 }),
            ..BandState::default()
        };
        assert_eq!(state.retarget(100, 2.0, 1.0, 8.0), None, "nothing learnt yet");
        state.learn(200_000, 200);
        assert_eq!(state.retarget(102, 2.0, 1.0, 8.0), None);
        assert_eq!(state.retarget(121, 2.0, 1.0, 8.0), Some(2.0 * 1.21f64.sqrt()));
        assert_eq!(state.retarget(50, 2.0, 1.5, 8.0), Some(1.5));
        assert_eq!(state.retarget(50, 1.0, 1.0, 8.0), None, "at the request already");
        assert_eq!(state.retarget(400, 8.0, 1.0, 8.0), None, "at the ceiling already");
    }
}
