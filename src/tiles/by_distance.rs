//! The error a tile's mesh may have at each of its vertices (issue 22):
//! what the bound allows at the vertex's own distance, not only at the
//! near end of the tile's ring.
//!
//! A tile of a ring (a level, or a leaf tile's sub-level) lies at least
//! `near` metres from the camera, so its whole mesh may err by what the
//! bound allows there. Its far parts are farther: Ulrich's bound,
//! `delta K / D <= tau`, lets a vertex `D` metres away err by `tau D / K`.
//! A [`RingView`] gives each vertex that error, measured from an *anchor*
//! (the camera's ground position when the ring's tiles were made) with a
//! *slack*: the camera may move `slack` metres from the anchor before the
//! ring's tiles are made again, so the distance used is the vertex's
//! distance to the anchor less the slack.
//!
//! Three rules keep the mesh what the levels' meshes are:
//! - **Conforming.** A vertex of the RTIN is kept when its code (the error
//!   of the mesh without it and everything it splits) is above its
//!   threshold. The vertices a split depends on lie within
//!   [`reach_legs`] legs of it, so with the distance taken less that reach
//!   a vertex's threshold is never above those of the vertices depending on
//!   it: the kept set stays closed under the hierarchy, as with one error
//!   for the whole mesh.
//! - **Bounded.** Every point of a triangle lies within half its hypotenuse
//!   of the vertex that would split it, which is less than that reach: the
//!   triangle's error is within the bound at every point of it.
//! - **Morphed.** Over the ring's morph (from `start` to `end`) the tile
//!   blends toward the mesh above, so a vertex there keeps the error at
//!   `start` (the blend's error is linear in the distance as the bound
//!   is); past `end` it is fully morphed and the tile draws the mesh above,
//!   whose vertices the tile keeps anyway: the ring's own threshold is
//!   never met there. Each vertex morphs over the band of the ring its own
//!   place falls in ([`DistanceRule::band_at`]), so a vertex on an edge
//!   morphs alike in the tiles on both sides.

use crate::camera::{Camera, Frustum};
use glam::{DQuat, Mat4, Vec3};

/// How far, in legs of the triangle a vertex splits, the vertices whose
/// splits depend on it reach: a split's children split the legs, half a leg
/// away, and each generation's legs are `1/sqrt(2)` of the last, so the
/// reach is `a/2 (1 + 1/sqrt 2 + 1/2 + ...) = a / (2 - sqrt 2)`.
pub fn reach_legs() -> f64 {
    1.0 / (2.0 - std::f64::consts::SQRT_2)
}

/// The leg of the triangles that map post `p` splits, in map posts: a
/// square's centre (both coordinates share their lowest set bit) splits
/// the square's diagonal, legs a square side; an edge's midpoint splits an
/// axis-aligned hypotenuse, legs `1/sqrt(2)` of it.
pub fn split_leg(p: [u32; 2]) -> f64 {
    let (a, b) = (p[0].trailing_zeros(), p[1].trailing_zeros());
    let low = a.min(b).min(31);
    let side = (1u64 << (low + 1)) as f64;
    if a == b {
        side
    } else {
        side * std::f64::consts::FRAC_1_SQRT_2
    }
}

/// One ring's errors by distance, fixed while its tiles are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct RingView {
    /// The camera's ground position the distances are taken from, metres
    /// in the chart (the frame's level-0 posts times their spacing).
    pub anchor_m: [f64; 2],
    /// How far the camera may move from the anchor before the ring's
    /// tiles are made again, metres.
    pub slack_m: f64,
    /// The ring's near end: no tile of the ring is nearer, metres.
    pub near_m: f64,
    /// Where its morph starts and ends, metres (`end` infinite: no morph,
    /// the ring's errors then stop growing at `start`).
    pub start_m: f64,
    /// Where the morph ends.
    pub end_m: f64,
    /// The bound's metres of error per metre of distance, `tau / K`.
    pub per_m: f64,
    /// The reference lattice's error, metres, which the mesh's comes on top of.
    pub reference_m: f64,
    /// The ring's quantised error at its near end, metres: the least any
    /// vertex gets.
    pub own_m: f64,
    /// What the camera may see while it keeps within the slack; `None`:
    /// everything. Where a vertex's split cannot be seen the ring keeps no
    /// vertex of its own.
    pub cone: Option<ViewCone>,
}

