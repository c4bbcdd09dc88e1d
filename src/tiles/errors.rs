//! The errors a frame's tiles are extracted at (issue 22): what the bound
//! allows each tile for this viewport and tau, no less, quantised so that
//! a tile is remade only when its error moves by a step.
//!
//! A tile of level `l` is drawn from its level's ring on, `split_l` away
//! or more, so Ulrich's bound `delta K / D <= tau` holds for it at
//! `delta_l = tau split_l / K` less its map's reference delta, and along
//! its morph toward the parent too: the rings' consistency rule starts
//! every morph past the band's near end, and the blend's error is linear
//! in the distance as the bound is (`morphs_start_past_their_band` below).
//!
//! Until the data's cut face was drawn solid ([`super::curtain`]) the
//! errors kept a margin of `1 - morph`: the cracks between leaf tiles of
//! other nodes or sub-levels are as deep as both sides' errors, and seen
//! from past the data's edge, beneath the cut face, their skirts erred up
//! to 2.6 tau. With curtains no skirt is seen from below, the margin went,
//! and the lod bench's LOD/RTIN-floor ratio at 1280x720 fell from 4.1 to
//! 2.8 (tau 1) and 6.3 to 3.8 (tau 4), p99.9 within tau.
//! A *leaf* tile (no finer node under it) is drawn however near the camera
//! comes: nearer than its level's ring it takes *sub-levels*, the ring
//! halved `k` times and the error with it, each morphing toward the one
//! above over the outer part of its band, as the levels do. Each vertex
//! follows the band of the ring its own place falls in (its *morph band*),
//! and a leaf tile's rule starts fine enough for every vertex it holds
//! ([`MeshErrors::leaf_distance`]): a vertex's error, band and target do
//! not depend on the tile it is cut in, so leaf tiles of other sub-levels
//! share their edges (issue 25).
//!
//! Within its ring a tile's error grows with each vertex's distance
//! ([`RingView`], issue 22), from an anchor each ring keeps until the
//! camera moves past its slack.

use super::by_distance::{reach_legs, DistanceRule, RingView, ViewCone};
use crate::camera::Camera;

/// Sub-levels a leaf tile may take: the error halves each time, 2^-16 of
/// its level's at the most.
pub const MAX_SUB_LEVEL: u8 = 16;

/// Rings a level has: sub-levels 0 to [`MAX_SUB_LEVEL`].
const SUBS: usize = MAX_SUB_LEVEL as usize + 1;

/// Share of a ring's near end the camera may travel from its anchor before
/// the ring's tiles are made again ([`RingView::slack_m`]): more remakes
/// the smaller, more triangles the larger.
pub const SLACK_SHARE: f64 = 0.1;

/// How far, radians, the view of a near ring is widened each side
/// ([`RingView::cone`]); the camera may turn half of it before the ring's
/// tiles are made again.
pub const TURN_RAD: f64 = 0.26;

/// Whether a ring's vertices out of the camera's view are left out: the
/// near rings (level 0's, and every leaf tile's sub-levels), whose tiles
/// reach around and behind the camera. Farther rings keep every direction:
/// their tiles straddle the frustum less, and a turn would make them all
/// again.
fn coned(level: usize, sub: usize) -> bool {
    level == 0 || sub > 0
}

/// Quantisation steps a doubling of the error spans.
const STEPS_PER_OCTAVE: f64 = 8.0;

/// `value` on the lattice of `step` (itself where the step is not a
/// positive number): within half a step.
fn snap(value: f64, step: f64) -> f64 {
    if step.is_finite() && step > 0.0 {
        (value / step).round() * step
    } else {
        value
    }
}

/// Steps of a ring's cone's camera angles: rounding each of the three by
/// half of it turns the camera by at most `sqrt 3 / 4` of it, within the
/// half of [`TURN_RAD`] a cone allows.
const ANGLE_STEP_RAD: f64 = TURN_RAD / 4.0;

