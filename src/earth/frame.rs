//! [`EarthFrame`]: one frame's placement of a geographic grid's tiles on the
//! ellipsoid, as the vertex shader computes it. Vertices stay integer post
//! numbers and heights; every large number (the eye's and each node
//! centre's ECEF) stays here in f64, and the GPU gets per node only small
//! ones in f32: the node centre's camera-relative position and the
//! rotation from its east-north-up frame to the camera's.
//!
//! **The camera frame.** Camera-relative points are metres along the
//! camera's own east, north and up (the ENU frame at the eye's geodetic
//! place): the display's view matrix, which turns heading, pitch and roll
//! relative to that frame into the eye's axes, is unchanged, and the camera
//! is exactly where [`crate::accuracy`]'s true camera is.
//!
//! **A vertex** at post `(u, v)` and height `h` lies at latitude
//! `phi0 + dphi`, longitude `lam0 + dlam` about its node's centre
//! `(phi0, lam0)` (the post differences times the grid's spacing in
//! radians: exact in f32 for integer posts). Its offset from the centre's
//! surface point, in the centre's ENU frame, is written with only small
//! terms (`sin d`, `1 - cos d` by their series below half a radian, the
//! change of the prime vertical radius in closed form), so f32 rounding
//! costs about 1e-7 of the distance to the node centre, never of the earth's
//! radius ([`NodePlace::vertex`], `shaders/gles/terrain.vert`): 0.8 mm
//! across a 7.7 km node, whatever the latitude. Tiles of one node share the
//! node's centre, so the posts they share get the same bits from both.
//!
//! **A projected grid** (a known projection: UTM, Web Mercator) is placed
//! the same way but for its latitude and longitude differences, which come
//! from its node's [`Expansion`](super::Expansion) (a third-order series in the post offset,
//! its coefficients from the exact inverse projection); grids of unknown
//! projection stay in the chart.

use glam::{DMat3, DQuat, DVec3, Vec3};

use super::cache::{NodeSeries, PatchSamples, PlaceCache};
use super::ellipsoid::{self, A, E2};
use super::placement::{GridPlacement, ProjectedLattice};

/// Where the camera and the grid are for one frame (f64, CPU only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarthFrame {
    /// How posts become latitude and longitude.
    lattice: Lattice,
    /// The level-0 post the shader's post numbers count from.
    anchor: [i64; 2],
    /// The eye, ECEF metres.
    eye: DVec3,
    /// ECEF axes to the camera's east, north and up.
    to_camera: DMat3,
}

/// How a frame's posts become latitude and longitude.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Lattice {
    /// A geographic grid: longitude and latitude of post (0, 0) and
    /// between neighbouring posts, east and north, radians.
    Geographic { origin: [f64; 2], step: [f64; 2] },
    /// A projected grid of a known projection: by its inverse (exact), and
    /// per node by its [`Expansion`](super::Expansion) (the shader).
    Projected(ProjectedLattice),
}

/// One node's placement as the vertex shader takes it (two vec4 and a
/// float of its member's uniforms; two vec4 more for a projected grid).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodePlace {
    /// The node's centre post, numbered from the frame's anchor.
    pub centre: [f32; 2],
    /// The centre's surface point relative to the eye, camera axes, metres.
    pub offset: [f32; 3],
    /// The rotation from the centre's ENU axes to the camera's, as a unit
    /// quaternion (x, y, z, w).
    pub rotation: [f32; 4],
    /// A projected grid's node: its [`Expansion::uniforms`](super::Expansion::uniforms) (zero for a
    /// geographic grid).
    pub expansion: [f32; 8],
}

