//! The geodetic truth's image: each pixel's ray from the true camera pose,
//! cast in ECEF against the best data on the ellipsoid ([`EarthGround`]).
//!
//! **The true camera** ([`TrueCamera`]) is the display's camera read as
//! what it stands for: its position a place on the earth (the grid's chart
//! point at its latitude and longitude, the altitude a height), its heading,
//! pitch and roll relative to the local east-north-up frame there, its
//! field of view and viewport the display's.
//!
//! **The march.** A ray enters the shell below the data's highest height
//! (an ellipsoid of semi-axes `a + top`, `b + top`, padded so that it holds
//! every point of that height) and is followed until it meets the surface,
//! leaves the shell, or passes the loaded reach:
//! 1. *Skip.* Where the ray's height is above the highest ground of the 3 x 3
//!    blocks around it at some level of the block pyramid, it moves on by that
//!    height difference or a block's width, whichever is less: a height
//!    changes by at most a metre a metre, and a block's width on the ground
//!    cannot be crossed in less. The same with whole rows (rings near a
//!    pole, where blocks are slivers): the highest ground within `2^k` rows.
//! 2. *Cells.* Near the ground it moves half a cell of the best data at a
//!    time. A segment that stays above the highest ground of every row it
//!    can reach is clear as it is (near a pole it would cross thousands of
//!    converging meridians). Otherwise it evaluates the height above the
//!    surface exactly (ECEF to
//!    geodetic, then the triangle there) at both ends and wherever the
//!    segment crosses a lattice line or a cell's diagonal. Between those
//!    points both the ray's height and the surface are linear but for the
//!    earth's curvature, bounded by `len^2 / (8 R)` and the lattice's own
//!    bend; a piece whose ends are not clear by that margin is halved, and
//!    a piece whose end is below the surface is bisected to the hit
//!    ([`HIT_TOLERANCE_M`] along the ray).
//!
//! No hit can be stepped over: every skip is conservative and every cell
//! is checked with a bound on what lies between its samples.

use glam::{DMat3, DVec2, DVec3};
use rayon::prelude::*;

use super::earth_ground::EarthGround;
use super::ray_truth::HIT_TOLERANCE_M;
use crate::camera::Camera;
use crate::earth::ellipsoid::{self, A, B};
use crate::earth::GridPlacement;

/// The shell's semi-axes are padded by this much over `a + top`, `b + top`:
/// more than the gap between that ellipsoid and the surface of constant
/// geodetic height `top` (e^2 top / 2, 30 m at 9 km).
const SHELL_PAD_M: f64 = 200.0;
/// The least radius of curvature of a line of constant height on the
/// ellipsoid, metres (the meridian's at the equator, 6335 km), less a margin.
const LEAST_RADIUS_M: f64 = 6.3e6;
/// Most lattice crossings one segment is checked at; a segment crossing
/// more is halved.
const CROSSINGS: usize = 32;
/// Most steps a ray takes before it is given up as sky (a guard).
const MAX_STEPS: u32 = 2_000_000;

/// The camera the display's camera stands for, on the earth.
#[derive(Clone, Copy, Debug)]
pub struct TrueCamera {
    /// The eye, ECEF metres.
    pub eye: DVec3,
    /// Eye axes (x right, y up, z back) to ECEF.
    ecef_from_eye: DMat3,
    /// `tan` of half the field of view, across and up.
    tan_half: DVec2,
    /// Viewport, pixels.
    pub viewport: [u32; 2],
    /// Ulrich's K: pixels per radian at the centre of the screen.
    pub perspective_scale: f64,
}

impl TrueCamera {
    /// The true pose of `camera`, whose position is a chart point of the
    /// grid `placement` places (and an altitude).
    pub fn new(camera: &Camera, placement: &GridPlacement) -> TrueCamera {
        let chart = [camera.position.x, camera.position.y];
        let (lat, lon) = placement.geodetic_of_chart(chart);
        let eye = ellipsoid::to_ecef(lat, lon, camera.position.z);
        let enu = ellipsoid::enu_to_ecef(lat, lon);
        let body_to_enu = DMat3::from_quat(camera.attitude());
        // Eye (right, up, back) to body (right, nose, up).
        let body_from_eye = DMat3::from_cols(DVec3::X, DVec3::Z, -DVec3::Y);
        let half_x = (camera.fov_x_deg.to_radians() / 2.0).tan();
        TrueCamera {
            eye,
            ecef_from_eye: enu * body_to_enu * body_from_eye,
            tan_half: DVec2::new(half_x, (camera.fov_y() / 2.0).tan()),
            viewport: camera.viewport,
            perspective_scale: camera.perspective_scale(),
        }
    }