/// The camera's view at a ring's anchoring, widened by a turn and the
/// ring's slack: the space a camera within them may see.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCone {
    /// The eye: chart metres east and north, and height.
    pub eye_m: [f64; 3],
    /// The attitude it looked with.
    pub attitude: DQuat,
    /// The fields of view it looked with, radians across and up.
    pub fov_rad: [f64; 2],
    /// The frustum, its half angles widened by the turn allowed,
    /// eye-relative.
    pub frustum: Frustum,
}

impl ViewCone {
    /// The view of `camera` at `eye_m` (chart east, north, height), widened
    /// by `turn_rad` each side; `None` when a widened half angle reaches a
    /// right angle (everything ahead and aside may come into view).
    pub fn of_camera(camera: &Camera, turn_rad: f64) -> Option<ViewCone> {
        let fov = [camera.fov_x_deg.to_radians(), camera.fov_y()];
        let [ax, ay] = fov.map(|f| f / 2.0 + turn_rad);
        let right = std::f64::consts::FRAC_PI_2 - 0.02;
        if !(ax < right && ay < right) {
            return None;
        }
        let aspect = ax.tan() / ay.tan();
        let projection = Mat4::perspective_rh_gl((2.0 * ay) as f32, aspect as f32, 0.5, 1.0e7);
        let p = camera.position;
        Some(ViewCone {
            eye_m: [p.x, p.y, p.z],
            attitude: camera.attitude(),
            fov_rad: fov,
            frustum: Frustum::from_view_projection(projection * camera.view()),
        })
    }

    /// Whether `camera` sees nothing this cone (anchored with `turn_rad`)
    /// does not: the same fields of view, turned by at most half the turn
    /// (a rotation moves no ray farther than its angle; the other half
    /// covers the widened frustum's corners).
    pub fn holds(&self, camera: &Camera, turn_rad: f64) -> bool {
        let fov = [camera.fov_x_deg.to_radians(), camera.fov_y()];
        let turned = self.attitude.angle_between(camera.attitude());
        fov == self.fov_rad && turned <= turn_rad / 2.0
    }

    /// Whether the box around `offset_m` (east and north of the eye) of
    /// half side `radius_m`, between `heights` (metres, below the eye by
    /// `eye_m[2]`), meets the frustum. The box reaches down by the
    /// earth's curvature at its far corner, as the display lowers it.
    pub fn meets(&self, offset_m: [f64; 2], radius_m: f64, heights: [f64; 2]) -> bool {
        let [fx, fy] = [0, 1].map(|k| offset_m[k].abs() + radius_m);
        let far = (fx * fx + fy * fy).sqrt();
        let low = heights[0] - radius_m - crate::camera::curvature_drop(far) - self.eye_m[2];
        let high = heights[1] + radius_m - self.eye_m[2];
        let min =
            Vec3::new((offset_m[0] - radius_m) as f32, (offset_m[1] - radius_m) as f32, low as f32);
        let max = Vec3::new(
            (offset_m[0] + radius_m) as f32,
            (offset_m[1] + radius_m) as f32,
            high as f32,
        );
        self.frustum.intersects_box(min, max)
    }
}

impl RingView {
    /// The error the mesh may have at a vertex `distance_m` from the anchor
    /// whose dependants reach `reach_m` around it; `None` past the morph's
    /// end, where the ring keeps only the mesh above's vertices.
    /// `heights`: the lowest and highest the data under the split may be.
    pub fn error_at(&self, offset_m: [f64; 2], reach_m: f64, heights: [f64; 2]) -> Option<f64> {
        // Not `hypot`: chart metres cannot overflow a square, and this runs
        // for every post a mesh may keep.
        let distance_m = (offset_m[0] * offset_m[0] + offset_m[1] * offset_m[1]).sqrt();
        let d = distance_m - reach_m - self.slack_m;
        if d >= self.end_m {
            return None;
        }
        let unseen = |cone: &ViewCone| {
            let from_eye = [0, 1].map(|k| offset_m[k] + self.anchor_m[k] - cone.eye_m[k]);
            !cone.meets(from_eye, reach_m + self.slack_m, heights)
        };
        if self.cone.as_ref().is_some_and(unseen) {
            return None;
        }
        let bound = self.per_m * d.clamp(self.near_m, self.start_m) - self.reference_m;
        Some(bound.max(self.own_m))
    }

    /// The largest error any vertex of the ring's tiles gets, metres
    /// (reference not included).
    pub fn largest_m(&self) -> f64 {
        self.largest_within(f64::INFINITY)
    }

    /// The largest error a vertex at most `distance_m` from the anchor gets.
    pub fn largest_within(&self, distance_m: f64) -> f64 {
        let d = distance_m.clamp(self.near_m, self.start_m);
        (self.per_m * d - self.reference_m).max(self.own_m)
    }

