//! A deterministic procedural earth: a [`NodeSource`] that computes any node
//! of an earth-sized pyramid (2^24 samples a side and more) on demand, without
//! touching disk, for scale tests of the clipmap and the renderer.
//!
//! The height of level-0 sample `(i, j)` is
//! `base + sum_k amplitude_k * noise_k(i, j)` where `noise_k` is value noise of
//! wavelength `2^k` samples: hashed lattice values in `[-1, 1]` at multiples of
//! `2^k`, blended with the quintic fade `6t^5 - 15t^4 + 10t^3`. The lattice
//! values are hashed from `(seed, k, lattice x, lattice y)`, so there is no
//! random state and every node is the same on every call and every machine.
//! Lattice values are skewed towards -1 (`2u^4 - 1` for uniform `u`), so
//! lowlands are common and high peaks rare; heights stay inside
//! [`HEIGHT_RANGE_M`] by construction.
//!
//! Posts of a level-`l` node are level-0 samples at stride `2^l`, evaluated
//! directly; `min` and `max` are exact over the posts. `delta` cannot be
//! brute-forced for coarse nodes (a root node covers 2^48 samples), so it is a
//! conservative bound from the octaves, see [`ProceduralEarth::delta_bound`].
//!
//! [`ProceduralEarth::shifted`] moves the same terrain to another place of the
//! grid, so that a test can draw one landscape both at the origin and 10^7 m
//! out and compare the pictures.

use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// Lowest and highest height the earth can have, in metres.
pub const HEIGHT_RANGE_M: [f64; 2] = [-400.0, 8800.0];

/// Largest |d fade / dt| on [0, 1] (at t = 1/2): 30/16.
const FADE_SLOPE_MAX: f64 = 1.875;
/// Largest |d^2 fade / dt^2| on [0, 1] (at t = 1/2 -/+ sqrt(3)/6): 10/sqrt(3).
const FADE_CURVATURE_MAX: f64 = 5.773_502_691_896_258;
/// Slack added to every bound for the rounding of heights to f32 (a few
/// units in the last place of 8800 m).
const ROUNDING_SLACK_M: f64 = 0.004;
/// Wavelength (log2 samples) where the amplitude spectrum bends: above it
/// amplitudes grow slowly (continents and ranges), below it fast (hills).
const KNEE_LOG2: i32 = 13;
const HURST_ABOVE_KNEE: f64 = 0.15;
const HURST_BELOW_KNEE: f64 = 0.85;

/// Side of the square the built-in flights fly over, metres
/// ([`ProceduralEarth::flight_area_m`]; the whole earth is 40 000 km a side).
pub const FLIGHT_AREA_M: f64 = 100_000.0;

/// What [`ProceduralEarth::new`] builds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarthParams {
    /// Cells per node side.
    pub node_size: u32,
    /// Pyramid levels; the data has `node_size << (levels - 1)` cells a side,
    /// so the root level is a single node.
    pub levels: u8,
    /// Border posts stored on each node side.
    pub border: u32,
    /// Metres between level-0 samples (both axes).
    pub spacing_m: f64,
    /// Seed of the terrain: the same parameters and seed give the same heights.
    pub seed: u64,
}

impl EarthParams {
    /// An earth-sized pyramid: at least 2^24 samples a side, 2.4 m apart
    /// (40 000 km, the equator), with one border post.
    pub fn earth(node_size: u32, seed: u64) -> Self {
        let mut levels = 1u8;
        while ((node_size.max(1) as u64) << (levels - 1)) < (1 << 24) {
            levels += 1;
        }
        EarthParams { node_size, levels, border: 1, spacing_m: 2.4, seed }
    }

    /// The earth `--dataset procedural` draws: 2^20 posts of 38.4 m a side
    /// (40 000 km), nodes of 64 cells with two border posts, seed 11 (the
    /// earth of `tests/render_stress.rs`). Out to a 10 km cruise's horizon
    /// its level 0 holds about 10^8 posts inside a 60-degree frustum.
    pub fn display_earth() -> Self {
        EarthParams { node_size: 64, levels: 15, border: 2, spacing_m: 38.4, seed: 11 }
    }
}

