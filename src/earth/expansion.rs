//! [`Expansion`]: where a projected grid's posts are about a node's centre,
//! as the vertex shader computes them: the latitude and longitude
//! differences from the centre as a short series in the post offset, its
//! coefficients from the exact inverse projection in f64 on the CPU.
//!
//! **Why a complex series.** The projections Ridgeline places (transverse
//! Mercator, Web Mercator) are conformal: with the isometric latitude `psi`
//! ([`isometric_latitude`]), `lambda + i psi` is a holomorphic function of
//! `x + i y` (easting, northing). Its Taylor series about the node's centre
//! takes one complex coefficient an order, where a real series in two
//! variables takes `2 (k + 1)`: to the third order, six floats. Latitude
//! follows from `psi` by a series in one variable whose coefficients depend
//! on the centre's latitude only (the shader computes them). A first-order
//! expansion (the 2 x 2 Jacobian) misses the meridians' curvature in the
//! plane, `r^2 tan(phi) / 2R` at `r` from the centre: 0.12 m at 1 km at
//! 45 degrees, a pixel at 100 m from the eye. The coefficients are the
//! Cauchy integral's over four points on a circle about the centre.
//!
//! **Error.** The series' error against the exact inverse, over every post
//! of every node of a UTM grid at every level, is measured in the tests
//! (`a_nodes_series_is_the_projection`).

use std::f64::consts::{PI, TAU};

use super::ellipsoid::A;
use super::placement::ProjectedLattice;

/// The series of one node: its centre's latitude and the complex
/// coefficients of `lambda + i psi` in `z = (east + i north) / a`, the
/// post offset from the centre in projected metres over the semi-major
/// axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expansion {
    /// The centre's latitude, radians.
    pub lat0: f64,
    /// Coefficients of `z`, `z^2`, `z^3` (real, imaginary).
    pub terms: [[f64; 2]; 3],
    /// The eccentricity squared of the isometric latitude
    /// ([`super::Projection::isometric_e2`]).
    pub e2: f64,
}

/// Points on the circle the coefficients are integrated over: four, a
/// quarter turn apart, fold order `k + 4` onto order `k` (and the negative
/// orders, zero for a holomorphic function, onto the first three).
const SAMPLES: usize = 4;
/// The circle's radius, in `z` (32 km): large enough that rounding in the
/// samples (1e-16) costs the third coefficient 1e-9 of itself, small
/// enough that the folded orders (`c_{k+4} r^4`, 6e-10 of `c_k`) vanish.
const RADIUS: f64 = 0.005;
/// `e^{i j pi / 2}`, `j` = 0..4: the samples' directions.
const TURNS: [[f64; 2]; SAMPLES] = [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]];

/// The isometric latitude of latitude `lat` (radians) on an ellipsoid of
/// eccentricity squared `e2`: `asinh(tan lat) - e atanh(e sin lat)`.
pub fn isometric_latitude(lat: f64, e2: f64) -> f64 {
    let e = e2.sqrt();
    lat.tan().asinh() - e * (e * lat.sin()).atanh()
}

fn mul([a, b]: [f64; 2], [c, d]: [f64; 2]) -> [f64; 2] {
    [a * c - b * d, a * d + b * c]
}

impl Expansion {
    /// The series of the node of `lattice` centred on level-0 post `centre`.
    pub fn new(lattice: &ProjectedLattice, centre: [f64; 2]) -> Expansion {
        let step = lattice.step;
        let e2 = lattice.projection.isometric_e2();
        let (lat0, lon0) = lattice.geodetic(centre);
        let psi0 = isometric_latitude(lat0, e2);
        let mut terms = [[0.0; 2]; 3];
        for (j, [cos, sin]) in TURNS.into_iter().enumerate() {
            let (u, v) =
                (centre[0] + RADIUS * A * cos / step[0], centre[1] + RADIUS * A * sin / step[1]);
            let (lat, lon) = lattice.geodetic([u, v]);
            let dlon = (lon - lon0 + PI).rem_euclid(TAU) - PI;
            let w = [dlon, isometric_latitude(lat, e2) - psi0];
            for (k, term) in terms.iter_mut().enumerate() {
                // e^{-i (k + 1) theta_j}
                let [c, s] = TURNS[(j * (k + 1)) % SAMPLES];
                let scale = 1.0 / (SAMPLES as f64 * RADIUS.powi(k as i32 + 1));
                let [re, im] = mul(w, [c, -s]);
                term[0] += re * scale;
                term[1] += im * scale;
            }
        }
        Expansion { lat0, terms, e2 }
    }