/// `camera` at `anchor_m` and `slack_m` (its height snapped to the slack's
/// lattice: within half of it), its angles snapped to [`ANGLE_STEP_RAD`].
fn snapped(camera: &Camera, anchor_m: [f64; 2], slack_m: f64) -> Camera {
    let step = ANGLE_STEP_RAD.to_degrees();
    let mut c = *camera;
    c.position = glam::DVec3::new(anchor_m[0], anchor_m[1], snap(c.position.z, slack_m));
    c.heading_deg = snap(c.heading_deg, step);
    c.pitch_deg = snap(c.pitch_deg, step);
    c.roll_deg = snap(c.roll_deg, step);
    c
}

/// `value` on the lattice of `steps` an octave, rounded by `round` (down
/// or up); infinite or not positive values as they are.
fn quantised(value: f64, round: fn(f64) -> f64, steps: f64) -> f64 {
    if !(value.is_finite() && value > 0.0) {
        return value;
    }
    (round(steps * value.log2()) / steps).exp2()
}

/// Steps an octave of the bound's error per metre in the rings' errors by
/// distance: every tile's errors move with it at once, so a step of it
/// moves a frame's triangles by about its share (2 %), within what a
/// frame budget holds; the rings' distances move one level at a time and
/// keep the errors' steps.
const PER_M_STEPS: f64 = 256.0;

/// Steps an octave of the rings' distances in their errors by distance.
const RING_STEPS: f64 = 256.0;

/// A quantised error: `2^(step / 4)` metres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct ErrorStep(pub i16);

impl ErrorStep {
    /// The largest step whose error is at most `error_m` (tiny errors
    /// clamp to the smallest step).
    pub fn at_most(error_m: f64) -> ErrorStep {
        if error_m.is_nan() || error_m <= 0.0 {
            return ErrorStep(i16::MIN);
        }
        let step = (STEPS_PER_OCTAVE * error_m.log2()).floor();
        ErrorStep(step.clamp(i16::MIN as f64 + 1.0, i16::MAX as f64) as i16)
    }

    /// The error of this step, metres (0 for the smallest step).
    pub fn metres(self) -> f64 {
        if self.0 == i16::MIN {
            0.0
        } else {
            (self.0 as f64 / STEPS_PER_OCTAVE).exp2()
        }
    }

    /// The step a sub-level `k` below this one: the error halved `k` times.
    pub fn halved(self, k: u8) -> ErrorStep {
        if self.0 == i16::MIN {
            return self;
        }
        ErrorStep(self.0.saturating_sub(STEPS_PER_OCTAVE as i16 * k as i16).max(i16::MIN + 1))
    }
}

/// What a frame's tiles are extracted at, per level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshErrors {
    /// Per level: the error its tiles are extracted at at their ring.
    pub level: Vec<ErrorStep>,
    /// Per level: the distance a leaf tile's sub-level 0 reaches down to,
    /// metres (the level's ring, or half the next for level 0).
    pub leaf_ring: Vec<f64>,
    /// Share of each band its tiles morph over, toward the band above.
    pub morph_range: f64,
    /// Per ring (level times sub-levels, sub-level fastest): its errors by
    /// distance and how many times they changed ([`Self::anchor`]).
    pub ring_views: Vec<RingState>,
    /// Per level: the ring generations of it and every level above, summed
    /// (a tile's mesh keeps its ancestors' vertices).
    chain: Vec<u32>,
    /// The bound's metres of error per metre, `tau / K`, last updated.
    per_m: f64,
    /// Per level: its maps' reference delta, last updated.
    reference: Vec<f64>,
    /// Per level: the error its ring allows, not quantised, metres.
    allowed: Vec<f64>,
    /// The camera's ground position the rings were last anchored for,
    /// chart metres.
    eye_m: [f64; 2],
    /// How far above the highest terrain the camera is, metres (0 when
    /// not above it): no point of the terrain is nearer.
    clearance_m: f64,
}

