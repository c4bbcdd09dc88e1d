//! The layers of a pyramid placed on one lattice, and the composite surface
//! the pyramid's posts sample: the best data at every place, blended where
//! a finer layer meets a coarser one.
//!
//! - **Level-0 lattice**: the finest layer's posts (smallest spacing in the
//!   shared coordinate system), extended over the bounding box of every
//!   layer. The finest layer is never resampled.
//! - **Native level** of a layer: the coarsest level whose post spacing does
//!   not exceed the layer's own (`floor(log2(layer spacing / level-0
//!   spacing))`, the smaller of the two axes): its posts are at most twice as
//!   dense as the data, and no data are lost.
//! - **A layer's surface** is its native level's: the layer sampled at the
//!   native level's posts (its own posts joined as south-west to north-east
//!   triangles), those posts joined as the same triangles. Every finer
//!   level's post outside finer layers therefore lies on the surface the
//!   native level's nodes draw, so where a finer node is absent its coarser
//!   ancestor draws exactly the same surface: no crack where the level
//!   changes.
//! - **Composite**: layers are applied coarsest first; each layer's height
//!   (its own posts joined as south-west to north-east triangles) replaces
//!   the height so far by a weight `w` rising from 0 at the layer's edge or
//!   at a no-data post of the layer to 1 at [`BLEND_MARGIN_M`] inside it, as
//!   a cosine ramp `w = (1 - cos(pi d / margin)) / 2`. Where nothing is
//!   under a layer it is taken as it is; where a layer has no data (a large
//!   void) the coarser layers show through.

use rayon::prelude::*;

use crate::dem::GridView;
use crate::node::cell_surface;

/// Width of the blend inside a finer layer's edge (and around its large
/// voids), metres: a few kilometres, some 30 to 40 posts of SRTM 3", so the
/// join of two layers that disagree by 100 m slopes by under 4 %.
pub const BLEND_MARGIN_M: f64 = 3000.0;

/// Slack, in posts, for positions that should be on a post.
const ON_POST: f64 = 1e-6;

/// One layer placed on the level-0 lattice.
pub(crate) struct PlacedLayer<'a> {
    pub grid: GridView<'a>,
    /// The layer's post (0, 0) in level-0 posts.
    pub offset: [f64; 2],
    /// The layer's spacing in level-0 posts.
    pub scale: [f64; 2],
    /// The layer's posts are level-0 posts (`scale` 1, integral `offset`).
    pub exact: Option<[i64; 2]>,
    /// The coarsest level whose posts are at least as dense as the layer's.
    pub native: u8,
    /// The last level-0 post of the pyramid, east and north (positions
    /// past it take its place, as nodes' posts do).
    pub last: [i64; 2],
    /// Blend weight per post of the layer, when a coarser layer may lie under it.
    pub weights: Option<&'a [f32]>,
}