    /// Unit ECEF direction of the ray through `pixel` (column and row from
    /// the top-left corner; a pixel's centre is at `+0.5`).
    pub fn ray(&self, pixel: DVec2) -> DVec3 {
        let [w, h] = self.viewport.map(f64::from);
        let ndc = DVec2::new(pixel.x / w * 2.0 - 1.0, 1.0 - pixel.y / h * 2.0);
        let eye_dir = DVec3::new(ndc.x * self.tan_half.x, ndc.y * self.tan_half.y, -1.0);
        (self.ecef_from_eye * eye_dir).normalize()
    }

    /// Where ECEF point `p` is on the screen (column and row from the top
    /// left), or `None` when it is not in front of the camera.
    pub fn pixel_of(&self, p: DVec3) -> Option<DVec2> {
        let q = self.ecef_from_eye.transpose() * (p - self.eye);
        (q.z < -1e-9).then(|| {
            let [w, h] = self.viewport.map(f64::from);
            let ndc = DVec2::new(q.x / -q.z / self.tan_half.x, q.y / -q.z / self.tan_half.y);
            DVec2::new((ndc.x + 1.0) / 2.0 * w, (1.0 - ndc.y) / 2.0 * h)
        })
    }

    /// Screen distance, pixels, from `pixel` to where the camera sees ECEF
    /// point `p`; behind the camera, the angle between the pixel's ray and
    /// the point times Ulrich's K.
    pub fn pixels_from(&self, pixel: DVec2, p: DVec3) -> f64 {
        match self.pixel_of(p) {
            Some(q) => q.distance(pixel),
            None => self.ray(pixel).angle_between(p - self.eye) * self.perspective_scale,
        }
    }
}

/// Where a true ray met the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarthHit {
    /// The point, ECEF metres.
    pub point: DVec3,
    /// Its level-0 post, on the grid.
    pub post: [f64; 2],
}

/// The geodetic truth of one view: the traced pixels' hits.
#[derive(Clone, Debug, Default)]
pub struct EarthImage {
    /// Viewport, pixels.
    pub viewport: [u32; 2],
    /// Every `stride`-th pixel across and down is traced (its centre at
    /// `stride * k + stride / 2 + 0.5`).
    pub stride: u32,
    /// Traced pixels across and down.
    pub size: [u32; 2],
    /// Per traced pixel, row-major from the top left: the hit, or sky.
    pub hits: Vec<Option<EarthHit>>,
    /// Steps taken by all rays.
    pub steps: u64,
}

impl EarthImage {
    /// Viewport pixel `(col, row)` of traced pixel `k`.
    pub fn pixel(&self, k: usize) -> [u32; 2] {
        let w = self.size[0].max(1) as usize;
        let s = self.stride;
        [(k % w) as u32 * s + s / 2, (k / w) as u32 * s + s / 2]
    }
}

/// Traces every `stride`-th pixel of `camera`'s view against `ground`,
/// out to `reach_m` metres, into `out`.
pub fn trace_earth(
    camera: &TrueCamera,
    ground: &EarthGround,
    stride: u32,
    reach_m: f64,
    out: &mut EarthImage,
) {
    let stride = stride.max(1);
    let size = camera.viewport.map(|n| n.div_ceil(stride).max(1));
    *out = EarthImage { viewport: camera.viewport, stride, size, hits: Vec::new(), steps: 0 };
    out.hits.resize(size[0] as usize * size[1] as usize, None);
    let template = EarthImage { hits: Vec::new(), ..out.clone() };
    out.steps = out
        .hits
        .par_chunks_mut(size[0] as usize)
        .enumerate()
        .map(|(row, hits)| {
            let mut steps = 0u64;
            for (col, hit) in hits.iter_mut().enumerate() {
                let [x, y] = template.pixel(row * size[0] as usize + col);
                let dir = camera.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                let (found, taken) = march(ground, camera.eye, dir, reach_m);
                *hit = found;
                steps += taken as u64;
            }
            steps
        })
        .sum();
}