    /// The same ring without its morph's end or cone (a tile with no
    /// mesh to morph toward, past every ring): its errors stop at the
    /// morph's start.
    pub fn without_end(self) -> RingView {
        RingView { end_m: f64::INFINITY, cone: None, ..self }
    }

    /// Whether the ring's errors differ from `other`'s but for the anchor
    /// and the cone.
    pub fn same_errors(&self, other: &RingView) -> bool {
        RingView { anchor_m: other.anchor_m, cone: other.cone, ..*self } == *other
    }
}

/// Rings a rule may chain: a leaf tile's sub-levels up to its level's.
pub const MAX_RINGS: usize = 17;

/// The errors by distance of one mesh: its ring's, then past that ring's
/// morph the next coarser ring's of the same level, and so on up to the
/// level's own ring (a leaf tile's sub-levels: fully morphed, a tile of
/// sub-level `k` shows sub-level `k - 1`'s mesh, which past its own morph
/// shows `k - 2`'s). Past the last ring's morph the mesh keeps no vertex
/// of its own when the level above is there to show (`ends`), else the
/// last ring's errors stop growing at its morph's start.
///
/// Each ring's errors grow with the distance and every ring starts where
/// the finer one ends at an error no smaller than the finer one reaches,
/// so the chain keeps a vertex's threshold at or below those of the
/// vertices depending on it ([`super::by_distance`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DistanceRule {
    /// The rings, finest first.
    pub rings: arrayvec::ArrayVec<RingView, MAX_RINGS>,
    /// Past the last ring's morph the level above shows.
    pub ends: bool,
    /// The sub-level of the first (finest) ring: ring `i` is sub-level
    /// `finest - i`, the morph band its vertices take ([`Self::band_at`]).
    pub finest: u8,
}

impl DistanceRule {
    /// The error the mesh may have at a vertex `distance_m` from the
    /// camera's place (each ring measures from its own anchor) whose
    /// dependants reach `reach_m`; `None`: no vertex of its own there.
    /// `heights`: the lowest and highest the data under the split may be.
    pub fn error_at(&self, east_north_m: [f64; 2], reach_m: f64, heights: [f64; 2]) -> Option<f64> {
        self.accepting(east_north_m, reach_m, heights).map(|(_, error)| error)
    }

    /// The ring that gives the vertex its error (its index, finest first;
    /// the last where it stops growing) and the error; `None` as
    /// [`Self::error_at`].
    pub fn accepting(
        &self,
        east_north_m: [f64; 2],
        reach_m: f64,
        heights: [f64; 2],
    ) -> Option<(usize, f64)> {
        let offset = |ring: &RingView| [0, 1].map(|k| east_north_m[k] - ring.anchor_m[k]);
        for (i, ring) in self.rings.iter().enumerate() {
            if let Some(error) = ring.error_at(offset(ring), reach_m, heights) {
                return Some((i, error));
            }
        }
        let last = self.rings.last()?;
        match self.ends {
            true => None,
            false => last
                .without_end()
                .error_at(offset(last), reach_m, heights)
                .map(|error| (self.rings.len() - 1, error)),
        }
    }

    /// The morph band of a vertex the rule gives an error at (see
    /// [`Self::accepting`]): the sub-level of its ring, whose morph it
    /// follows; 0 (the level's own morph) where no ring does. Two tiles
    /// whose rules hold the same rings give a vertex the same band, so
    /// their shared edges morph alike whatever their sub-levels.
    pub fn band_at(&self, east_north_m: [f64; 2], reach_m: f64, heights: [f64; 2]) -> u8 {
        match self.accepting(east_north_m, reach_m, heights) {
            Some((i, _)) => self.finest.saturating_sub(i as u8),
            None => 0,
        }
    }

    /// The largest error a vertex at most `distance_m` from the rings'
    /// anchors gets (the level above's where the rule ends), metres.
    pub fn largest_within(&self, distance_m: f64) -> f64 {
        for ring in &self.rings {
            if distance_m < ring.end_m {
                return ring.largest_within(distance_m);
            }
        }
        self.rings.last().map_or(0.0, |b| b.largest_within(distance_m))
    }