/// Why the parameters cannot make an earth.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProceduralError {
    /// `node_size` is below 2 cells.
    #[error("procedural earth: node_size {0} must be at least 2")]
    NodeSize(u32),
    /// `levels` is 0 or above 32, or `node_size << (levels - 1)` cells do not fit below
    /// 2^32 posts a side.
    #[error("procedural earth: {levels} levels of node_size {node_size} do not fit 2^32 samples")]
    TooLarge {
        /// Cells per node side asked for.
        node_size: u32,
        /// Pyramid levels asked for.
        levels: u8,
    },
    /// `border` is larger than `node_size`.
    #[error("procedural earth: border {border} must be at most node_size {node_size}")]
    Border {
        /// Border posts asked for on each node side.
        border: u32,
        /// Cells per node side asked for.
        node_size: u32,
    },
    /// The level-0 post spacing, metres, is not finite and positive.
    #[error("procedural earth: spacing {0} m must be finite and positive")]
    Spacing(f64),
}

#[derive(Clone, Copy, Debug)]
struct Octave {
    log2_wavelength: u32,
    amplitude_m: f64,
    /// Hash key of this octave's lattice, derived from the seed.
    key: u64,
}

/// The procedural earth. Cheap to share: nodes are computed from `&self`.
#[derive(Clone, Debug)]
pub struct ProceduralEarth {
    layout: NodeLayout,
    base_m: f64,
    octaves: Vec<Octave>,
    /// `delta` of every node of each level (see [`Self::delta_bound`]).
    delta_by_level: Vec<f32>,
    /// Level-0 posts added to every sample index (see [`Self::shifted`]).
    offset: [i64; 2],
}

impl ProceduralEarth {
    /// Builds the earth described by `params`, or says why it cannot.
    pub fn new(params: EarthParams) -> Result<Self, ProceduralError> {
        let EarthParams { node_size, levels, border, spacing_m, seed } = params;
        if node_size < 2 {
            return Err(ProceduralError::NodeSize(node_size));
        }
        let cells = (node_size as u64).checked_shl(levels.max(1) as u32 - 1).unwrap_or(u64::MAX);
        if levels == 0 || levels > 32 || cells >= u32::MAX as u64 {
            return Err(ProceduralError::TooLarge { node_size, levels });
        }
        if border > node_size {
            return Err(ProceduralError::Border { border, node_size });
        }
        if !(spacing_m.is_finite() && spacing_m > 0.0) {
            return Err(ProceduralError::Spacing(spacing_m));
        }
        let samples = cells as u32 + 1;
        let layout = NodeLayout {
            levels,
            node_size,
            border,
            posts: [samples; 2],
            spacing_m: [spacing_m; 2],
        };
        let octaves = octaves_for(cells, seed);
        let delta_by_level = (0..levels).map(|lod| level_delta_bound(&octaves, lod)).collect();
        let base_m = (HEIGHT_RANGE_M[0] + HEIGHT_RANGE_M[1]) / 2.0;
        Ok(ProceduralEarth { layout, base_m, octaves, delta_by_level, offset: [0, 0] })
    }

    /// The same terrain moved `posts` level-0 posts west and south: sample
    /// `(i, j)` of the result is sample `(i + posts[0], j + posts[1])` of
    /// `self`, the layout and the deltas unchanged. With `posts` a multiple of
    /// a level's node span, the nodes of that level and finer are those of
    /// `self` moved by whole nodes.
    pub fn shifted(mut self, posts: [u32; 2]) -> Self {
        self.offset = [self.offset[0] + posts[0] as i64, self.offset[1] + posts[1] as i64];
        self
    }

    /// Level-0 sample `(i, j)`, clamped to the data (the edge extends).
    pub fn sample(&self, i: i64, j: i64) -> f32 {
        let last = self.layout.posts[0] as i64 - 1;
        let (i, j) = (i.saturating_add(self.offset[0]), j.saturating_add(self.offset[1]));
        let (i, j) = (i.clamp(0, last) as u32, j.clamp(0, last) as u32);
        let mut height = self.base_m;
        for octave in &self.octaves {
            height += octave.amplitude_m * value_noise(octave, i, j);
        }
        height as f32
    }

    /// The `delta` given to every node of level `lod`: a bound on
    /// `|surface - sample|` over the level-0 samples a node covers.
    ///
    /// Per octave of amplitude `a` and wavelength `w`, with post spacing `s`
    /// (level-0 samples between posts):
    /// - both the octave and its interpolation lie in `[-a, a]`, so the error
    ///   is at most `2a`;
    /// - the octave's Hessian has spectral norm at most
    ///   `H = (2 F2 + 4 F1^2) a / w^2` (the row-sum bound, with `F1`, `F2` the
    ///   largest first and second derivatives of the fade), and linear
    ///   interpolation on a right triangle with legs `s` is off by at most
    ///   `H/2 * max sum_i w_i |v_i - p|^2 = H/2 * s^2/2` (the circumradius
    ///   squared, at the hypotenuse's midpoint).
    ///
    /// Interpolation is linear in the octaves, so the node's error is at most
    /// the sum over octaves of the smaller bound, plus f32 rounding slack.
    /// Level 0 is exact (its posts are the samples): 0.
    pub fn delta_bound(&self, lod: u8) -> f32 {
        self.delta_by_level[lod as usize]
    }

