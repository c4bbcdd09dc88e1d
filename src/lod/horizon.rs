//! Horizon culling: tiles the earth's curvature hides below the horizon are
//! neither selected, nor generated, nor drawn.
//!
//! Cesium culls against the WGS84 ellipsoid with an occludee point and a
//! horizon plane. Ridgeline draws a sphere of [`EARTH_RADIUS_M`] in the
//! display's own curvature model: a point `D` metres away horizontally, at
//! height `h`, is drawn `h - A - D² c` above the eye (`A` the camera's
//! altitude, `c = 1 / (2 R)`, the shader's `drop`). The occluder is that
//! paraboloid at the *floor*, the lowest height the drawn surface has
//! anywhere (every post's height, every morph, is at least the floor).
//!
//! **The test.** Along the sight line from the eye to the point, at
//! fraction `t`, the line is `t (h - A - D² c)` above the eye and the floor
//! `floor - A - t² D² c`. The line dips below the floor for some `t` in
//! (0, 1) exactly when `D √c > √(A − floor) + √(h − floor)`: the sum of the
//! eye's and the point's horizon distances over the floor, as on a sphere
//! (the derivation: the difference is a convex quadratic in `t`; its
//! minimum lies inside (0, 1) and below zero under that condition alone).
//!
//! **Conservative.** The distance falls and the bound grows with the
//! height, so a tile is hidden when its *nearest* horizontal point is
//! beyond the horizon of its *highest possible* point (the top of its
//! height bounds, which hold every post, morph target and mesh vertex).
//! A margin of [`MARGIN_SHARE`] and [`MARGIN_M`] covers the shader's f32.
//! The occluder must be drawn along the sight line: the selector only
//! culls by the horizon when the camera is over the data's rectangle
//! (convex, so the whole line lies over data) and the terrain says that
//! every post there has data (`Horizon::floor_m` is `None` otherwise).

use crate::camera::EARTH_RADIUS_M;

/// The horizon distance is widened by this share before a tile is culled.
pub const MARGIN_SHARE: f64 = 1e-3;
/// And by this many metres.
pub const MARGIN_M: f64 = 50.0;

/// The horizon of one view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Horizon {
    /// Camera altitude, metres.
    altitude_m: f64,
    /// The drawn surface is nowhere lower than this, metres.
    floor_m: f64,
}

impl Horizon {
    /// The horizon of an eye at `altitude_m` over terrain never drawn below
    /// `floor_m`; `None` when the eye is not above the floor (nothing is
    /// hidden) or either is not finite.
    pub fn new(altitude_m: f64, floor_m: f64) -> Option<Horizon> {
        (altitude_m.is_finite() && floor_m.is_finite() && altitude_m > floor_m)
            .then_some(Horizon { altitude_m, floor_m })
    }

    /// Horizontal distance beyond which a point of height `top_m` is hidden.
    pub fn hiding_distance(&self, top_m: f64) -> f64 {
        let root = |h: f64| h.max(0.0).sqrt();
        let exact = (2.0 * EARTH_RADIUS_M).sqrt()
            * (root(self.altitude_m - self.floor_m) + root(top_m - self.floor_m));
        exact * (1.0 + MARGIN_SHARE) + MARGIN_M
    }

    /// Whether every point whose horizontal distance is at least
    /// `nearest_m` and whose height is at most `top_m` is hidden.
    pub fn hides(&self, nearest_m: f64, top_m: f64) -> bool {
        nearest_m > self.hiding_distance(top_m)
    }

    /// Whether the sight line from the eye to the point `distance_m` away at
    /// `height_m` dips below the floor surface (brute force over the line,
    /// `steps` samples; for tests).
    pub fn line_dips(&self, distance_m: f64, height_m: f64, steps: u32) -> bool {
        let c = 1.0 / (2.0 * EARTH_RADIUS_M);
        let point = height_m - self.altitude_m - distance_m * distance_m * c;
        (1..steps).any(|k| {
            let t = k as f64 / steps as f64;
            let floor = self.floor_m - self.altitude_m - (t * distance_m).powi(2) * c;
            t * point < floor
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn ten_km_over_the_sea_sees_357_km() {
        let horizon = Horizon::new(10_000.0, 0.0).unwrap();
        let sea = horizon.hiding_distance(0.0);
        assert!((sea - 357_000.0).abs() < 1500.0, "{sea}");
        assert!(Horizon::new(0.0, 0.0).is_none());
    }

    proptest! {
        /// Never culls a point whose sight line stays above the floor, and
        /// the exact bound (without margin) is where the line starts to dip.
        #[test]
        fn culls_only_what_the_floor_hides(
            altitude in 10.0f64..20_000.0,
            height in 0.0f64..9_000.0,
            distance in 1_000.0f64..1_500_000.0,
        ) {
            let horizon = Horizon::new(altitude, 0.0).unwrap();
            if horizon.hides(distance, height) {
                prop_assert!(horizon.line_dips(distance, height, 20_000));
            }
        }
    }
}