    /// The largest near-end error of the rings a vertex at most
    /// `distance_m` from the anchors falls in: what a vertex keeps along a
    /// node's own edge (`super::extract`).
    pub fn near_end_within(&self, distance_m: f64) -> f64 {
        for ring in &self.rings {
            if distance_m < ring.end_m {
                return ring.largest_within(0.0);
            }
        }
        self.rings.last().map_or(0.0, |b| b.largest_within(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rtin::{Diagonal, Triangle};

    #[test]
    fn legs_follow_the_hierarchy_and_reach_the_dependants() {
        let length =
            |p: [u32; 2], q: [u32; 2]| (p[0] as f64 - q[0] as f64).hypot(p[1] as f64 - q[1] as f64);
        for diagonal in [Diagonal::of_node(0, 0), Diagonal::of_node(1, 0)] {
            let mut stack = Triangle::roots_along(64, diagonal).to_vec();
            while let Some(t) = stack.pop() {
                if t.is_leaf() {
                    continue;
                }
                let (m, leg) = (t.midpoint(), split_leg(t.midpoint()));
                assert!((length(t.c, t.a) - leg).abs() < 1e-9, "{t:?}: {leg}");
                for child in t.children().into_iter().filter(|c| !c.is_leaf()) {
                    // The split of the child's hypotenuse (a leg of `t`) needs `m`.
                    let c = child.midpoint();
                    let reach = |p: [u32; 2]| split_leg(p) * reach_legs();
                    assert!(length(m, c) + reach(c) <= reach(m) + 1e-9, "{t:?}");
                }
                stack.extend(t.children());
            }
        }
    }

    /// A ring from `anchor` with `slack`, near end 100 m, its morph from
    /// `morph[0]` to `morph[1]`, 1 cm a metre, no reference, 0.5 m least.
    fn ring(anchor_m: [f64; 2], slack_m: f64, morph: [f64; 2]) -> RingView {
        RingView {
            anchor_m,
            slack_m,
            near_m: 100.0,
            start_m: morph[0],
            end_m: morph[1],
            per_m: 0.01,
            reference_m: 0.0,
            own_m: 0.5,
            cone: None,
        }
    }

    #[test]
    fn errors_grow_with_distance_and_stop_at_the_morph() {
        let ring =
            RingView { reference_m: 0.2, own_m: 0.75, ..ring([0.0, 0.0], 10.0, [140.0, 200.0]) };
        let (east, heights) = (|d: f64| [d, 0.0], [0.0, 100.0]);
        assert_eq!(ring.error_at(east(50.0), 1.0, heights), Some(0.8));
        assert!((ring.error_at(east(131.0), 1.0, heights).unwrap() - 1.0).abs() < 1e-12);
        assert!((ring.error_at(east(190.0), 1.0, heights).unwrap() - 1.2).abs() < 1e-12);
        assert_eq!(ring.error_at(east(211.0), 1.0, heights), None);
        let far = ring.without_end().error_at(east(1e9), 1.0, heights);
        assert_eq!(far, Some(ring.largest_m()));
    }

    #[test]
    fn a_camera_sees_its_cone_and_nothing_behind_or_below_it() {
        use glam::DVec3;
        let camera = |heading_deg: f64, pitch_deg: f64| Camera {
            position: DVec3::new(1000.0, 2000.0, 1000.0),
            heading_deg,
            pitch_deg,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [1280, 720],
        };
        let turn = 0.26;
        let north = ViewCone::of_camera(&camera(0.0, -5.0), turn).expect("a cone");
        let ground = [0.0, 50.0];
        assert!(north.meets([0.0, 5000.0], 10.0, ground), "ahead");
        assert!(!north.meets([0.0, -5000.0], 10.0, ground), "behind");
        assert!(!north.meets([5000.0, 100.0], 10.0, ground), "abeam");
        // Straight below is out of view: the lowest ray, 18 + 5 + 15
        // degrees down, meets the ground 1.3 km ahead.
        assert!(!north.meets([0.0, 200.0], 10.0, ground), "below");
        assert!(north.meets([0.0, 200.0], 900.0, ground), "a wide box reaches into view");
        assert!(north.holds(&camera(7.0, -5.0), turn) && !north.holds(&camera(8.0, -5.0), turn));
        assert!(
            ViewCone::of_camera(&Camera { fov_x_deg: 150.0, ..camera(0.0, 0.0) }, turn).is_none()
        );
        // A ring with a cone keeps nothing of its own out of view.
        let ring = RingView { cone: Some(north), ..ring([1000.0, 2000.0], 1.0, [1e6, 2e6]) };
        assert!(ring.error_at([0.0, 5000.0], 10.0, ground).is_some());
        assert!(ring.error_at([0.0, -5000.0], 10.0, ground).is_none());
    }
}