impl EarthFrame {
    /// The frame of an eye at chart point and altitude `eye_chart` over the
    /// grid `placement` places, post numbers counted from `anchor`. `None`
    /// for a grid placed by assumption (a local grid, or a projected one of
    /// an unknown projection: drawn in the chart).
    pub fn new(placement: &GridPlacement, eye_chart: DVec3, anchor: [i64; 2]) -> Option<Self> {
        let lattice = match (placement.geographic_lattice(), placement.projected_lattice()) {
            (Some((origin, step)), _) => Lattice::Geographic { origin, step },
            (None, Some(projected)) => Lattice::Projected(projected),
            (None, None) => return None,
        };
        let (lat, lon) = placement.geodetic_of_chart([eye_chart.x, eye_chart.y]);
        let eye = ellipsoid::to_ecef(lat, lon, eye_chart.z);
        let to_camera = ellipsoid::enu_to_ecef(lat, lon).transpose();
        Some(EarthFrame { lattice, anchor, eye, to_camera })
    }

    /// The eye, ECEF metres.
    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    /// `u_earth[2]`: for a geographic grid radians between posts east and
    /// north, the latitude of the anchor's row, 1 (the ellipsoid on); for
    /// a projected one projected metres between posts over `a`, 0, 2; then
    /// the semi-major axis, the first eccentricity squared and the
    /// isometric latitude's ([`super::Projection::isometric_e2`], projected
    /// grids).
    pub fn uniforms(&self) -> [f32; 8] {
        let (a, e2) = (A as f32, E2 as f32);
        match self.lattice {
            Lattice::Geographic { origin, step } => {
                let anchor_lat = origin[1] + self.anchor[1] as f64 * step[1];
                let [east, north] = step.map(|s| s as f32);
                [east, north, anchor_lat as f32, 1.0, a, e2, 0.0, 0.0]
            }
            Lattice::Projected(projected) => {
                let [east, north] = projected.step.map(|s| (s / A) as f32);
                let isometric_e2 = projected.projection.isometric_e2() as f32;
                [east, north, 0.0, 2.0, a, e2, isometric_e2, 0.0]
            }
        }
    }

    /// Latitude and longitude, radians, of level-0 post `post` (for a
    /// geographic grid not clamped: a node centre past a pole is placed by
    /// the same formula the shader uses).
    fn geodetic(&self, post: [f64; 2]) -> (f64, f64) {
        match &self.lattice {
            Lattice::Geographic { origin, step } => {
                (origin[1] + post[1] * step[1], origin[0] + post[0] * step[0])
            }
            Lattice::Projected(projected) => projected.geodetic(post),
        }
    }

    /// The placement of a node whose centre is level-0 post `centre`.
    pub fn place(&self, centre: [i64; 2]) -> NodePlace {
        match &self.lattice {
            Lattice::Geographic { .. } => {
                let (lat, lon) = self.geodetic(centre.map(|c| c as f64));
                let (surface, enu) =
                    (ellipsoid::to_ecef(lat, lon, 0.0), ellipsoid::enu_to_ecef(lat, lon));
                self.place_at(centre, surface, enu, [0.0; 8])
            }
            Lattice::Projected(projected) => {
                let node = NodeSeries::new(projected, centre);
                self.place_at(centre, node.surface, node.enu, node.uniforms)
            }
        }
    }

    /// [`Self::place`] with a projected grid's node centre and series from
    /// `cache` (made once a node, not once a tile and frame).
    pub fn place_with(&self, centre: [i64; 2], cache: &mut PlaceCache) -> NodePlace {
        match &self.lattice {
            Lattice::Geographic { .. } => self.place(centre),
            Lattice::Projected(_) => {
                debug_assert!(
                    cache.serves(self.projected_lattice()),
                    "the cache was not started for this frame's grid"
                );
                match cache.node(centre) {
                    Some(node) => self.place_at(centre, node.surface, node.enu, node.uniforms),
                    None => self.place(centre),
                }
            }
        }
    }