/// One ring's errors by distance ([`RingView`]) and its generation: tiles
/// made with another are made again.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RingState {
    /// Its errors by distance.
    pub view: RingView,
    /// How many times they changed (0: never set).
    pub generation: u32,
}

/// What the maps of each level can do: the smallest error their sparse
/// maps serve (0 where every map is dense) and the largest error of their
/// reference lattices, metres, per level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MapErrors {
    /// Per level, the floor.
    pub floor: Vec<f64>,
    /// Per level, the reference delta.
    pub reference: Vec<f64>,
    /// Per level, the error of its coarsest meshes.
    pub max: Vec<f64>,
}

impl MapErrors {
    /// The floor of `level` (0 past the table).
    pub fn floor(&self, level: u8) -> f64 {
        self.floor.get(level as usize).copied().unwrap_or(0.0)
    }

    /// Whether the terrain has error maps at all (else tiles are grids,
    /// whose triangles tau does not change).
    pub fn is_empty(&self) -> bool {
        self.floor.is_empty()
    }

    /// The error of `level`'s coarsest meshes (0 past the table).
    pub fn max(&self, level: u8) -> f64 {
        self.max.get(level as usize).copied().unwrap_or(0.0)
    }

    /// The reference delta of `level` (0 past the table).
    pub fn reference(&self, level: u8) -> f64 {
        self.reference.get(level as usize).copied().unwrap_or(0.0)
    }
}

/// The errors one tile is made with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileErrors {
    /// Its sub-level (0 but for leaf tiles nearer than their level's ring).
    pub sub_level: u8,
    /// The error it is extracted at.
    pub own: ErrorStep,
    /// The error of the mesh it morphs toward: the same node's one
    /// sub-level up, or the parent level's at sub-level 0.
    pub target: ErrorStep,
    /// The generations of the rings its mesh depends on, summed: its own,
    /// its target's and its ancestors' ([`MeshErrors::anchor`]).
    pub views: u32,
    /// A leaf tile: its rule starts at a sub-level no ring finer than
    /// reaches its vertices ([`MeshErrors::leaf_distance`]), so every
    /// vertex takes the error and morph band of the rule of all its
    /// level's sub-levels, as its banded neighbours' do.
    pub banded: bool,
}

impl MeshErrors {
    /// Fills the table for rings `split` (per level, metres; 0 for level
    /// 0), `k` (Ulrich's K), `tau_px`, `morph_range` and the maps' floors
    /// and reference deltas per level (`maps`). Reuses its buffers.
    pub fn update(
        &mut self,
        split: impl Fn(u8) -> f64,
        levels: u8,
        k: f64,
        tau_px: f64,
        morph_range: f64,
        maps: &MapErrors,
    ) {
        self.level.clear();
        self.allowed.clear();
        self.leaf_ring.clear();
        self.reference.clear();
        self.morph_range = morph_range;
        self.per_m = tau_px / k;
        for level in 0..levels {
            let ring = if level == 0 || split(level) <= 0.0 {
                split(level.saturating_add(1).min(levels - 1)) / 2.0
            } else {
                split(level)
            };
            // The reference lattice's own error comes on top of the mesh's.
            let allowed = tau_px * ring / k - maps.reference(level);
            let wanted = ErrorStep::at_most(allowed.max(maps.floor(level)));
            self.allowed.push(allowed.max(maps.floor(level)));
            self.level.push(wanted);
            self.leaf_ring.push(ring);
            self.reference.push(maps.reference(level));
        }
    }