/// The hit of the ray through `pixel` (column and row from the top left; a
/// pixel's centre at `+0.5`), followed out to `reach_m` metres.
pub fn trace_ray(
    camera: &TrueCamera,
    ground: &EarthGround,
    pixel: DVec2,
    reach_m: f64,
) -> Option<EarthHit> {
    march(ground, camera.eye, camera.ray(pixel), reach_m).0
}

/// Where the ray's parameter lies inside the ellipsoid of semi-axes
/// `(a, a, b)` (from 0 on); `None` when it misses it.
fn inside_ellipsoid(eye: DVec3, dir: DVec3, a: f64, b: f64) -> Option<(f64, f64)> {
    let scale = DVec3::new(1.0 / a, 1.0 / a, 1.0 / b);
    let (e, d) = (eye * scale, dir * scale);
    let (qa, qb, qc) = (d.length_squared(), 2.0 * e.dot(d), e.length_squared() - 1.0);
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let (lo, hi) = ((-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa));
    (hi >= 0.0).then_some((lo.max(0.0), hi))
}

/// One ray's state: where it starts and where it points.
struct Ray<'a> {
    ground: &'a EarthGround,
    eye: DVec3,
    dir: DVec3,
}

/// The ray at parameter `s`: its post (maybe off the grid), its height,
/// and its height above the surface (`None` where there is none).
#[derive(Clone, Copy)]
struct Sample {
    s: f64,
    post: [f64; 2],
    height: f64,
    above: Option<f64>,
}

impl Ray<'_> {
    fn at(&self, s: f64) -> Sample {
        let placement = self.ground.placement();
        let (post, height) = placement.post_of_ecef(self.eye + self.dir * s);
        let above = self.ground.height(post[0], post[1]).map(|z| height - z);
        Sample { s, post, height, above }
    }

    fn hit(&self, s: f64) -> EarthHit {
        let sample = self.at(s);
        let post = self.ground.on_grid(sample.post[0], sample.post[1]).unwrap_or(sample.post);
        EarthHit { point: self.eye + self.dir * s, post }
    }
}

/// What a ray meets first.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Meet {
    /// The surface, at this parameter.
    Surface(f64),
    /// The data's cut face: it entered the data below their surface at a
    /// data edge or a void's rim. The display hangs a curtain of no data
    /// there; the truth has no terrain at that pixel, and the ray stops.
    CutFace,
}

/// Follows one ray; its hit and the steps taken.
fn march(ground: &EarthGround, eye: DVec3, dir: DVec3, reach_m: f64) -> (Option<EarthHit>, u32) {
    let (bottom, top) = ground.height_range();
    if !top.is_finite() {
        return (None, 0);
    }
    let pad = top + SHELL_PAD_M;
    let Some((enter, leave)) = inside_ellipsoid(eye, dir, A + pad, B + pad) else {
        return (None, 0);
    };
    let ray = Ray { ground, eye, dir };
    let end = leave.min(reach_m);
    let mut s = enter;
    // The last sample off the grid, while the ray has not reached it since.
    let mut off_grid = None;
    for step in 1..=MAX_STEPS {
        if s > end {
            return (None, step);
        }
        let here = ray.at(s);
        if here.height < bottom - 2_000.0 {
            // Below every height of the data: it passed under no-data.
            return (None, step);
        }
        let Some([u, v]) = ground.on_grid(here.post[0], here.post[1]) else {
            off_grid = Some(s);
            s += off_grid_step(ground, here.post);
            continue;
        };
        if let (Some(outside), Some(above)) = (off_grid.take(), here.above) {
            if above <= 0.0 {
                // It reached the grid below the surface.
                return match enter_data(&ray, outside, s) {
                    Meet::Surface(hit) => (Some(ray.hit(hit)), step),
                    Meet::CutFace => (None, step),
                };
            }
        }
        // Half a cell, by its narrower side; near a pole, where cells are
        // slivers east-west, at least a sixteenth of their north side (the
        // lattice crossings between are all checked).
        let cell = ground.cell_posts(u, v).unwrap_or(1.0);
        let side = ground.post_spacing_near(v).max(ground.north_spacing_near(v) / 16.0);
        let length = (0.5 * cell * side).max(0.05);
        // A skip shorter than a cell's step is not taken: near a pole a
        // block is a sliver whose width, the most it lets a ray go, is
        // centimetres, and the cells' check goes farther at no risk.
        if let Some(step) = skip(ground, u, v, here.height).filter(|&step| step >= length) {
            s += step;
            continue;
        }
        match check_segment(&ray, here, s + length) {
            Some(Meet::Surface(hit)) => return (Some(ray.hit(hit)), step),
            Some(Meet::CutFace) => return (None, step),
            None => {}
        }
        s += length;
    }
    (None, MAX_STEPS)
}