    /// A bound on the slope of the exact surface ([`NodeSource::exact_height`]:
    /// the level-0 samples joined as triangles), metres per metre.
    ///
    /// Along one axis an octave of amplitude `a` and wavelength `w` metres
    /// changes by at most `2 a F1 / w` per metre (its lattice values differ
    /// by at most 2, the fade's slope is at most `F1`), so two neighbouring
    /// samples differ by at most the sum of that times the spacing. A
    /// triangle's gradient has those two differences over the spacing as
    /// components: at most `sqrt(2)` times the per-axis sum, plus the f32
    /// rounding of two samples over the spacing.
    pub fn slope_bound(&self) -> f64 {
        let spacing = self.layout.spacing_m[0];
        let per_axis: f64 = self
            .octaves
            .iter()
            .map(|o| {
                2.0 * o.amplitude_m * FADE_SLOPE_MAX
                    / ((1u64 << o.log2_wavelength) as f64 * spacing)
            })
            .sum();
        std::f64::consts::SQRT_2 * (per_axis + 2.0 * ROUNDING_SLACK_M / spacing)
    }

    /// Where the built-in flights fly over this earth: the south-west corner
    /// and the size, metres, of a square [`FLIGHT_AREA_M`] wide in the
    /// middle of the earth.
    pub fn flight_area_m(&self) -> ([f64; 2], [f64; 2]) {
        let layout = &self.layout;
        let side = |k: usize| (layout.posts[k] - 1) as f64 * layout.spacing_m[k];
        let half = FLIGHT_AREA_M / 2.0;
        ([side(0) / 2.0 - half, side(1) / 2.0 - half], [FLIGHT_AREA_M; 2])
    }

    /// Lowest and highest height any sample can have: base -/+ the amplitudes.
    pub fn height_bounds(&self) -> [f64; 2] {
        let total: f64 = self.octaves.iter().map(|o| o.amplitude_m).sum();
        [self.base_m - total, self.base_m + total]
    }

    fn fill_posts(&self, id: NodeId, out: &mut NodeData) {
        let layout = &self.layout;
        let side = layout.stored_side() as i64;
        let stride = 1i64 << id.level;
        let span = layout.span(id.level) as i64;
        let first = |node: u32| node as i64 * span - layout.border as i64 * stride;
        let (x0, y0) = (first(id.x), first(id.y));
        out.heights.clear();
        for row in 0..side {
            for col in 0..side {
                out.heights.push(self.sample(x0 + col * stride, y0 + row * stride));
            }
        }
    }
}

impl NodeSource for ProceduralEarth {
    fn layout(&self) -> &NodeLayout {
        &self.layout
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        if !self.layout.contains(id) {
            return Err(NodeError::OutOfRange { id });
        }
        self.fill_posts(id, out);
        let (mut min, mut max) = (f32::INFINITY, f32::NEG_INFINITY);
        for j in 0..=self.layout.node_size {
            for i in 0..=self.layout.node_size {
                let h = out.post(&self.layout, i, j);
                min = min.min(h);
                max = max.max(h);
            }
        }
        out.min = min;
        out.max = max;
        out.delta = self.delta_bound(id.level);
        out.grid_delta = out.delta;
        Ok(())
    }

    /// Three samples joined as the level-0 triangle holding the point.
    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        let spacing = self.layout.spacing_m[0];
        let last = (self.layout.posts[0] - 1) as f64;
        let (sx, sy) = (x_m / spacing, y_m / spacing);
        if !(sx >= 0.0 && sx <= last && sy >= 0.0 && sy <= last) {
            return Err(NodeError::OutsideData { x_m, y_m });
        }
        let cell = |s: f64| (s.floor() as i64).min(last as i64 - 1);
        let (i, j) = (cell(sx), cell(sy));
        let (fx, fy) = (sx - i as f64, sy - j as f64);
        let h = |di: i64, dj: i64| self.sample(i + di, j + dj) as f64;
        Ok(crate::node::cell_surface(h(0, 0), h(1, 0), h(0, 1), h(1, 1), fx, fy) as f32)
    }
}