impl PlacedLayer<'_> {
    /// The layer's closed bounding box in level-0 posts: `[min, max]` per axis.
    pub fn bounds(&self) -> [[f64; 2]; 2] {
        let size = [self.grid.width, self.grid.height];
        [0, 1].map(|a| [self.offset[a], self.offset[a] + (size[a] - 1) as f64 * self.scale[a]])
    }

    /// The layer's surface at level-0 post `(i, j)`: its native level's
    /// posts joined as triangles; NaN outside the layer or where a corner
    /// has no data.
    pub fn height(&self, i: i64, j: i64) -> f32 {
        if self.native == 0 {
            return self.sample(i, j, self.grid.heights);
        }
        let step = 1i64 << self.native;
        let (k, m) = (i.div_euclid(step) * step, j.div_euclid(step) * step);
        let (fu, fv) = ((i - k) as f64 / step as f64, (j - m) as f64 / step as f64);
        let post = |x: i64, y: i64| {
            self.sample(x.clamp(0, self.last[0]), y.clamp(0, self.last[1]), self.grid.heights)
                as f64
        };
        // On a post or a cell edge, only the posts there count (a corner
        // without data elsewhere must not void it).
        let h00 = post(k, m);
        let surface = match (fu == 0.0, fv == 0.0) {
            (true, true) => h00,
            (true, false) => h00 + fv * (post(k, m + step) - h00),
            (false, true) => h00 + fu * (post(k + step, m) - h00),
            (false, false) => {
                let (h10, h01, h11) =
                    (post(k + step, m), post(k, m + step), post(k + step, m + step));
                cell_surface(h00, h10, h01, h11, fu, fv)
            }
        };
        surface as f32
    }

    /// The blend weight at level-0 post `(i, j)` (1 without a weight raster).
    pub fn weight(&self, i: i64, j: i64) -> f32 {
        match self.weights {
            Some(weights) => {
                let w = self.sample(i, j, weights);
                if w.is_nan() {
                    0.0
                } else {
                    w
                }
            }
            None => 1.0,
        }
    }

    fn sample(&self, i: i64, j: i64, values: &[f32]) -> f32 {
        let (w, h) = (self.grid.width as i64, self.grid.height as i64);
        if let Some([ox, oy]) = self.exact {
            let (p, q) = (i - ox, j - oy);
            if p < 0 || q < 0 || p >= w || q >= h {
                return f32::NAN;
            }
            return values[(q * w + p) as usize];
        }
        let u = (i as f64 - self.offset[0]) / self.scale[0];
        let v = (j as f64 - self.offset[1]) / self.scale[1];
        // Level-0 posts within half a level-0 cell of the layer's edge take
        // the edge: lattices that are half a cell apart still meet.
        let slack = [0.5 / self.scale[0], 0.5 / self.scale[1]];
        let (Some((p, fu)), Some((q, fv))) = (cell(u, w, slack[0]), cell(v, h, slack[1])) else {
            return f32::NAN;
        };
        let at = |p: i64, q: i64| values[(q * w + p) as usize] as f64;
        let (p1, q1) = ((p + 1).min(w - 1), (q + 1).min(h - 1));
        let corners = [at(p, q), at(p1, q), at(p, q1), at(p1, q1)];
        if corners.iter().any(|c| c.is_nan()) {
            // On a post with data the neighbours do not matter.
            let snap = |f: f64| (f < ON_POST).then_some(0).or((f > 1.0 - ON_POST).then_some(1));
            return match (snap(fu), snap(fv)) {
                (Some(a), Some(b)) => corners[a + 2 * b] as f32,
                _ => f32::NAN,
            };
        }
        cell_surface(corners[0], corners[1], corners[2], corners[3], fu, fv) as f32
    }
}

/// The cell holding `position` (in posts of a line of `count` posts) and
/// the fraction across it; `None` farther than `slack` posts outside the line.
fn cell(position: f64, count: i64, slack: f64) -> Option<(i64, f64)> {
    let last = (count - 1) as f64;
    let slack = slack.max(ON_POST);
    if !(position >= -slack && position <= last + slack) {
        return None;
    }
    let position = position.clamp(0.0, last);
    let p = (position.floor() as i64).min((count - 2).max(0));
    Some((p, position - p as f64))
}

/// Every layer on the level-0 lattice, coarsest first (the order of the blend).
pub(crate) struct Composite<'a> {
    pub layers: Vec<PlacedLayer<'a>>,
}

impl Composite<'_> {
    /// The best data at level-0 post `(i, j)`: NaN where no layer has data.
    pub fn height(&self, i: i64, j: i64) -> f32 {
        self.height_without(i, j, usize::MAX)
    }

    /// The height at `(i, j)` from every layer except `skip`, NaN where
    /// none of them has data.
    pub fn height_without(&self, i: i64, j: i64, skip: usize) -> f32 {
        let mut height = f32::NAN;
        for (k, layer) in self.layers.iter().enumerate() {
            let h = if k == skip { f32::NAN } else { layer.height(i, j) };
            if !h.is_nan() {
                height =
                    if height.is_nan() { h } else { height + layer.weight(i, j) * (h - height) };
            }
        }
        height
    }
}