    /// Sets each ring's errors by distance for a camera over `eye_m`
    /// (chart metres) and the levels' morphs `morph` (start and end per
    /// level, metres), after [`Self::update`]; with `camera`, the near
    /// rings keep nothing of their own out of its view. A ring's anchor is
    /// the camera's place snapped to a lattice of its slack (its cone's
    /// camera snapped likewise, and its angles to `ANGLE_STEP_RAD`), so
    /// the camera is always within its slack; when that or its errors
    /// change the ring takes a new generation.
    pub fn anchor(
        &mut self,
        eye_m: [f64; 2],
        camera: Option<&Camera>,
        morph: impl Fn(u8) -> (f64, f64),
    ) {
        let levels = self.level.len();
        self.eye_m = eye_m;
        self.ring_views.resize(levels * SUBS, RingState::default());
        for level in 0..levels {
            for sub in 0..SUBS {
                let near = self.leaf_ring[level] / (1u64 << sub) as f64;
                let (start, end) = match sub {
                    0 => morph(level as u8),
                    k => self.sub_level_morph(level as u8, k as u8),
                };
                // Quantised as the errors are, each toward the side that
                // keeps the bound, so that a budget moving tau a little
                // does not make every tile again.
                let near = quantised(near, f64::floor, RING_STEPS);
                let slack = SLACK_SHARE * near;
                // The anchor and the cone's camera snap to lattices, so a
                // ring's errors depend on where the camera is, not on the
                // way it came: the same place draws the same meshes.
                let anchor = eye_m.map(|v| snap(v, slack));
                let cone = camera
                    .filter(|_| coned(level, sub))
                    .and_then(|c| ViewCone::of_camera(&snapped(c, anchor, slack), TURN_RAD));
                let wanted = RingView {
                    anchor_m: anchor,
                    slack_m: slack,
                    near_m: near,
                    start_m: quantised(start, f64::floor, RING_STEPS).max(near),
                    end_m: quantised(end, f64::ceil, RING_STEPS).max(near),
                    per_m: quantised(self.per_m, f64::floor, PER_M_STEPS),
                    reference_m: self.reference[level],
                    own_m: self.level[level].halved(sub as u8).metres(),
                    cone,
                };
                let state = &mut self.ring_views[level * SUBS + sub];
                if state.generation == 0 || wanted != state.view {
                    state.view = wanted;
                    state.generation = state.generation.wrapping_add(1).max(1);
                }
            }
        }
        self.chain.clear();
        self.chain.resize(levels + 1, 0);
        for level in (0..levels).rev() {
            let own = self.ring_views[level * SUBS].generation;
            self.chain[level] = self.chain[level + 1].wrapping_add(own);
        }
    }

    /// The errors by distance of `level`'s sub-level `sub` (`None` before
    /// [`Self::anchor`], or past the table).
    pub fn ring_view(&self, level: u8, sub: u8) -> Option<RingView> {
        if sub as usize >= SUBS {
            return None;
        }
        self.ring_views.get(level as usize * SUBS + sub as usize).map(|b| b.view)
    }

    /// The errors by distance of a mesh of `level`'s sub-level `sub`: its
    /// ring's, then each coarser sub-level's up to the level's own
    /// ([`DistanceRule`]); `ends`: past the level's own ring the level above
    /// shows. `None` before [`Self::anchor`].
    pub fn rule(&self, level: u8, sub: u8, ends: bool) -> Option<DistanceRule> {
        let finest = sub.min(MAX_SUB_LEVEL);
        let mut rule = DistanceRule { rings: Default::default(), ends, finest };
        for k in (0..=finest).rev() {
            rule.rings.push(self.ring_view(level, k)?);
        }
        Some(rule)
    }