/// Octaves of wavelengths 2 .. cells/2 samples, amplitudes following a
/// two-slope fractal spectrum scaled so the heights fill [`HEIGHT_RANGE_M`].
fn octaves_for(cells: u64, seed: u64) -> Vec<Octave> {
    let top = (63 - cells.leading_zeros()).saturating_sub(1).max(1);
    let relative = |k: u32| {
        let above = k as i32 - KNEE_LOG2;
        let hurst = if above >= 0 { HURST_ABOVE_KNEE } else { HURST_BELOW_KNEE };
        (hurst * above as f64).exp2()
    };
    let total: f64 = (1..=top).map(relative).sum();
    let half_range = (HEIGHT_RANGE_M[1] - HEIGHT_RANGE_M[0]) / 2.0;
    (1..=top)
        .map(|k| Octave {
            log2_wavelength: k,
            amplitude_m: half_range * relative(k) / total,
            key: mix64(seed ^ mix64(k as u64 + 1)),
        })
        .collect()
}

fn level_delta_bound(octaves: &[Octave], lod: u8) -> f32 {
    if lod == 0 {
        return 0.0;
    }
    let post_spacing = (1u64 << lod) as f64;
    let hessian_per_amplitude = 2.0 * FADE_CURVATURE_MAX + 4.0 * FADE_SLOPE_MAX * FADE_SLOPE_MAX;
    let bound: f64 = octaves
        .iter()
        .map(|o| {
            let ratio = post_spacing / (1u64 << o.log2_wavelength) as f64;
            let curvature = hessian_per_amplitude * o.amplitude_m * ratio * ratio / 4.0;
            curvature.min(2.0 * o.amplitude_m)
        })
        .sum();
    (bound + ROUNDING_SLACK_M) as f32
}

/// Value noise of one octave at sample `(i, j)`, in `[-1, 1]`.
fn value_noise(octave: &Octave, i: u32, j: u32) -> f64 {
    let k = octave.log2_wavelength;
    let mask = (1u32 << k) - 1;
    let scale = 1.0 / (1u64 << k) as f64;
    let (lx, ly) = (i >> k, j >> k);
    let tx = fade((i & mask) as f64 * scale);
    let ty = fade((j & mask) as f64 * scale);
    let v = |dx: u32, dy: u32| lattice(octave.key, lx + dx, ly + dy);
    let south = v(0, 0) + tx * (v(1, 0) - v(0, 0));
    let north = v(0, 1) + tx * (v(1, 1) - v(0, 1));
    south + ty * (north - south)
}

fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// The hashed lattice value at `(x, y)`: `2u^4 - 1` for `u` uniform in [0, 1).
fn lattice(key: u64, x: u32, y: u32) -> f64 {
    let h = mix64(key ^ ((x as u64) << 32 | y as u64));
    let u = (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let u2 = u * u;
    2.0 * u2 * u2 - 1.0
}

/// The splitmix64 finaliser: a bijection that spreads every input bit.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fade_derivative_maxima_are_what_the_bound_assumes() {
        let (mut slope, mut curvature) = (0.0f64, 0.0f64);
        for n in 0..=100_000 {
            let t = n as f64 / 100_000.0;
            slope = slope.max((30.0 * t * t * (1.0 - t) * (1.0 - t)).abs());
            curvature = curvature.max((60.0 * t * (2.0 * t - 1.0) * (t - 1.0)).abs());
        }
        assert!((slope - FADE_SLOPE_MAX).abs() < 1e-6 && slope <= FADE_SLOPE_MAX);
        assert!((curvature - FADE_CURVATURE_MAX).abs() < 1e-6 && curvature <= FADE_CURVATURE_MAX);
    }

    #[test]
    fn a_shifted_earth_has_the_same_nodes_whole_nodes_away() {
        let params = EarthParams { node_size: 8, levels: 6, border: 2, spacing_m: 30.0, seed: 3 };
        let base = ProceduralEarth::new(params).unwrap();
        let shifted = base.clone().shifted([48, 16]);
        assert_eq!(shifted.sample(5, 7), base.sample(53, 23));
        let read = |earth: &ProceduralEarth, id: NodeId| {
            let mut data = NodeData::default();
            earth.read_node(id, &mut data).unwrap();
            data
        };
        // 48 and 16 posts are 3 and 1 nodes of level 1 (span 16).
        assert_eq!(read(&shifted, NodeId::new(1, 2, 4)), read(&base, NodeId::new(1, 5, 5)));
        assert_ne!(read(&shifted, NodeId::new(1, 2, 4)), read(&base, NodeId::new(1, 2, 4)));
    }

    #[test]
    fn lattice_values_stay_in_range() {
        for n in 0..10_000u32 {
            let v = lattice(mix64(7), n, n.wrapping_mul(2_654_435_761));
            assert!((-1.0..=1.0).contains(&v));
        }
    }
}
