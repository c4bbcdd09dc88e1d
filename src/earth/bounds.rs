//! Bounds of pieces of a grid on the ellipsoid, for culling and distances
//! on the earth rather than in the chart: an oriented box holding a patch
//! of posts between two heights ([`EarthBox`]), and the horizon of the
//! ellipsoid under the lowest surface ([`EllipsoidHorizon`], Cesium's
//! scaled-space test).
//!
//! **The box.** In the east-north-up frame at the patch's centre, the
//! patch's points at both heights are sampled on a lattice fine enough
//! that between samples the surface bends by little; the box holds every
//! sample, grown by that bend (`R (1 - cos(step / 2))` for a step of
//! `step` radians on the ellipsoid, with the largest radius) on every side.
//!
//! **The horizon.** Scaled by `(1/a', 1/a', 1/b')` the occluding ellipsoid
//! (semi-axes `a + floor - margin`, `b + floor - margin`) is the unit
//! sphere, and a point `q` is hidden from the eye `v` exactly when it lies
//! beyond the horizon plane (`(v - q) . v > |v|^2 - 1`... read as Cesium
//! writes it) and inside the horizon cone. That region is convex, so a box
//! whose eight corners are all hidden is hidden whole.

use glam::{DMat3, DVec3};

use super::ellipsoid::{self, A, B};
use super::placement::GridPlacement;

/// An oriented box on the earth: ECEF centre, unit axes, half extents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarthBox {
    /// Centre, ECEF metres.
    pub centre: DVec3,
    /// Unit axes (east, north, up at the patch's centre) as columns.
    pub axes: DMat3,
    /// Half extents along the axes, metres.
    pub half: DVec3,
}

/// The largest radius of curvature on the ellipsoid, metres (the polar
/// `a^2 / b`), with the highest heights added.
const LARGEST_RADIUS_M: f64 = 6_399_594.0 + 10_000.0;

impl EarthBox {
    /// The box of posts `[u0, u1] x [v0, v1]` of `placement` between
    /// heights `lo` and `hi` metres.
    pub fn of_patch(
        placement: &GridPlacement,
        [u0, v0]: [f64; 2],
        [u1, v1]: [f64; 2],
        (lo, hi): (f64, f64),
    ) -> EarthBox {
        let (uc, vc) = ((u0 + u1) / 2.0, (v0 + v1) / 2.0);
        let (lat, lon) = placement.geodetic_of_post(uc, vc);
        let axes = ellipsoid::enu_to_ecef(lat, lon);
        let origin = ellipsoid::to_ecef(lat, lon, 0.0);
        // Samples a side: enough that neighbouring samples are at most
        // half a degree apart on the earth.
        let span = placement
            .ecef(u0, v0, 0.0)
            .distance(placement.ecef(u1, v1, 0.0))
            .max(placement.ecef(u1, v0, 0.0).distance(placement.ecef(u0, v1, 0.0)));
        let n = ((span / 55_000.0).ceil() as usize).clamp(2, 64);
        let (mut min, mut max) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut step_m: f64 = 0.0;
        for j in 0..=n {
            for i in 0..=n {
                let u = u0 + (u1 - u0) * i as f64 / n as f64;
                let v = v0 + (v1 - v0) * j as f64 / n as f64;
                let (la, lo_) = placement.geodetic_of_post(u, v);
                let base = ellipsoid::to_ecef(la, lo_, 0.0);
                let up = ellipsoid::normal(la, lo_);
                for h in [lo, hi] {
                    let local = axes.transpose() * (base + up * h - origin);
                    min = min.min(local);
                    max = max.max(local);
                }
                if i > 0 {
                    let (pla, plo) = placement.geodetic_of_post(u - (u1 - u0) / n as f64, v);
                    step_m = step_m.max(base.distance(ellipsoid::to_ecef(pla, plo, 0.0)));
                }
                if j > 0 {
                    let (pla, plo) = placement.geodetic_of_post(u, v - (v1 - v0) / n as f64);
                    step_m = step_m.max(base.distance(ellipsoid::to_ecef(pla, plo, 0.0)));
                }
            }
        }
        // Between samples (diagonally up to sqrt(2) steps) the surface
        // bends away from their hull by at most this much.
        let diagonal = std::f64::consts::SQRT_2 * step_m;
        let bend = diagonal * diagonal / (8.0 * LARGEST_RADIUS_M.min(6_335_000.0)) + 0.01;
        let (min, max) = (min - DVec3::splat(bend), max + DVec3::splat(bend));
        let centre_local = (min + max) / 2.0;
        EarthBox { centre: origin + axes * centre_local, axes, half: (max - min) / 2.0 }
    }

    /// The distance from `p` (ECEF) to the box, 0 inside.
    pub fn distance(&self, p: DVec3) -> f64 {
        let local = self.axes.transpose() * (p - self.centre);
        (local.abs() - self.half).max(DVec3::ZERO).length()
    }

    /// Whether `p` (ECEF) lies in the box (within a millimetre).
    pub fn contains(&self, p: DVec3) -> bool {
        let local = self.axes.transpose() * (p - self.centre);
        (local.abs() - self.half).max_element() <= 1e-3
    }