    /// The placement of the node centred on `centre`, whose surface point
    /// is `surface` (ECEF) with east-north-up axes `enu`, and whose series
    /// uniforms (a projected grid's) are `expansion`.
    fn place_at(
        &self,
        centre: [i64; 2],
        surface: DVec3,
        enu: DMat3,
        expansion: [f32; 8],
    ) -> NodePlace {
        let offset = self.to_camera * (surface - self.eye);
        let rotation = DQuat::from_mat3(&(self.to_camera * enu));
        NodePlace {
            centre: [0, 1].map(|k| (centre[k] - self.anchor[k]) as f32),
            offset: offset.as_vec3().to_array(),
            rotation: rotation.normalize().as_quat().to_array(),
            expansion,
        }
    }

    /// Camera-relative point (camera axes) of level-0 post `post` (any
    /// fraction) at `height` metres: exact, f64.
    pub fn point(&self, post: [f64; 2], height: f64) -> DVec3 {
        let (lat, lon) = self.geodetic(post);
        self.to_camera * (ellipsoid::to_ecef(lat, lon, height) - self.eye)
    }

    /// The box, in camera axes (lowest and highest corner), holding level-0
    /// posts `[p0, p1]` at every height in `heights`: the patch sampled on
    /// a lattice (neighbouring samples at most about 55 km apart) at both
    /// heights, grown on every side by twice the most a surface arc bows
    /// away from its chord between samples (a point inside a lattice cell
    /// is on an arc between two points on arcs between samples). What the
    /// selector culls, rings and orders tiles by on the ellipsoid.
    pub fn camera_box(&self, p0: [f64; 2], p1: [f64; 2], heights: (f64, f64)) -> (DVec3, DVec3) {
        match &self.lattice {
            // Latitude and longitude depend on both post numbers.
            Lattice::Projected(projected) => {
                self.samples_box(&PatchSamples::new(projected, p0, p1), heights)
            }
            Lattice::Geographic { .. } => {
                let span = self.point(p0, 0.0).distance(self.point(p1, 0.0));
                let n = ((span / 55_000.0).ceil() as usize).clamp(2, 32);
                let (min, max) = self.lattice_box(p0, p1, n, heights);
                grown((min, max), span / n as f64, heights.1)
            }
        }
    }

    /// [`Self::camera_box`] with a projected grid's samples from `cache`
    /// (made once a tile, not once a frame).
    pub fn camera_box_with(
        &self,
        p0: [f64; 2],
        p1: [f64; 2],
        heights: (f64, f64),
        cache: &mut PlaceCache,
    ) -> (DVec3, DVec3) {
        debug_assert!(
            cache.serves(self.projected_lattice()),
            "the cache was not started for this frame's grid"
        );
        match cache.patch(p0, p1) {
            Some(samples) if matches!(self.lattice, Lattice::Projected(_)) => {
                self.samples_box(samples, heights)
            }
            _ => self.camera_box(p0, p1, heights),
        }
    }

    /// A projected grid's lattice, `None` for a geographic grid.
    pub fn projected_lattice(&self) -> Option<ProjectedLattice> {
        match self.lattice {
            Lattice::Projected(projected) => Some(projected),
            Lattice::Geographic { .. } => None,
        }
    }

    /// The camera's axes: ECEF to east, north and up at the eye.
    pub fn axes(&self) -> DMat3 {
        self.to_camera
    }

    /// The box of a geographic grid's patch sampled on an `n` x `n`
    /// lattice at both heights (sines and cosines once a column and a row).
    fn lattice_box(
        &self,
        p0: [f64; 2],
        p1: [f64; 2],
        n: usize,
        (lo, hi): (f64, f64),
    ) -> (DVec3, DVec3) {
        let (mut min, mut max) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        // On the stack: the selector calls this for every tile it visits,
        // every frame.
        let mut columns = [[0.0; 2]; 33];
        let mut rows = [[0.0; 2]; 33];
        for k in 0..=n {
            let f = k as f64 / n as f64;
            let (lat, lon) =
                self.geodetic([p0[0] + (p1[0] - p0[0]) * f, p0[1] + (p1[1] - p0[1]) * f]);
            let ((sin_lat, cos_lat), (sin_lon, cos_lon)) = (lat.sin_cos(), lon.sin_cos());
            rows[k] = [sin_lat, cos_lat];
            columns[k] = [sin_lon, cos_lon];
        }
        for &row in &rows[..=n] {
            for &column in &columns[..=n] {
                for h in [lo, hi] {
                    let p = self.camera_of(ellipsoid::to_ecef_sincos(row, column, h));
                    min = min.min(p);
                    max = max.max(p);
                }
            }
        }
        (min, max)
    }