    /// The node's share of its member's uniforms (two vec4): the centre's
    /// latitude, then the three coefficients, real and imaginary.
    pub fn uniforms(&self) -> [f32; 8] {
        let [[a, b], [c, d], [e, f]] = self.terms;
        [self.lat0, a, b, c, d, e, f, 0.0].map(|x| x as f32)
    }

    /// Longitude and latitude differences, radians, from the centre of the
    /// point `z` (post offset in projected metres over `a`, east and
    /// north), by the series (f64: its truncation alone).
    pub fn offsets(&self, z: [f64; 2]) -> [f64; 2] {
        let [c1, c2, c3] = self.terms;
        let inner = mul(z, c3);
        let inner = mul(z, [c2[0] + inner[0], c2[1] + inner[1]]);
        let [dlon, dpsi] = mul(z, [c1[0] + inner[0], c1[1] + inner[1]]);
        let [g1, g2, g3] = latitude_series(self.lat0, self.e2);
        [dlon, dpsi * (g1 + dpsi * (g2 + dpsi * g3))]
    }
}

/// The first three Taylor coefficients of latitude in isometric latitude
/// about latitude `lat` (eccentricity squared `e2`): with
/// `f = dphi/dpsi = cos(phi) (1 - e2 sin^2 phi) / (1 - e2)`, they are
/// `f`, `f' f / 2` and `(f'' f + f'^2) f / 6` (derivatives in `phi`).
pub fn latitude_series(lat: f64, e2: f64) -> [f64; 3] {
    let (s, c) = lat.sin_cos();
    let k = 1.0 / (1.0 - e2);
    let m = 1.0 - e2 * s * s + 2.0 * e2 * c * c;
    let f = c * (1.0 - e2 * s * s) * k;
    let f1 = -s * m * k;
    let f2 = (-c * m + 6.0 * e2 * s * s * c) * k;
    [f, f1 * f / 2.0, (f2 * f + f1 * f1) * f / 6.0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::earth::{ellipsoid, GridPlacement};
    use crate::geo::{Crs, GeoRef};

    /// Level-0 posts a node spans (the pyramid's default node size).
    const NODE: i64 = 64;
    /// Levels of the grid below: 16 384 posts is 64 << 8.
    const LEVELS: u32 = 9;
    /// Ulrich's K for 1280 px over 60 degrees.
    const K: f64 = 640.0 / 0.577_350_269_189_625_8;

    /// A UTM grid (zone 37 N) of 30 m posts, 491 km on a side, from 250 km
    /// to 741 km east (its west and east edges are 2.8 degrees off the
    /// central meridian at its north edge) and 36.1 to 40.6 N.
    fn utm(epsg: u32, origin: [f64; 2]) -> GridPlacement {
        let georef =
            GeoRef { crs: Crs::Projected { epsg: Some(epsg) }, origin, spacing: [30.0; 2] };
        GridPlacement::new(&georef, [16_385, 16_385], [30.0, 30.0])
    }

    /// The largest distance (metres, on the ellipsoid at height 0) between
    /// the series' place and the exact inverse projection's over every post
    /// (at the level's spacing) of the node of `level` at node column and
    /// row `node`, the series cut after `orders` complex terms.
    fn node_error(placement: &GridPlacement, level: u32, node: [i64; 2], orders: usize) -> f64 {
        let span = NODE << level;
        let centre = node.map(|n| (n * span + span / 2) as f64);
        let lattice = placement.projected_lattice().expect("projected");
        let mut e = Expansion::new(&lattice, centre);
        e.terms[orders..].fill([0.0; 2]);
        let step = lattice.step;
        let (lat0, lon0) = placement.geodetic_of_post(centre[0], centre[1]);
        let mut worst: f64 = 0.0;
        for i in 0..=NODE {
            for j in 0..=NODE {
                let post = [node[0] * span + (i << level), node[1] * span + (j << level)];
                let (lat, lon) = placement.geodetic_of_post(post[0] as f64, post[1] as f64);
                let z = [0, 1].map(|k| (post[k] as f64 - centre[k]) * step[k] / A);
                let [dlon, dlat] = e.offsets(z);
                let series = ellipsoid::to_ecef(lat0 + dlat, lon0 + dlon, 0.0);
                worst = worst.max(series.distance(ellipsoid::to_ecef(lat, lon, 0.0)));
            }
        }
        worst
    }

    /// The series against the exact inverse projection over every post of
    /// nine nodes a level (the grid's corners, edges' middles and centre),
    /// at every level of a UTM grid, in metres and in pixels at the
    /// nearest distance a node of that level is drawn at (its level's ring
    /// by Kühnert's rule alone, `lod::rings`: three tiles of 32 cells, the
    /// nearest any tau and data allow; at level 0, 100 m): under 0.025 px
    /// at every level.
    #[test]
    fn a_nodes_series_is_the_projection() {
        for placement in
            [utm(32637, [250_000.0, 4_000_000.0]), utm(32737, [250_000.0, 5_600_000.0])]
        {
            for level in 0..LEVELS {
                let last = (16_384 / (NODE << level) - 1).max(0);
                let near = if level == 0 { 100.0 } else { 3.0 * 32.0 * 30.0 * (1 << level) as f64 };
                // The first and second orders for comparison (printed).
                let [first, second, worst_m] = [1, 2, 3].map(|orders| {
                    let mut worst: f64 = 0.0;
                    for a in [0, last / 2, last] {
                        for b in [0, last / 2, last] {
                            worst = worst.max(node_error(&placement, level, [a, b], orders));
                        }
                    }
                    worst
                });
                let px = worst_m / near * K;
                eprintln!(
                    "level {level}: {worst_m:.3e} m, {px:.3e} px at {near:.0} m \
                     (first order {first:.3e} m, {:.3e} px; second {second:.3e} m, {:.3e} px)",
                    first / near * K,
                    second / near * K
                );
                assert!(px < 0.025, "level {level}: {worst_m} m is {px} px at {near} m");
            }
        }
    }

    /// Web Mercator's series is exact: longitude and the sphere's
    /// isometric latitude are linear in its metres.
    #[test]
    fn web_mercators_series_is_linear() {
        let georef = GeoRef {
            crs: Crs::Projected { epsg: Some(3857) },
            origin: [250_000.0, 6_000_000.0],
            spacing: [100.0; 2],
        };
        let placement = GridPlacement::new(&georef, [4097, 4097], [100.0; 2]);
        let e =
            Expansion::new(&placement.projected_lattice().expect("projected"), [2048.0, 2048.0]);
        assert_eq!(e.e2, 0.0);
        assert!((e.terms[0][0] - 1.0).abs() < 1e-9 && e.terms[0][1].abs() < 1e-9, "{e:?}");
        for t in &e.terms[1..] {
            assert!(t[0].abs() < 1e-6 && t[1].abs() < 1e-6, "{e:?}");
        }
    }

    /// The latitude series against `isometric_latitude`'s inverse (by
    /// bisection) on WGS 84 and the sphere.
    #[test]
    fn latitude_follows_isometric_latitude() {
        for e2 in [ellipsoid::E2, 0.0] {
            for lat in [-70.0f64, -20.0, 0.0, 38.0, 60.0, 84.0] {
                let lat = lat.to_radians();
                let [g1, g2, g3] = latitude_series(lat, e2);
                let psi0 = isometric_latitude(lat, e2);
                for dpsi in [-0.01, 0.003, 0.01] {
                    let (mut lo, mut hi) = (-1.57, 1.57);
                    for _ in 0..100 {
                        let mid = 0.5 * (lo + hi);
                        if isometric_latitude(mid, e2) < psi0 + dpsi {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    let series = lat + dpsi * (g1 + dpsi * (g2 + dpsi * g3));
                    // The fourth order's term: below 1e-8 of 0.01^4.
                    assert!((series - lo).abs() < 2e-9, "{lat} {dpsi}: {series} vs {lo}");
                }
            }
        }
    }
}
