//! The distance rings: how near the camera may come to a tile of each level
//! before it splits, and where its vertices morph toward the parent level.
//!
//! For a tile of level `l`, `split[l]` is the distance (camera to the tile's
//! bounding box) below which it splits. Its vertices morph toward level `l+1`
//! between `morph_start[l] = split[l+1] * (1 - morph_range)` and
//! `morph_end[l] = split[l+1]`. The rings are the largest of three rules:
//! 1. Kühnert's: `view_distance` tile sizes, so tiles look about equally big;
//! 2. Ulrich's: `delta[l] * K / (tau * (1 - morph_range))`, so a level-`l`
//!    surface, and the morph toward it, is only shown where its error projects
//!    to at most tau pixels (K = viewport width / (2 tan(fov_x / 2)));
//! 3. consistency: `split[l+1] * (1 - morph_range) >= split[l] + diagonal[l]`,
//!    where `diagonal[l]` is the 3-D diagonal of a level-`l` tile with the
//!    data's full height range. Then where a level-`l` tile meets a level-`l+1`
//!    neighbour, the fine side is fully morphed and the coarse side not at all
//!    (no cracks), and neighbours never differ by more than one level.

use super::LodConfig;

/// Per-level split and morph distances in metres, for levels `0..levels`.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelRings {
    split: Vec<f64>,
    morph_range: f64,
}

/// What the rings are computed from.
#[derive(Clone, Copy, Debug)]
pub struct RingInputs<'a> {
    /// Tile side in metres at level 0 (grid_size times the post spacing).
    pub tile_size_m: f64,
    /// Largest geometric error of each level, metres (from the pyramid).
    pub delta_per_level: &'a [f64],
    /// Highest minus lowest height of the data, metres.
    pub height_range_m: f64,
    /// Ulrich's K for the current viewport and field of view.
    pub perspective_scale: f64,
}

impl LevelRings {
    /// The rings for `config` and `inputs`.
    pub fn new(config: &LodConfig, inputs: RingInputs<'_>) -> Self {
        let mut rings = LevelRings {
            split: Vec::with_capacity(inputs.delta_per_level.len() + 1),
            morph_range: 0.0,
        };
        rings.update(config, inputs);
        rings
    }

    /// Recomputes the rings in place (no allocation once sized).
    pub fn update(&mut self, config: &LodConfig, inputs: RingInputs<'_>) {
        let levels = inputs.delta_per_level.len();
        let keep = 1.0 - config.morph_range;
        let split = &mut self.split;
        split.clear();
        split.resize(levels + 1, 0.0);
        for level in 1..=levels {
            let size = inputs.tile_size_m * (1u64 << level.min(62)) as f64;
            let kuehnert = config.view_distance * size;
            let delta = inputs.delta_per_level.get(level).copied().unwrap_or(0.0);
            let ulrich = delta * inputs.perspective_scale / (config.tau_px * keep);
            let below = level - 1;
            let below_size = inputs.tile_size_m * (1u64 << below.min(62)) as f64;
            let diagonal = (2.0 * below_size * below_size + inputs.height_range_m.powi(2)).sqrt();
            let consistent = if below == 0 { 0.0 } else { (split[below] + diagonal) / keep };
            split[level] = kuehnert.max(ulrich).max(consistent);
        }
        self.morph_range = config.morph_range;
    }

    /// The tau above which rings for `inputs` stop shrinking, pixels: past
    /// it Ulrich's rule is under the other two at every level, so a budget
    /// gains nothing by raising tau further. `scratch` is left holding the
    /// rings without Ulrich's rule (no allocation once sized).
    pub fn tau_ceiling(
        scratch: &mut LevelRings,
        config: &LodConfig,
        inputs: RingInputs<'_>,
    ) -> f64 {
        scratch.update(&LodConfig { tau_px: f64::INFINITY, ..*config }, inputs);
        let keep = 1.0 - config.morph_range;
        let ceiling = |level: usize| {
            let delta = inputs.delta_per_level.get(level).copied().unwrap_or(0.0);
            let ring = scratch.split[level];
            if ring > 0.0 {
                delta * inputs.perspective_scale / (keep * ring)
            } else {
                0.0
            }
        };
        (1..scratch.split.len()).map(ceiling).fold(0.0, f64::max)
    }

    /// Levels covered (the root level is `levels() - 1`).
    pub fn levels(&self) -> usize {
        self.split.len() - 1
    }

    /// Distance below which a tile of `level` splits (0 for level 0).
    pub fn split_distance(&self, level: u8) -> f64 {
        self.split[level as usize]
    }

    /// `(start, end)` of the morph of `level` toward `level + 1`; the root
    /// level never morphs (infinite range).
    pub fn morph(&self, level: u8) -> (f64, f64) {
        let next = level as usize + 1;
        if next >= self.levels() {
            return (f64::INFINITY, f64::INFINITY);
        }
        let end = self.split[next];
        (end * (1.0 - self.morph_range), end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rings(deltas: &[f64], tau: f64) -> LevelRings {
        let config = LodConfig { tau_px: tau, ..LodConfig::default() };
        let inputs = RingInputs {
            tile_size_m: 1000.0,
            delta_per_level: deltas,
            height_range_m: 2000.0,
            perspective_scale: 1000.0,
        };
        LevelRings::new(&config, inputs)
    }

    #[test]
    fn rings_grow_and_stay_consistent() {
        let r = rings(&[0.0, 5.0, 12.0, 30.0, 70.0], 1.0);
        for level in 1..4u8 {
            let diagonal = (2.0 * (1000.0 * (1u64 << (level - 1)) as f64).powi(2) + 4e6).sqrt();
            let (start, _) = r.morph(level);
            assert!(start >= r.split_distance(level) + diagonal - 1e-6, "level {level}");
        }
    }

    #[test]
    fn past_the_ceiling_tau_changes_no_ring() {
        let deltas = [0.0, 5.0, 12.0, 30.0, 70.0];
        let config = LodConfig::default();
        let inputs = RingInputs {
            tile_size_m: 1000.0,
            delta_per_level: &deltas,
            height_range_m: 2000.0,
            perspective_scale: 1000.0,
        };
        let mut scratch = rings(&deltas, 1.0);
        let ceiling = LevelRings::tau_ceiling(&mut scratch, &config, inputs);
        assert!(ceiling > 1.0 && ceiling.is_finite());
        assert_eq!(rings(&deltas, ceiling * 1.001), rings(&deltas, ceiling * 100.0));
        assert_ne!(rings(&deltas, ceiling * 0.9), rings(&deltas, ceiling * 100.0));
    }

    #[test]
    fn ulrich_rule_widens_rings_for_rough_data() {
        let smooth = rings(&[0.0, 0.1, 0.2, 0.4, 0.8], 1.0);
        let rough = rings(&[0.0, 500.0, 900.0, 1500.0, 3000.0], 1.0);
        for level in 1..5u8 {
            let delta = [0.0, 500.0, 900.0, 1500.0, 3000.0][level as usize];
            assert!(rough.split_distance(level) >= delta * 1000.0 / 0.7 - 1e-6);
            assert!(rough.split_distance(level) >= smooth.split_distance(level));
        }
    }
}
