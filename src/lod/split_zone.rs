//! Wu et al.'s split zone (section 4.3) and valid life (section 5), as the
//! paper states them, with the points it leaves open worked out. Ridgeline
//! selects with Ulrich's distance test, whose split zone is exact and
//! cheaper ([`super::life`]); this module keeps Wu's geometry checkable.
//!
//! - **Radius, re-derived** (the formula is lost from the text). A vertical
//!   error segment DE of length δ subtends the angle θ from every point of
//!   the two circles through D and E whose inscribed angle over the chord DE
//!   is θ: chord = 2 r sin θ, so `r = δ / (2 sin θ)`, and for the small θ =
//!   (fovy / h) τ of a pixel bound `r ≈ δ h / (2 τ fovy)`. The circles'
//!   centres lie `r cos θ` beside the segment's midpoint, so the zone
//!   (those circles swept around the vertical) reaches less than `2 r`
//!   horizontally and `r` vertically: Wu's box, 4r × 4r × 2r.
//! - **Enlarged by the node.** A node's error δ may sit anywhere in it, so
//!   a box centred on the node's centre misses eyes near an error at its
//!   corner once the node's half-width is not small against `r`; the box
//!   must grow by the node's half-width (and half its height range).
//! - **Life.** With the vertical speed at most half the horizontal `v_h`,
//!   `life = (max(d_h − half_h, 2 (d_v − half_v), 0)) / v_h` frames, which
//!   is Wu's `(max(d_h, 2 d_v) − 2r) / v_h` for a point node.

use glam::DVec3;

/// Wu's angular tolerance θ of a `tau_px` bound: `fovy / h · τ`, radians.
pub fn angular_tolerance(fovy_rad: f64, height_px: f64, tau_px: f64) -> f64 {
    fovy_rad / height_px * tau_px
}

/// Radius of the circles from which a segment of `delta_m` subtends `theta` radians.
pub fn split_zone_radius(delta_m: f64, theta: f64) -> f64 {
    delta_m / (2.0 * theta.sin())
}

/// An axis-aligned split zone: the eye inside it may see more than θ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitZone {
    /// Centre of the node, metres.
    pub centre: DVec3,
    /// Half-extents east, north and up, metres.
    pub half: DVec3,
}

impl SplitZone {
    /// Wu's box as printed: `4r × 4r × 2r` around the node's centre.
    pub fn wu(centre: DVec3, r: f64) -> Self {
        SplitZone { centre, half: DVec3::new(2.0 * r, 2.0 * r, r) }
    }

    /// Wu's box grown by the node's half-width and half its height range.
    pub fn enlarged(centre: DVec3, r: f64, half_width_m: f64, half_height_m: f64) -> Self {
        let grow = DVec3::new(half_width_m, half_width_m, half_height_m);
        SplitZone { centre, half: Self::wu(centre, r).half + grow }
    }

    /// Whether `eye` is inside the zone.
    pub fn contains(&self, eye: DVec3) -> bool {
        let d = (eye - self.centre).abs();
        d.x <= self.half.x && d.y <= self.half.y && d.z <= self.half.z
    }

    /// Frames before `eye` can enter the zone at `v_h` metres a frame
    /// horizontally and half that vertically (0 inside).
    pub fn life(&self, eye: DVec3, v_h: f64) -> f64 {
        let d = (eye - self.centre).abs();
        let d_h = d.x.max(d.y) - self.half.x.min(self.half.y);
        let d_v = d.z - self.half.z;
        d_h.max(2.0 * d_v).max(0.0) / v_h
    }
}

/// The angle segment `d`–`e` subtends from `eye`, radians.
pub fn subtended(eye: DVec3, d: DVec3, e: DVec3) -> f64 {
    (d - eye).angle_between(e - eye)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every eye from which an error segment anywhere in the node
        /// subtends more than θ is inside the enlarged box.
        #[test]
        fn the_enlarged_box_holds_the_exact_zone(
            delta in 1.0f64..200.0,
            tau in 0.5f64..8.0,
            half_width in 0.0f64..50_000.0,
            at in (-1.0f64..1.0, -1.0f64..1.0, 0.0f64..1.0),
            eye in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        ) {
            let theta = angular_tolerance(0.6, 720.0, tau);
            let r = split_zone_radius(delta, theta);
            let half_height = 500.0;
            let zone = SplitZone::enlarged(DVec3::ZERO, r, half_width, half_height);
            // The segment lies inside the node's height range.
            let z = -half_height + at.2 * (2.0 * half_height - delta);
            let foot = DVec3::new(at.0 * half_width, at.1 * half_width, z);
            let top = foot + DVec3::new(0.0, 0.0, delta);
            let reach = zone.half * 1.5;
            let eye = DVec3::new(eye.0 * reach.x, eye.1 * reach.y, eye.2 * reach.z);
            if subtended(eye, foot, top) > theta {
                prop_assert!(zone.contains(eye), "eye {eye} sees {} > {theta}", subtended(eye, foot, top));
                prop_assert_eq!(zone.life(eye, 1.0), 0.0);
            }
        }
    }

    #[test]
    fn the_box_as_printed_misses_errors_at_a_large_nodes_corner() {
        let theta = angular_tolerance(0.6, 720.0, 1.0);
        let r = split_zone_radius(10.0, theta);
        let half_width = 4.0 * r;
        // Error at the node's north-east corner; eye just beside it, outside Wu's box.
        let foot = DVec3::new(half_width, half_width, 0.0);
        let eye = foot + DVec3::new(r, 0.0, 5.0);
        assert!(subtended(eye, foot, foot + DVec3::new(0.0, 0.0, 10.0)) > theta);
        assert!(!SplitZone::wu(DVec3::ZERO, r).contains(eye));
        assert!(SplitZone::enlarged(DVec3::ZERO, r, half_width, 10.0).contains(eye));
    }

    #[test]
    fn life_is_wus_formula_for_a_point_node() {
        let zone = SplitZone::wu(DVec3::ZERO, 100.0);
        let eye = DVec3::new(900.0, -300.0, 150.0);
        // max(d_h, 2 d_v) - 2r = max(900, 300) - 200.
        assert_eq!(zone.life(eye, 10.0), 70.0);
        let high = DVec3::new(100.0, 0.0, 600.0);
        assert_eq!(zone.life(high, 10.0), (1200.0 - 200.0) / 10.0);
    }
}