    /// The box of a projected grid's patch from its samples at both
    /// heights (its latitude and longitude depend on both post numbers).
    fn samples_box(&self, samples: &PatchSamples, (lo, hi): (f64, f64)) -> (DVec3, DVec3) {
        let (mut min, mut max) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &[surface, up] in samples.points.iter() {
            for h in [lo, hi] {
                let p = self.camera_of(surface + up * h);
                min = min.min(p);
                max = max.max(p);
            }
        }
        grown((min, max), samples.span / samples.n as f64, hi)
    }

    /// The ECEF point of camera-relative point `d` (camera axes).
    pub fn ecef_of(&self, d: DVec3) -> DVec3 {
        self.eye + self.to_camera.transpose() * d
    }

    /// Camera-relative point (camera axes) of ECEF point `p`.
    pub fn camera_of(&self, p: DVec3) -> DVec3 {
        self.to_camera * (p - self.eye)
    }
}

/// The meridian's radius of curvature at the equator, `a (1 - e^2)`,
/// metres: the smallest on the ellipsoid.
const SMALLEST_RADIUS_M: f64 = 6_335_439.0;
/// The polar radius of curvature, `a^2 / b`, metres: the largest.
const LARGEST_RADIUS_M: f64 = 6_399_594.0;

/// The box `[min, max]` of samples `step_m` apart grown on every side by
/// twice the most a surface arc bows away from its chord between samples
/// (a point inside a lattice cell is on an arc between two points on arcs
/// between samples), at heights up to `hi`. The smallest radius of
/// curvature (the meridian's at the equator) bends most; the highest
/// surface is farthest out.
fn grown((min, max): (DVec3, DVec3), step_m: f64, hi: f64) -> (DVec3, DVec3) {
    let step = step_m / SMALLEST_RADIUS_M;
    let bow = 2.0 * (LARGEST_RADIUS_M + hi.max(0.0)) * (1.0 - (step / 2.0).cos());
    (min - DVec3::splat(bow), max + DVec3::splat(bow))
}

impl NodePlace {
    /// The member uniforms' two vec4 it fills: the offset and the centre's
    /// column; the rotation.
    pub fn vectors(&self) -> [f32; 8] {
        let [x, y, z] = self.offset;
        let [qx, qy, qz, qw] = self.rotation;
        [x, y, z, self.centre[0], qx, qy, qz, qw]
    }

    /// Camera-relative point, f32, of the vertex at post number `post`
    /// (from the anchor, in level-0 posts) at `height` metres, computed as
    /// `terrain.vert` computes it with `earth` (`u_earth`): the CPU's mirror of
    /// the drawn geometry.
    pub fn vertex(&self, earth: &[f32; 8], post: [f32; 2], height: f32) -> Vec3 {
        let (surface, up) = self.local(earth, post);
        self.to_camera(surface + up * height)
    }