    /// The errors by distance of the mesh a tile made with
    /// [`Self::rule`]`(level, sub, ends)` morphs toward, vertex by vertex:
    /// where sub-level `k >= 1`'s ring gives a vertex its error, the error
    /// sub-level `k - 1`'s ring has at its near end (where that ring takes
    /// over, fully morphed); where the level's own ring does, the level
    /// above's mesh (`ends`), or the tile's own (no level above: no morph).
    /// Each ring keeps its anchor, slack, end and cone, so a vertex falls
    /// in the same ring in both rules, and in every tile's: the target of
    /// a shared edge is the same on both sides. `None` before
    /// [`Self::anchor`].
    pub fn target_rule(&self, level: u8, sub: u8, ends: bool) -> Option<DistanceRule> {
        let finest = sub.min(MAX_SUB_LEVEL);
        let mut rule = DistanceRule { rings: Default::default(), ends, finest };
        for k in (1..=finest).rev() {
            let (ring, coarser) = (self.ring_view(level, k)?, self.ring_view(level, k - 1)?);
            let near = coarser.near_m;
            rule.rings.push(RingView { near_m: near, start_m: near, own_m: coarser.own_m, ..ring });
        }
        if !ends {
            rule.rings.push(self.ring_view(level, 0)?);
        }
        Some(rule)
    }

    /// The bound's metres of error per metre of distance, `tau / K`, last
    /// updated (not quantised).
    pub fn per_m(&self) -> f64 {
        self.per_m
    }

    /// The error a tile of `level`'s sub-level `sub` is allowed at its
    /// ring's near end, not quantised (0 past the table): what a frame
    /// budget's estimates scale by, smoothly in tau, where the tiles' own
    /// errors move in steps.
    pub fn allowed_m(&self, level: u8, sub: u8) -> f64 {
        let allowed = self.allowed.get(level as usize).copied().unwrap_or(0.0);
        allowed / (1u64 << sub.min(MAX_SUB_LEVEL)) as f64
    }

    /// The generation of `level`'s sub-level `sub` (0 past the table).
    fn generation(&self, level: u8, sub: u8) -> u32 {
        let at = level as usize * SUBS + sub as usize;
        self.ring_views.get(at).map_or(0, |b| b.generation)
    }

    /// The tau past which no level's tiles get any coarser, pixels: every
    /// level's error reaches its coarsest meshes' (the table as last
    /// filled by [`Self::update`] at `tau_px`, whose errors are linear in
    /// tau but for the reference deltas).
    pub fn tau_ceiling(&self, maps: &MapErrors, k: f64, tau_px: f64) -> f64 {
        let mut ceiling = tau_px;
        for (level, &ring) in self.leaf_ring.iter().enumerate() {
            let level = level as u8;
            let coarsest = maps.max(level) + maps.reference(level);
            if ring > 0.0 && coarsest > 0.0 {
                ceiling = ceiling.max(coarsest * k / ring);
            }
        }
        ceiling
    }

    /// The errors of a tile of `level` at `distance` metres; `leaf`: no
    /// finer node lies under it.
    pub fn for_tile(&self, level: u8, distance: f64, leaf: bool) -> TileErrors {
        let l = level as usize;
        let own = self.level.get(l).copied().unwrap_or_default();
        let parent = self.level.get(l + 1).copied().unwrap_or(own);
        // The clearance is the same for every tile: their rules stay alike.
        let at = distance.max(self.clearance_m);
        let sub_level = if leaf { self.sub_level(level, at) } else { 0 };
        let target = if sub_level == 0 { parent } else { own.halved(sub_level - 1) };
        // Its rule chains its sub-levels up to its level's own ring.
        let rings = (0..=sub_level).map(|k| self.generation(level, k));
        let above = self.chain.get(l + 1).copied().unwrap_or(0);
        let views = rings.fold(above, u32::wrapping_add);
        TileErrors { sub_level, own: own.halved(sub_level), target, views, banded: leaf }
    }

    /// Sets how far above the highest terrain the camera is (metres; 0 or
    /// less: not above it). No leaf tile's rule starts at a sub-level
    /// nearer than that ([`Self::for_tile`]): every point is at least that
    /// far from the eye, so the bound holds there, and a camera high above
    /// the terrain does not make the tiles under it again whenever its
    /// finest rings move.
    pub fn set_clearance(&mut self, clearance_m: f64) {
        self.clearance_m = if clearance_m.is_finite() { clearance_m.max(0.0) } else { 0.0 };
    }