/// How far a ray at grid post `(u, v)` and `height` may move without
/// meeting the ground: by the clearest 3 x 3 block neighbourhood, or where
/// blocks are slivers (near a pole) the clearest latitude band or strip of
/// rows, whichever lets it go farthest; `None` when none is clear.
fn skip(ground: &EarthGround, u: f64, v: f64, height: f64) -> Option<f64> {
    let block = ground.clear_block(u, v, height).map(|(k, top)| {
        let side_m = ground.block_side_posts(k) * ground.post_spacing_near(v);
        (height - top).min(side_m)
    });
    let band = ground.clear_band(v, height).map(|(k, top)| {
        let side_m = ground.block_side_posts(k) * ground.north_spacing_near(v);
        (height - top).min(side_m)
    });
    let strip = ground.clear_strips(v, height);
    [block, band, strip].into_iter().flatten().reduce(f64::max).map(|step| step.max(0.01))
}

/// How far a ray off the grid at `post` may move before it can reach the
/// grid: its distance in posts to the grid's rectangle times the least
/// spacing there, at least a twentieth of a post.
fn off_grid_step(ground: &EarthGround, post: [f64; 2]) -> f64 {
    let placement = ground.placement();
    let last = placement.posts().map(|p| p.saturating_sub(1) as f64);
    let away = |p: f64, last: f64| (-p).max(p - last).max(0.0);
    let posts = away(post[0], last[0]).max(away(post[1], last[1]));
    let v = post[1].clamp(0.0, last[1]);
    let here = placement.ecef(post[0], post[1].clamp(-1e9, 1e9), 0.0);
    let east = here.distance(placement.ecef(post[0] + 1.0, post[1], 0.0));
    let spacing = east.min(ground.post_spacing_near(v)).max(1e-3);
    (posts * spacing * 0.99).max(0.05 * spacing)
}

/// Whether the ray meets the surface between `from` and parameter `to`:
/// the hit's parameter if it does.
fn check_segment(ray: &Ray<'_>, from: Sample, to: f64) -> Option<Meet> {
    let end = ray.at(to);
    if clear_of_rows(ray.ground, &from, &end) {
        return None;
    }
    let mut cuts = [0.0f64; CROSSINGS];
    let count = lattice_crossings(ray.ground, from.post, end.post, &mut cuts);
    if count == CROSSINGS && to - from.s > 2.0 * HIT_TOLERANCE_M {
        // More lattice lines than room: the two halves on their own.
        let middle = 0.5 * (from.s + to);
        return check_segment(ray, from, middle).or_else(|| check_segment(ray, ray.at(middle), to));
    }
    let mut previous = from;
    for &t in cuts[..count].iter().chain(std::iter::once(&1.0)) {
        let next = if t >= 1.0 { end } else { ray.at(from.s + t * (to - from.s)) };
        if let Some(hit) = check_piece(ray, previous, next, 0) {
            return Some(hit);
        }
        previous = next;
    }
    None
}

/// Whether the ray between samples `a` and `b` stays above the highest
/// ground of every row it can reach: then no lattice crossing needs a look
/// (near a pole a short segment crosses thousands of meridians). The ray's
/// geodetic height is its distance to the ellipsoid, a convex function along
/// a line that bends by at most `1 / LEAST_RADIUS_M`: it is nowhere below
/// the lower end by more than `len^2 / (8 R)`. Its row changes by at most
/// its length over the least distance between rows.
fn clear_of_rows(ground: &EarthGround, a: &Sample, b: &Sample) -> bool {
    let length = b.s - a.s;
    let lowest = a.height.min(b.height) - length * length / (8.0 * LEAST_RADIUS_M) - 0.01;
    let rows = length / ground.least_north_m().max(1e-3);
    let (v_lo, v_hi) = (a.post[1].min(b.post[1]) - rows, a.post[1].max(b.post[1]) + rows);
    v_lo.is_finite() && v_hi.is_finite() && lowest > ground.rows_top(v_lo, v_hi)
}

