//! [`trace_truth`]: the full-resolution image of a view without drawing it.
//! Out to a 10 km cruise's horizon the full-resolution mesh is 10^8
//! triangles and more, so instead of the GPU truth pass each pixel's ray is
//! followed on the CPU against the exact heights (the level-0 posts joined
//! as triangles) and the first point where it meets the surface becomes
//! that pixel's truth position, as the truth pass would have drawn it.
//!
//! **The route.** The ray leaves the eye through the pixel's centre (the
//! inverse of the frame's own view-projection). The surface is drawn in the
//! display's curvature model: `exact(x, y) - A - D² c` relative to the eye.
//! 1. Skip: the ray meets nothing while it is above the paraboloid of the
//!    highest possible height `top`; solving one quadratic gives where it
//!    enters that shell and where it leaves it past the horizon (or that it
//!    never enters: sky).
//! 2. March: with `g` a bound on the surface's slope (metres per metre;
//!    [`RayGround::slope`]), the ray's height above the surface, `f`, falls
//!    by at most `L = |dz| + |d_xy| (g + 2 c s_max |d_xy|)` per metre along
//!    the ray, so the ray advances `f / L` and cannot step over terrain
//!    (conservative sphere tracing; no hit is ever skipped, unlike fixed
//!    steps). It stops within [`HIT_TOLERANCE_M`] above the surface.
//! 3. Refine: the last step's bracket is bisected to [`HIT_TOLERANCE_M`]
//!    whenever a step would overshoot (never, with an exact slope bound; a
//!    guard against rounding).
//!
//! A pixel whose ray reaches no surface before leaving the shell is sky.

use glam::{DMat4, DVec2, DVec3, DVec4, UVec2};
use rayon::prelude::*;

use super::{ExactHeight, PositionImage, ViewGeometry};

/// A ray stops this close above the surface, metres.
pub const HIT_TOLERANCE_M: f64 = 0.01;
/// Most steps a ray takes before it is given up as sky (never reached on
/// the procedural earth; a guard).
const MAX_STEPS: u32 = 100_000;

/// The exact surface a ray is followed against.
#[derive(Clone, Copy)]
pub struct RayGround<'a> {
    /// The exact height at a local point (`None`: no data, nothing to hit).
    pub exact: ExactHeight<'a>,
    /// Bound on the exact surface's slope, metres per metre.
    pub slope: f64,
    /// No exact height is higher than this, metres.
    pub top_m: f64,
    /// Post spacing, metres: the step over ground without data.
    pub spacing_m: f64,
}

/// Fills `out` with the truth positions of `geometry`'s view over `ground`:
/// per pixel, the camera-relative point where its ray first meets the
/// surface (alpha 1), or sky (alpha 0). Returns the rays' total steps.
pub fn trace_truth(
    geometry: &ViewGeometry,
    ground: &RayGround<'_>,
    out: &mut PositionImage,
) -> u64 {
    let [w, h] = geometry.viewport;
    out.size = UVec2::new(w, h);
    out.texels.clear();
    out.texels.resize(w as usize * h as usize, [0.0; 4]);
    let inverse = geometry.view_projection.inverse();
    out.texels
        .par_chunks_mut(w.max(1) as usize)
        .enumerate()
        .map(|(row, texels)| {
            let mut steps = 0u64;
            for (col, texel) in texels.iter_mut().enumerate() {
                let ndc = DVec2::new(
                    (col as f64 + 0.5) / w as f64 * 2.0 - 1.0,
                    1.0 - (row as f64 + 0.5) / h as f64 * 2.0,
                );
                let dir = ray_direction(&inverse, ndc);
                let (hit, taken) = march(geometry, ground, dir);
                steps += taken as u64;
                if let Some(p) = hit {
                    *texel = [p.x as f32, p.y as f32, p.z as f32, 1.0];
                }
            }
            steps
        })
        .sum()
}

/// Unit direction, camera-relative, of the ray through `ndc`.
fn ray_direction(inverse: &DMat4, ndc: DVec2) -> DVec3 {
    let unproject = |z: f64| {
        let p: DVec4 = *inverse * DVec4::new(ndc.x, ndc.y, z, 1.0);
        p.truncate() / p.w
    };
    (unproject(1.0) - unproject(-1.0)).normalize()
}