    /// The eight corners, ECEF.
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|k| {
            let sign = DVec3::new(
                if k & 1 == 0 { -1.0 } else { 1.0 },
                if k & 2 == 0 { -1.0 } else { 1.0 },
                if k & 4 == 0 { -1.0 } else { 1.0 },
            );
            self.centre + self.axes * (sign * self.half)
        })
    }
}

/// The horizon of the ellipsoid under the lowest surface, seen from an eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EllipsoidHorizon {
    scale: DVec3,
    eye: DVec3,
    /// `|eye|^2 - 1` in scaled space: the horizon plane's distance.
    plane: f64,
}

/// The occluder is lowered by this much below the floor: more than the gap
/// between the scaled ellipsoid and the surface of constant geodetic
/// height (`e^2 |floor| / 2`) and the sag of drawn triangles.
pub const HORIZON_MARGIN_M: f64 = 50.0;

impl EllipsoidHorizon {
    /// The horizon from `eye` (ECEF) over a surface nowhere lower than
    /// `floor_m`; `None` when the eye is not above the occluder.
    pub fn new(eye: DVec3, floor_m: f64) -> Option<EllipsoidHorizon> {
        let lowered = floor_m - HORIZON_MARGIN_M;
        let scale = DVec3::new(1.0 / (A + lowered), 1.0 / (A + lowered), 1.0 / (B + lowered));
        let v = eye * scale;
        let plane = v.length_squared() - 1.0;
        (plane > 0.0 && eye.is_finite()).then_some(EllipsoidHorizon { scale, eye: v, plane })
    }

    /// Whether ECEF point `p` is hidden behind the occluder.
    pub fn hides(&self, p: DVec3) -> bool {
        let q = p * self.scale;
        let t = q - self.eye;
        let along = -t.dot(self.eye);
        along > self.plane && along * along / t.length_squared() > self.plane
    }

    /// Whether the whole box is hidden (its eight corners are).
    pub fn hides_box(&self, b: &EarthBox) -> bool {
        b.corners().iter().all(|&c| self.hides(c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geo::{Crs, GeoRef};

    fn global() -> GridPlacement {
        let georef = GeoRef { crs: Crs::Geographic, origin: [0.0, -90.0], spacing: [0.25, 0.25] };
        GridPlacement::new(&georef, [1441, 721], georef.spacing_m([1441, 721]))
    }

    /// Every point of a patch, at any height between its bounds, is in its
    /// box: small and large patches, at the equator, 60 N and the pole.
    #[test]
    fn a_patch_lies_in_its_box() {
        let p = global();
        for (u0, v0, size) in
            [(100.0, 360.0, 4.0), (700.0, 600.0, 64.0), (0.0, 680.0, 40.0), (1000.0, 200.0, 300.0)]
        {
            let b = EarthBox::of_patch(
                &p,
                [u0, v0],
                [u0 + size, (v0 + size).min(720.0)],
                (-100.0, 4000.0),
            );
            for a in 0..=16 {
                for c in 0..=16 {
                    for h in [-100.0, 1000.0, 4000.0] {
                        let u = u0 + size * a as f64 / 16.0;
                        let v = (v0 + size * c as f64 / 16.0).min(720.0);
                        let x = p.ecef(u, v, h);
                        assert!(
                            b.contains(x),
                            "{u0} {v0} {size}: ({u}, {v}, {h}) is {} m out",
                            b.distance(x)
                        );
                    }
                }
            }
        }
    }

    /// The horizon never hides a point whose sight line stays above the
    /// floor, and from 10 km over the sea hides the sea beyond about 383 km
    /// (357 km to the geometric horizon, 25 km more over the 50 m margin).
    #[test]
    fn the_horizon_hides_only_what_the_floor_hides() {
        let p = global();
        let eye = p.ecef(400.0, 600.0, 10_000.0);
        let horizon = EllipsoidHorizon::new(eye, 0.0).unwrap();
        let mut hidden = 0;
        for k in 0..400 {
            let u = 400.0 + (k % 20) as f64 * 2.0;
            let v = 600.0 + (k / 20) as f64 * 2.0;
            let h = (k * 37 % 3000) as f64;
            let x = p.ecef(u, v, h);
            if horizon.hides(x) {
                hidden += 1;
                // Some point of the sight line is below the floor.
                let dips = (1..200).any(|s| {
                    let t = s as f64 / 200.0;
                    ellipsoid::from_ecef(eye + (x - eye) * t).2 < 0.0
                });
                assert!(dips, "hid ({u}, {v}, {h}) though it is in sight");
            }
        }
        assert!(hidden > 50, "{hidden}");
        // Along a meridian from 60 N at 10 km.
        let range = (1..100)
            .map(|k| k as f64 * 0.05)
            .find(|dv| horizon.hides(p.ecef(400.0, 600.0 + dv / 0.25 * 1.0, 0.0)));
        let km = range.unwrap() * 111.2;
        assert!((km - 383.0).abs() < 8.0, "{km} km");
    }
}