    /// The ground distance from the camera's place at the last
    /// [`Self::anchor`] to the rectangle `[lo_m, hi_m]` (chart metres, east
    /// and north): what the rings measure, unlike a tile's distance in the
    /// selection (to its box, heights included).
    pub fn ground_distance(&self, lo_m: [f64; 2], hi_m: [f64; 2]) -> f64 {
        let gap = |k: usize| (lo_m[k] - self.eye_m[k]).max(self.eye_m[k] - hi_m[k]).max(0.0);
        gap(0).hypot(gap(1))
    }

    /// The distance a leaf tile `distance_m` away on the ground
    /// ([`Self::ground_distance`]), `width_m` wide, takes its sub-level
    /// at: the nearest any of its vertices' splits reaches
    /// (a split of the tile's square reaches [`reach_legs`] of its width),
    /// less both ways the camera may move within a ring's slack. A ring
    /// finer than that sub-level's takes none of the tile's vertices
    /// wherever its anchor is, so the tile's rule, starting there, gives
    /// every vertex the error and band that a rule of all the level's
    /// sub-levels does: the rule every neighbour's mesh follows too.
    pub fn leaf_distance(distance_m: f64, width_m: f64) -> f64 {
        (distance_m - width_m * reach_legs()) / (1.0 + 2.0 * SLACK_SHARE + 0.05)
    }

    /// The sub-level of a leaf tile of `level` `distance` metres away: how
    /// many times its level's ring halves before it is no farther than the
    /// tile.
    pub fn sub_level(&self, level: u8, distance: f64) -> u8 {
        let ring = self.leaf_ring.get(level as usize).copied().unwrap_or(0.0);
        if ring.is_nan() || ring <= 0.0 || distance >= ring {
            return 0;
        }
        let halvings = (ring / distance.max(1e-3)).log2().ceil();
        halvings.clamp(0.0, MAX_SUB_LEVEL as f64) as u8
    }