/// Rows of a layer between two calls of the release callback of
/// [`blend_weights_into`]: a few MB of a world-wide grid's rows.
const WEIGHT_BAND_ROWS: usize = 64;

/// Blend weights of `grid`: 0 on its edge posts and its no-data posts,
/// rising as a cosine ramp to 1 at [`BLEND_MARGIN_M`] from the nearest of
/// them (chamfer distance in metres, `spacing_m` between posts).
pub(crate) fn blend_weights(grid: GridView, spacing_m: [f64; 2]) -> Vec<f32> {
    let mut distance = vec![0.0f64; grid.heights.len()];
    let mut weights = vec![0.0f32; grid.heights.len()];
    blend_weights_into(grid, spacing_m, &mut distance, &mut weights, &mut || {});
    weights
}

/// [`blend_weights`] into `weights`, with `distance` (one per post) as
/// scratch; `band_done` is called every [`WEIGHT_BAND_ROWS`] rows of each
/// sweep, so memory-mapped arrays can drop the pages behind it.
pub(crate) fn blend_weights_into(
    grid: GridView,
    spacing_m: [f64; 2],
    d: &mut [f64],
    weights: &mut [f32],
    band_done: &mut dyn FnMut(),
) {
    let (w, h) = (grid.width as usize, grid.height as usize);
    debug_assert!(d.len() == w * h && weights.len() == w * h);
    let band = WEIGHT_BAND_ROWS * w;
    d.par_chunks_mut(w).enumerate().for_each(|(j, row)| {
        for (i, d) in row.iter_mut().enumerate() {
            let edge = i == 0 || j == 0 || i + 1 == w || j + 1 == h;
            *d = if edge || grid.heights[j * w + i].is_nan() { 0.0 } else { f64::INFINITY };
        }
    });
    band_done();
    let [sx, sy] = spacing_m;
    let diagonal = (sx * sx + sy * sy).sqrt();
    // Forward pass: west, south-west, south, south-east neighbours.
    for j in 0..h {
        for i in 0..w {
            let mut best = d[j * w + i];
            if i > 0 {
                best = best.min(d[j * w + i - 1] + sx);
            }
            if j > 0 {
                best = best.min(d[(j - 1) * w + i] + sy);
                if i > 0 {
                    best = best.min(d[(j - 1) * w + i - 1] + diagonal);
                }
                if i + 1 < w {
                    best = best.min(d[(j - 1) * w + i + 1] + diagonal);
                }
            }
            d[j * w + i] = best;
        }
        if j % WEIGHT_BAND_ROWS == WEIGHT_BAND_ROWS - 1 {
            band_done();
        }
    }
    // Backward pass: east, north-east, north, north-west neighbours.
    for j in (0..h).rev() {
        for i in (0..w).rev() {
            let mut best = d[j * w + i];
            if i + 1 < w {
                best = best.min(d[j * w + i + 1] + sx);
            }
            if j + 1 < h {
                best = best.min(d[(j + 1) * w + i] + sy);
                if i + 1 < w {
                    best = best.min(d[(j + 1) * w + i + 1] + diagonal);
                }
                if i > 0 {
                    best = best.min(d[(j + 1) * w + i - 1] + diagonal);
                }
            }
            d[j * w + i] = best;
        }
        if j % WEIGHT_BAND_ROWS == 0 {
            band_done();
        }
    }
    for (out, d) in weights.chunks_mut(band).zip(d.chunks(band)) {
        out.par_iter_mut().zip(d).for_each(|(w, &d)| *w = ramp(d / BLEND_MARGIN_M));
        band_done();
    }
}

/// The cosine ramp: 0 at `t <= 0`, 1 at `t >= 1`, smooth in between.
pub fn ramp(t: f64) -> f32 {
    let t = t.clamp(0.0, 1.0);
    (0.5 - 0.5 * (std::f64::consts::PI * t).cos()) as f32
}