    /// The vertex's surface point and geodetic up, in the centre's ENU
    /// frame (`terrain.vert`'s `earth_local`).
    pub fn local(&self, earth: &[f32; 8], post: [f32; 2]) -> (Vec3, Vec3) {
        let (a, e2) = (earth[4], earth[5]);
        let (phi0, [dlam, dphi]) = if earth[3] > 1.5 {
            (self.expansion[0], self.projected_offsets(earth, post))
        } else {
            let d = [0, 1].map(|k| (post[k] - self.centre[k]) * earth[k]);
            (earth[2] + self.centre[1] * earth[1], d)
        };
        let (s0, c0) = (phi0.sin(), phi0.cos());
        let [sl, hl] = sin_hav(dlam);
        let [sp, hp] = sin_hav(dphi);
        // sin and cos of the latitude, as changes from the centre's.
        let ds = c0 * sp - s0 * hp;
        let dc = -c0 * hp - s0 * sp;
        let (s, c) = (s0 + ds, c0 + dc);
        let k = ds * (2.0 * s0 + ds);
        let w0 = (1.0 - e2 * s0 * s0).sqrt();
        let w = (1.0 - e2 * s0 * s0 - e2 * k).sqrt();
        let n0 = a / w0;
        let dn = a * e2 * k / (w * w0 * (w + w0));
        // Surface point minus the centre's, in the centre meridian's
        // axes (x out at the equator, y east, z north).
        let dx = dn * c * (1.0 - hl) + n0 * dc * (1.0 - hl) - n0 * c0 * hl;
        let dy = (n0 + dn) * c * sl;
        let dz = dn * (1.0 - e2) * s + n0 * (1.0 - e2) * ds;
        let up = [c * (1.0 - hl), c * sl, s];
        let enu = |[x, y, z]: [f32; 3]| Vec3::new(y, -s0 * x + c0 * z, c0 * x + s0 * z);
        (enu([dx, dy, dz]), enu(up))
    }

    /// A projected grid's vertex: its longitude and latitude differences
    /// from the node's centre by the node's series (`terrain.vert`'s
    /// `projected_offsets`; [`Expansion::offsets`](super::Expansion::offsets) in f32).
    fn projected_offsets(&self, earth: &[f32; 8], post: [f32; 2]) -> [f32; 2] {
        let e = &self.expansion;
        let z = [0, 1].map(|k| (post[k] - self.centre[k]) * earth[k]);
        let mul = |[a, b]: [f32; 2], [c, d]: [f32; 2]| [a * c - b * d, a * d + b * c];
        let inner = mul(z, [e[5], e[6]]);
        let inner = mul(z, [e[3] + inner[0], e[4] + inner[1]]);
        let [dlam, dpsi] = mul(z, [e[1] + inner[0], e[2] + inner[1]]);
        // Latitude from isometric latitude (expansion::latitude_series).
        let (s0, c0, e2) = (e[0].sin(), e[0].cos(), earth[6]);
        let k = 1.0 / (1.0 - e2);
        let m = 1.0 - e2 * s0 * s0 + 2.0 * e2 * c0 * c0;
        let f = c0 * (1.0 - e2 * s0 * s0) * k;
        let f1 = -s0 * m * k;
        let f2 = (-c0 * m + 6.0 * e2 * s0 * s0 * c0) * k;
        let [g1, g2, g3] = [f, f1 * f / 2.0, (f2 * f + f1 * f1) * f / 6.0];
        [dlam, dpsi * (g1 + dpsi * (g2 + dpsi * g3))]
    }

    /// A point of the centre's ENU frame, camera-relative.
    pub fn to_camera(&self, local: Vec3) -> Vec3 {
        let [qx, qy, qz, qw] = self.rotation;
        let q = Vec3::new(qx, qy, qz);
        let t = q.cross(local) + local * qw;
        local + 2.0 * q.cross(t) + Vec3::from(self.offset)
    }
}