    /// The morph of a leaf tile of `level` at sub-level `k >= 1` toward
    /// sub-level `k - 1`: `(start, end)` metres.
    pub fn sub_level_morph(&self, level: u8, k: u8) -> (f64, f64) {
        let ring = self.leaf_ring.get(level as usize).copied().unwrap_or(0.0);
        let end = ring / (1u64 << (k.max(1) - 1)) as f64;
        (end * (1.0 - self.morph_range), end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_at_most_the_error_and_halve_by_four() {
        for e in [0.003, 0.1, 1.0, 7.3, 12.0, 450.0] {
            let s = ErrorStep::at_most(e);
            assert!(s.metres() <= e && s.metres() > e / 2f64.powf(0.25) - 1e-12, "{e}");
            assert!((s.halved(1).metres() * 2.0 - s.metres()).abs() < 1e-9);
        }
        assert_eq!(ErrorStep::at_most(0.0).metres(), 0.0);
    }

    #[test]
    fn leaf_tiles_nearer_than_their_ring_halve_their_error() {
        let mut errors = MeshErrors::default();
        let rings = [0.0, 20_000.0, 40_000.0, 80_000.0];
        errors.update(|l| rings[l as usize], 4, 1000.0, 1.0, 0.3, &MapErrors::default());
        // Level 0's sub-level 0 reaches down to half of level 1's ring.
        assert_eq!(errors.sub_level(0, 10_000.0), 0);
        assert_eq!(errors.sub_level(0, 9_999.0), 1);
        assert_eq!(errors.sub_level(0, 2_400.0), 3);
        let near = errors.for_tile(0, 2_400.0, true);
        assert_eq!(near.own, errors.level[0].halved(3));
        assert_eq!(near.target, errors.level[0].halved(2));
        // A tile with finer data under it never takes a sub-level.
        assert_eq!(errors.for_tile(2, 1.0, false).sub_level, 0);
        // The bound: the error at the band's near end is tau D / K at most,
        // and within a step of it.
        let (_, end) = errors.sub_level_morph(0, 3);
        assert!((end - 2_500.0).abs() < 1e-9);
        let at_near_end = near.own.metres() * 1000.0 / 1_250.0;
        assert!(at_near_end <= 1.0 + 1e-12 && at_near_end > 2f64.powf(-0.125) - 1e-12);
    }
    #[test]
    fn rings_anchor_on_a_lattice_of_their_slack() {
        let (mut errors, rings, morph) = (anchored(), RINGS, ring_morph);
        let (tile, leaf) = (errors.for_tile(1, 25_000.0, false), errors.for_tile(0, 3_000.0, true));
        let ring = errors.ring_view(1, 0).expect("anchored");
        let slack = SLACK_SHARE * 20_000.0;
        assert!(ring.slack_m <= slack && ring.slack_m > 0.9 * slack, "{}", ring.slack_m);
        // Level 1's slack is about 2 km, level 0's 1 km (its near end is
        // 10 km): a move of 0.4 of level 1's keeps its lattice point and
        // leaves level 0's.
        let s1 = ring.slack_m;
        errors.anchor([0.4 * s1, 0.0], None, morph);
        assert_eq!(errors.for_tile(1, 25_000.0, false), tile, "within level 1's lattice cell");
        assert_ne!(errors.for_tile(0, 3_000.0, true).views, leaf.views, "past level 0's");
        errors.anchor([0.4 * s1, 0.6 * s1], None, morph);
        assert_ne!(errors.for_tile(1, 25_000.0, false).views, tile.views, "past level 1's");
        assert_eq!(errors.ring_view(1, 0).expect("anchored").anchor_m, [0.0, s1]);
        // The same place gives the same errors whatever the way there.
        errors.anchor([0.0, 0.0], None, morph);
        errors.anchor([0.4 * s1, 0.6 * s1], None, morph);
        assert_eq!(errors.ring_view(1, 0).expect("anchored").anchor_m, [0.0, s1]);
        // A new tau moves every ring's errors: all tiles are made again.
        let now = errors.for_tile(2, 50_000.0, false);
        errors.update(|l| rings[l as usize], 4, 1000.0, 2.0, 0.3, &MapErrors::default());
        errors.anchor([0.4 * s1, 0.6 * s1], None, morph);
        assert_ne!(errors.for_tile(2, 50_000.0, false).views, now.views);
        // A rule chains a leaf tile's sub-levels up to its level's ring.
        let rule = errors.rule(0, 3, true).expect("anchored");
        let nears: Vec<f64> = rule.rings.iter().map(|b| b.near_m).collect();
        for (near, exact) in nears.iter().zip([1_250.0, 2_500.0, 5_000.0, 10_000.0]) {
            // Quantised down, by less than a step.
            assert!(*near <= exact && *near > exact * 2f64.powf(-0.125), "{near} for {exact}");
        }
    }

    /// Every morph starts past its band's near end, so a tile extracted at
    /// the full error the bound allows there keeps the bound all along its
    /// morph: within tau at the start, where it draws its own mesh, and at
    /// the end, where it draws its target.
    #[test]
    fn morphs_start_past_their_band() {
        use crate::lod::rings::RingInputs;
        use crate::lod::{LevelRings, LodConfig};
        let (k, levels) = (1108.5, 9u8);
        for (tau, morph_range, view_distance) in [(1.0, 0.3, 3.0), (4.0, 0.5, 1.0), (2.0, 0.1, 5.0)]
        {
            let config =
                LodConfig { tau_px: tau, morph_range, view_distance, ..LodConfig::default() };
            let deltas = [0.0, 3.0, 9.0, 30.0, 80.0, 200.0, 400.0, 900.0, 2000.0];
            let inputs = RingInputs {
                tile_size_m: 32.0 * 90.0,
                delta_per_level: &deltas,
                height_range_m: 4_000.0,
                perspective_scale: k,
            };
            let rings = LevelRings::new(&config, inputs);
            let mut errors = MeshErrors::default();
            let split = |l: u8| rings.split_distance(l);
            errors.update(split, levels, k, tau, morph_range, &MapErrors::default());
            // The error against the bound at `d`.
            let within = |e: ErrorStep, d: f64| e.metres() * k / d <= tau * (1.0 + 1e-9);
            for level in 0..levels - 1 {
                let near = errors.leaf_ring[level as usize];
                let (start, end) = rings.morph(level);
                assert!(start >= near, "level {level}: morph from {start} before {near}");
                assert!(within(errors.level[level as usize], near), "level {level} at {near}");
                assert!(within(errors.level[level as usize + 1], end), "level {level}'s target");
                for sub in 1..4u8 {
                    let tile = errors.for_tile(level, near / f64::from(1u32 << sub), true);
                    let (start, end) = errors.sub_level_morph(level, tile.sub_level);
                    let band = near / f64::from(1u32 << tile.sub_level);
                    assert!(start >= band && within(tile.own, band), "{level}.{sub}");
                    assert!(within(tile.target, end), "{level}.{sub}'s target");
                }
            }
        }
    }

    use proptest::prelude::*;

    /// Rings of 20, 40 and 80 km above level 0.
    const RINGS: [f64; 4] = [0.0, 20_000.0, 40_000.0, 80_000.0];

    /// Their morphs: over the outer 30 % of each band.
    fn ring_morph(level: u8) -> (f64, f64) {
        match RINGS.get(level as usize + 1) {
            Some(&end) => (end * 0.7, end),
            None => (f64::INFINITY, f64::INFINITY),
        }
    }

    /// Errors for [`RINGS`] at tau 1 and K 1000, anchored with the camera
    /// at the origin (no cone: every direction counts).
    fn anchored() -> MeshErrors {
        let mut errors = MeshErrors::default();
        errors.update(|l| RINGS[l as usize], 4, 1000.0, 1.0, 0.3, &MapErrors::default());
        errors.anchor([0.0, 0.0], None, ring_morph);
        errors
    }

    proptest! {
        /// A leaf tile's rule, starting at the sub-level its distance less
        /// its reach gives, gives each of its vertices the error and the
        /// morph band of the rule of all the level's sub-levels: the model
        /// every neighbour's mesh follows, whatever its own sub-level.
        #[test]
        fn a_leaf_rule_agrees_with_the_rule_of_every_sub_level(
            tile_m in 0.0f64..30_000.0,
            width_m in 50.0f64..3_000.0,
            along in 0.0f64..1.0,
            across in 0.0f64..1.0,
            legs in 0.0f64..1.0,
            ends in any::<bool>(),
        ) {
            let errors = anchored();
            let sub = errors.sub_level(0, MeshErrors::leaf_distance(tile_m, width_m));
            let rule = errors.rule(0, sub, ends).expect("anchored");
            let model = errors.rule(0, MAX_SUB_LEVEL, ends).expect("anchored");
            // A vertex of the tile's square east of the camera, whose
            // split's dependants reach at most the square's diagonal split.
            let at = [tile_m + along * width_m, (across - 0.5) * width_m];
            let reach = legs * width_m * reach_legs();
            let heights = [0.0, 100.0];
            prop_assert_eq!(rule.error_at(at, reach, heights), model.error_at(at, reach, heights));
            prop_assert_eq!(rule.band_at(at, 0.0, heights), model.band_at(at, 0.0, heights));
            let target = errors.target_rule(0, sub, ends).expect("anchored");
            let target_model = errors.target_rule(0, MAX_SUB_LEVEL, ends).expect("anchored");
            prop_assert_eq!(
                target.error_at(at, reach, heights),
                target_model.error_at(at, reach, heights)
            );
        }
    }
}