/// Follows one ray; the camera-relative hit and the steps taken.
fn march(geometry: &ViewGeometry, ground: &RayGround<'_>, dir: DVec3) -> (Option<DVec3>, u32) {
    let c = geometry.curvature;
    let horizontal = dir.truncate().length();
    // Height of the ray over the `top` paraboloid: a s^2 + b s + k.
    let (a, b, k) = (c * horizontal * horizontal, dir.z, geometry.altitude - ground.top_m);
    let Some((enter, leave)) = shell(a, b, k) else { return (None, 0) };
    let slope = horizontal * (ground.slope + 2.0 * c * leave * horizontal);
    let rate = dir.z.abs() + slope;
    let above = |s: f64| -> Option<f64> {
        let p = dir * s;
        let g = geometry.eye.truncate() + p.truncate();
        let h = (ground.exact)(g.x, g.y)?;
        // The surface as the measurement compares it (`drawn_truth`).
        Some(p.z - (geometry.drawn_truth(g, h) - geometry.altitude))
    };
    let (mut s, mut prev) = (enter, enter);
    for step in 1..=MAX_STEPS {
        if s > leave {
            return (None, step);
        }
        let Some(f) = above(s) else {
            prev = s;
            s += ground.spacing_m;
            continue;
        };
        if f <= HIT_TOLERANCE_M {
            let hit = if f < 0.0 { bisect(&above, prev, s) } else { s };
            return (Some(dir * hit), step);
        }
        prev = s;
        s += f / rate;
    }
    (None, MAX_STEPS)
}

/// Where `a s^2 + b s + k <= 0` for `s >= 0`: the ray inside the shell
/// under the highest possible surface. `None` when it never is.
fn shell(a: f64, b: f64, k: f64) -> Option<(f64, f64)> {
    if a <= 0.0 {
        // No curvature, or straight down/up: linear.
        return match (k <= 0.0, b < 0.0) {
            (true, _) => Some((0.0, f64::MAX)),
            (false, true) => Some((-k / b, f64::MAX)),
            (false, false) => None,
        };
    }
    let disc = b * b - 4.0 * a * k;
    if disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let (lo, hi) = ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a));
    (hi >= 0.0).then_some((lo.max(0.0), hi))
}

/// Bisects `[lo, hi]` (ray above the surface at `lo`, below at `hi`) to
/// [`HIT_TOLERANCE_M`] along the ray.
pub(super) fn bisect(above: &dyn Fn(f64) -> Option<f64>, mut lo: f64, mut hi: f64) -> f64 {
    while hi - lo > HIT_TOLERANCE_M {
        let mid = 0.5 * (lo + hi);
        match above(mid) {
            Some(f) if f > 0.0 => lo = mid,
            _ => hi = mid,
        }
    }
    hi
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::render::{DepthSlices, FrameUniforms, PostFrame};

    fn geometry(camera: &Camera, curvature: bool) -> ViewGeometry {
        let frame = FrameUniforms {
            view_projection: camera.projection(1.0, 1e6) * camera.view(),
            camera_altitude: camera.position.z,
            sun_direction: glam::Vec3::Z,
            curvature,
            horizon_floor_m: 0.0,
            morph_start_share: 0.7,
            warning_above_m: 0.0,
            caution_below_m: 0.0,
            viewport: camera.viewport,
            fog_distance_m: 1e6,
            posts: PostFrame::new(camera.position.truncate(), [30.0, 30.0]),
            last_post: [1 << 30; 2],
            slices: DepthSlices::new(camera, 1.0, 1e6, (0.0, 0.0)),
            earth: None,
        };
        ViewGeometry::new(camera, &frame)
    }

    /// Over a flat sea the rays meet the plane (or the curved sea) where
    /// geometry says, and rays above the horizon see sky.
    #[test]
    fn rays_meet_a_flat_sea_where_geometry_says() {
        let camera = Camera {
            position: DVec3::new(0.0, 0.0, 1000.0),
            heading_deg: 0.0,
            pitch_deg: -10.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [32, 18],
        };
        let sea = |_: f64, _: f64| Some(0.0f32);
        let ground = RayGround { exact: &sea, slope: 0.0, top_m: 0.0, spacing_m: 30.0 };
        for curvature in [false, true] {
            let g = geometry(&camera, curvature);
            let mut image = PositionImage::default();
            trace_truth(&g, &ground, &mut image);
            let (mut hits, mut sky) = (0, 0);
            for k in 0..image.pixel_count() {
                match image.point(k) {
                    Some(p) => {
                        let p = p.as_dvec3();
                        let drop = p.truncate().length_squared() * g.curvature;
                        assert!((p.z - (-1000.0 - drop)).abs() < 0.05 + 1e-6 * p.length(), "{p}");
                        hits += 1;
                    }
                    None => sky += 1,
                }
            }
            assert!(hits > 0 && sky > 0, "{hits} {sky}");
        }
    }

    /// A ridge of slope 1 is found by the march, never stepped over.
    #[test]
    fn rays_never_step_over_a_ridge() {
        let camera = Camera {
            position: DVec3::new(0.0, 0.0, 500.0),
            heading_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [16, 16],
        };
        // A 4 m wide, 600 m tall wall of slope 300 at y = 5 km.
        let wall = |_: f64, y: f64| Some((600.0 - 300.0 * (y - 5000.0).abs()).max(0.0) as f32);
        let ground = RayGround { exact: &wall, slope: 300.0, top_m: 600.0, spacing_m: 1.0 };
        let g = geometry(&camera, false);
        let mut image = PositionImage::default();
        trace_truth(&g, &ground, &mut image);
        let centre = image.point(8 * 16 + 8).expect("the wall is ahead");
        assert!((centre.y - 5000.0).abs() < 2.0, "{centre}");
    }
}