/// Parameters in (0, 1) where the straight grid segment `a` to `b` crosses
/// a lattice line or a cell diagonal of the best data's finer cell at
/// either end, sorted; how many were written to `out`.
fn lattice_crossings(
    ground: &EarthGround,
    a: [f64; 2],
    b: [f64; 2],
    out: &mut [f64; CROSSINGS],
) -> usize {
    let cell = |p: [f64; 2]| ground.cell_posts(p[0], p[1]);
    let c = match (cell(a), cell(b)) {
        (Some(x), Some(y)) => x.min(y),
        (Some(x), None) | (None, Some(x)) => x,
        (None, None) => return 0,
    };
    let mut b = b;
    if let Some(period) = ground.placement().period_posts() {
        // The shorter way round.
        b[0] = a[0] + (b[0] - a[0] + period / 2.0).rem_euclid(period) - period / 2.0;
    }
    let mut count = 0;
    let lines = [(a[0], b[0]), (a[1], b[1]), (a[0] - a[1], b[0] - b[1])];
    for (p, q) in lines {
        let (lo, hi) = (p.min(q) / c, p.max(q) / c);
        let mut k = lo.floor() + 1.0;
        while k < hi && count < out.len() {
            out[count] = (k * c - p) / (q - p);
            count += 1;
            k += 1.0;
        }
    }
    out[..count].sort_unstable_by(f64::total_cmp);
    count
}

/// Whether the ray meets the surface between samples `a` and `b` (one
/// triangle of the surface, or no surface at an end): bisected to the
/// hit when `b` is below the surface, halved while neither end is clear
/// by the curvature's margin.
fn check_piece(ray: &Ray<'_>, a: Sample, b: Sample, depth: u32) -> Option<Meet> {
    let (Some(fa), Some(fb)) = (a.above, b.above) else {
        // No surface at an end: a data edge or a post without data.
        return match (a.above, b.above) {
            (None, Some(fb)) if fb <= 0.0 => Some(enter_data(ray, a.s, b.s)),
            _ => None,
        };
    };
    if fa <= 0.0 {
        return Some(Meet::Surface(a.s));
    }
    if fb <= 0.0 {
        return Some(Meet::Surface(bisect(ray, a.s, b.s)));
    }
    let length = b.s - a.s;
    let lat = ray.ground.placement().geodetic_of_post(a.post[0], a.post[1]).0;
    let bend = 1.0 + 10.0 * (1.0 + lat.abs().min(1.5692).tan());
    let margin = length * length * bend / (8.0 * LEAST_RADIUS_M);
    if fa.min(fb) > margin || length < HIT_TOLERANCE_M || depth > 40 {
        return None;
    }
    let middle = ray.at(0.5 * (a.s + b.s));
    check_piece(ray, a, middle, depth + 1).or_else(|| check_piece(ray, middle, b, depth + 1))
}

/// Where a ray without surface at `lo` and below the surface at `hi` meets
/// the data: it enters them between (to [`HIT_TOLERANCE_M`]); below the
/// surface there it meets the data's cut face, which the display draws as
/// a curtain of no data and the truth mesh as the same (`Meet::CutFace`),
/// else it meets the surface further on.
fn enter_data(ray: &Ray<'_>, lo: f64, below: f64) -> Meet {
    // The shared bisection, with "no surface" on the side it keeps as lo.
    let outside = |s: f64| ray.at(s).above.is_none().then_some(1.0);
    let entry = super::ray_truth::bisect(&outside, lo, below);
    match ray.at(entry).above {
        Some(f) if f > 0.0 => Meet::Surface(bisect(ray, entry, below)),
        _ => Meet::CutFace,
    }
}

/// The ray's first parameter within [`HIT_TOLERANCE_M`] of the surface
/// between `lo` (above it) and `hi` (below it, or without surface).
fn bisect(ray: &Ray<'_>, lo: f64, hi: f64) -> f64 {
    super::ray_truth::bisect(&|s| ray.at(s).above, lo, hi)
}