/// `sin d` and `1 - cos d`, f32, as `terrain.vert` computes them: by their
/// series (to the tenth power; the rest below 2e-11) for `|d| <= 0.5`, so
/// a small angle keeps all its digits whatever the GPU's `sin` does with it.
pub fn sin_hav(d: f32) -> [f32; 2] {
    if d.abs() > 0.5 {
        let half = (0.5 * d).sin();
        return [d.sin(), 2.0 * half * half];
    }
    let d2 = d * d;
    let s = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0))));
    let h =
        d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 * (1.0 - d2 / 90.0))));
    [s, h]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geo::{Crs, GeoRef};

    fn grid(origin: [f64; 2], spacing_deg: f64, posts: [u32; 2]) -> GridPlacement {
        let georef = GeoRef { crs: Crs::Geographic, origin, spacing: [spacing_deg; 2] };
        GridPlacement::new(&georef, posts, georef.spacing_m(posts))
    }

    fn utm() -> GridPlacement {
        let georef = GeoRef {
            crs: Crs::Projected { epsg: Some(32637) },
            origin: [250_000.0, 4_000_000.0],
            spacing: [30.0; 2],
        };
        GridPlacement::new(&georef, [16_385, 16_385], [30.0; 2])
    }

    /// The shader's f32 mirror against the exact f64 point, for nodes near
    /// and far from the eye, small and huge, from the equator to 89.9 N and
    /// across the antimeridian, and a UTM grid's: within 1e-6 of the
    /// distance to the node's centre plus a millimetre.
    #[test]
    fn the_shaders_vertex_is_the_earths_point() {
        // 3-second data at 39 N; 5-minute global data.
        let cases = [
            (grid([-106.0, 39.0], 1.0 / 1200.0, [1201, 1201]), [600.5, 400.25], 256, 0),
            (grid([-106.0, 39.0], 1.0 / 1200.0, [1201, 1201]), [10.0, 1000.0], 256, 2),
            (grid([0.0, -90.0], 1.0 / 12.0, [4321, 2161]), [1800.0, 1800.0], 256, 0),
            (grid([0.0, -90.0], 1.0 / 12.0, [4321, 2161]), [2160.3, 1860.0], 256, 3),
            (grid([0.0, -90.0], 1.0 / 12.0, [4321, 2161]), [5.0, 2158.8], 256, 1),
            (grid([0.0, -90.0], 1.0 / 12.0, [4321, 2161]), [4319.0, 1300.0], 256, 5),
            // 30 m UTM (zone 37 N) by its nodes' series.
            (utm(), [10.0, 16_000.0], 256, 0),
            (utm(), [8000.5, 3000.25], 256, 3),
        ];
        for (placement, eye_post, node, level) in cases {
            let chart = placement.chart_of_post(eye_post);
            let eye = DVec3::new(chart[0], chart[1], 3000.0);
            let anchor = eye_post.map(|p| p.floor() as i64);
            let frame = EarthFrame::new(&placement, eye, anchor).expect("placed");
            let earth = frame.uniforms();
            let span = (node as i64) << level;
            for (i, j) in [(0, 0), (1, 0), (-1, 2), (3, -2)] {
                let node_sw =
                    [anchor[0] / span * span + i * span, anchor[1] / span * span + j * span];
                let centre = node_sw.map(|c| c + span / 2);
                let place = frame.place(centre);
                for (a, b, h) in
                    [(0, 0, 0.0), (span, span, 8000.0), (span / 3, 2 * span / 3, -400.0)]
                {
                    let post = [node_sw[0] + a, node_sw[1] + b];
                    let exact = frame.point(post.map(|p| p as f64), h);
                    let number = [0, 1].map(|k| (post[k] - anchor[k]) as f32);
                    let drawn = place.vertex(&earth, number, h as f32).as_dvec3();
                    let reach = frame.point(centre.map(|c| c as f64), 0.0).length()
                        + exact.distance(frame.point(centre.map(|c| c as f64), 0.0));
                    let error = drawn.distance(exact);
                    assert!(
                        error <= 1e-6 * reach + 1e-3,
                        "post {post:?} of node {centre:?} at level {level}: {error} m off at {reach} m"
                    );
                }
            }
        }
    }

    /// Every point of a patch, at any height between its bounds, lies in
    /// its camera box: a fine patch near the eye and a coarse one spanning
    /// 20 degrees, at 60 N; a UTM grid's near the eye and 240 km across.
    #[test]
    fn a_patch_lies_in_its_camera_box() {
        let geographic = grid([0.0, -90.0], 1.0 / 12.0, [4321, 2161]);
        let cases = [
            (geographic, [120.0, 1800.0], [([100.0, 1790.0], [132.0, 1822.0])]),
            (geographic, [120.0, 1800.0], [([0.0, 1700.0], [240.0, 1940.0])]),
            (utm(), [8000.0, 8000.0], [([7980.0, 7990.0], [8012.0, 8022.0])]),
            (utm(), [8000.0, 8000.0], [([4000.0, 4000.0], [12_000.0, 12_000.0])]),
        ];
        for (placement, eye, [(p0, p1)]) in cases {
            let chart = placement.chart_of_post(eye);
            let frame = EarthFrame::new(
                &placement,
                DVec3::new(chart[0], chart[1], 5000.0),
                eye.map(|p| p as i64),
            )
            .expect("placed");
            let (min, max) = frame.camera_box(p0, p1, (-100.0, 4000.0));
            for i in 0..=20 {
                for j in 0..=20 {
                    let (fu, fv) = (i as f64 / 20.0, j as f64 / 20.0);
                    let post = [p0[0] + (p1[0] - p0[0]) * fu, p0[1] + (p1[1] - p0[1]) * fv];
                    for h in [-100.0, 1234.0, 4000.0] {
                        let p = frame.point(post, h);
                        assert!(p.cmpge(min).all() && p.cmple(max).all(), "{post:?} at {h} m");
                    }
                }
            }
        }
    }

    /// The small-angle series agree with the library's functions.
    #[test]
    fn small_angles_keep_their_digits() {
        for d in [1e-7f64, 1e-4, 0.01, 0.3, 0.49, 0.51, 2.0] {
            let [s, h] = sin_hav(d as f32);
            assert!((s as f64 - d.sin()).abs() <= 1e-7 * d.sin().abs(), "sin {d}");
            let hav = 2.0 * (d / 2.0).sin().powi(2);
            assert!((h as f64 - hav).abs() <= 2e-7 * hav, "1 - cos {d}: {h} against {hav}");
        }
    }

    /// Cached places and boxes are the uncached ones, bit for bit, frame
    /// after frame as the eye moves; entries a frame and the next do not
    /// use are dropped, and a geographic frame caches nothing.
    #[test]
    fn cached_places_and_boxes_are_the_frames_own() {
        let placement = utm();
        let mut cache = PlaceCache::default();
        let at = |placement: &GridPlacement, eye_post: [f64; 2]| {
            let chart = placement.chart_of_post(eye_post);
            let eye = DVec3::new(chart[0], chart[1], 3000.0);
            EarthFrame::new(placement, eye, eye_post.map(|p| p as i64)).expect("placed")
        };
        let (p0, p1) = ([7936.0, 8064.0], [8000.0, 8128.0]);
        for k in 0..3 {
            let frame = at(&placement, [8000.0 + 40.0 * k as f64, 8000.0]);
            cache.next_frame(frame.projected_lattice());
            let centre = [8032, 8096];
            assert_eq!(frame.place_with(centre, &mut cache), frame.place(centre));
            let heights = (-50.0, 2500.0);
            assert_eq!(
                frame.camera_box_with(p0, p1, heights, &mut cache),
                frame.camera_box(p0, p1, heights)
            );
            assert_eq!(cache.len(), (1, 1), "frame {k}");
        }
        let frame = at(&placement, [8000.0, 8000.0]);
        cache.next_frame(frame.projected_lattice());
        assert_eq!(cache.len(), (1, 1), "last frame's entries kept one frame");
        cache.next_frame(frame.projected_lattice());
        assert_eq!(cache.len(), (0, 0), "unused two frames: dropped");
        let georef = GeoRef { crs: Crs::Geographic, origin: [0.0, -90.0], spacing: [0.25; 2] };
        let global = GridPlacement::new(&georef, [1441, 721], georef.spacing_m([1441, 721]));
        let geographic =
            EarthFrame::new(&global, DVec3::new(1e5, 2e6, 3000.0), [10, 200]).expect("placed");
        cache.next_frame(geographic.projected_lattice());
        assert_eq!(cache.node([20, 210]), None);
        assert!(cache.patch([0.0, 0.0], [8.0, 8.0]).is_none());
    }
}
