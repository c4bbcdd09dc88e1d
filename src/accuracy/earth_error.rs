//! [`measure_earth`]: the display's error against the geodetic truth, per
//! pixel, in pixels. Where the LOD-only error (`pixel_error`) compares two
//! surfaces drawn in the display's own frame, this one compares the
//! display with the earth, seen from where the aircraft is.
//!
//! **The error at pixel `p`** is the larger of two screen distances:
//! - *where the display drew:* the display drew at `p` some geodetic place
//!   (latitude, longitude: its drawn point read back in the display's frame,
//!   [`DisplayFrame::place_of`]); the true camera sees the true surface
//!   point at that place (the best data's height there, on the ellipsoid) at
//!   pixel `q`: the error is `|q - p|`;
//! - *where the earth is:* the true camera's ray through `p` meets the
//!   true surface at a place; the display's surface at that place
//!   ([`DisplayFrame::point_at`], with the height the drawn tiles have
//!   there) is drawn at pixel `q'`: the error is `|q' - p|`.
//!
//! Both are zero for a display that draws every place where the earth has it,
//! and both move with any misplacement: a surface drawn too low or too high,
//! a place drawn at the wrong bearing or distance (horizontal misplacement
//! moves `q` across the screen even where heights are exact), a camera at
//! the wrong place. Comparing places, not hit points, keeps the measure
//! stable along grazing rays (a millimetre of height moves a hit point
//! kilometres there, not the place's image). Coverage is classed as the
//! LOD-only measure classes it (silhouette, mismatch, hole).

use glam::{DMat4, DVec2, DVec3, DVec4};
use rayon::prelude::*;

use super::earth_ground::EarthGround;
use super::earth_rays::{EarthImage, TrueCamera};
#[cfg(doc)]
use super::LodSurface;
use super::PositionImage;
use crate::camera::Camera;
use crate::earth::{EarthFrame, GridPlacement};
use crate::render::FrameUniforms;

/// How the display maps its drawn, camera-relative points to places and back.
#[derive(Clone, Copy, Debug)]
pub enum DisplayFrame {
    /// The local planar frame: chart metres east and north of the grid's
    /// south-west post, each vertex lowered by `d^2 / 2R` (the display up
    /// to issue 26).
    Planar {
        /// The grid's placement (its chart).
        placement: GridPlacement,
        /// The camera's chart point and altitude.
        eye: DVec3,
        /// The altitude the shader subtracted (the f32 uniform, widened).
        altitude: f64,
        /// The frame's view-projection, widened.
        view_projection: DMat4,
        /// Viewport, pixels.
        viewport: [u32; 2],
    },
    /// The ellipsoid: camera-relative points along the camera's east,
    /// north and up (the display since issue 26's phase B).
    Ellipsoid {
        /// The grid's placement.
        placement: GridPlacement,
        /// The eye and its axes.
        earth: EarthFrame,
        /// The frame's view-projection, widened.
        view_projection: DMat4,
        /// Viewport, pixels.
        viewport: [u32; 2],
    },
}

impl DisplayFrame {
    /// The frame `camera` was drawn with, by the frame's `uniforms`.
    pub fn planar(placement: GridPlacement, camera: &Camera, uniforms: &FrameUniforms) -> Self {
        let m = uniforms.view_projection.to_cols_array().map(f64::from);
        DisplayFrame::Planar {
            placement,
            eye: camera.position,
            altitude: uniforms.camera_altitude as f32 as f64,
            view_projection: DMat4::from_cols_array(&m),
            viewport: uniforms.viewport,
        }
    }

    /// The frame `uniforms` were drawn in: the ellipsoid where they carry
    /// an [`EarthFrame`], else the planar chart.
    pub fn of(placement: GridPlacement, camera: &Camera, uniforms: &FrameUniforms) -> Self {
        let Some(earth) = uniforms.earth else {
            return DisplayFrame::planar(placement, camera, uniforms);
        };
        let m = uniforms.view_projection.to_cols_array().map(f64::from);
        DisplayFrame::Ellipsoid {
            placement,
            earth,
            view_projection: DMat4::from_cols_array(&m),
            viewport: uniforms.viewport,
        }
    }

    /// The level-0 post (the geodetic place) the display drew at
    /// camera-relative point `d`.
    pub fn place_of(&self, d: DVec3) -> [f64; 2] {
        match self {
            DisplayFrame::Planar { placement, eye, .. } => {
                placement.post_of_chart([eye.x + d.x, eye.y + d.y])
            }
            DisplayFrame::Ellipsoid { placement, earth, .. } => {
                placement.post_of_ecef(earth.ecef_of(d)).0
            }
        }
    }

    /// The chart point of `post`, where the display's surface is looked up.
    pub fn chart_of(&self, post: [f64; 2]) -> [f64; 2] {
        match self {
            DisplayFrame::Planar { placement, .. } | DisplayFrame::Ellipsoid { placement, .. } => {
                placement.chart_of_post(post)
            }
        }
    }

    /// The camera-relative point the display draws at `post` with its
    /// surface `drawn_m` there (as [`LodSurface::height_at`] gives it).
    pub fn point_at(&self, post: [f64; 2], drawn_m: f64) -> DVec3 {
        match self {
            DisplayFrame::Planar { placement, eye, altitude, .. } => {
                let [x, y] = placement.chart_of_post(post);
                DVec3::new(x - eye.x, y - eye.y, drawn_m - altitude)
            }
            DisplayFrame::Ellipsoid { placement, earth, .. } => {
                earth.camera_of(placement.ecef(post[0], post[1], drawn_m))
            }
        }
    }

    /// Where the display puts camera-relative point `d` on the screen
    /// (column and row from the top left), if in front of the camera.
    pub fn pixel_of(&self, d: DVec3) -> Option<DVec2> {
        match self {
            DisplayFrame::Planar { view_projection, viewport, .. }
            | DisplayFrame::Ellipsoid { view_projection, viewport, .. } => {
                let clip: DVec4 = *view_projection * d.extend(1.0);
                (clip.w > 1e-9).then(|| {
                    let [w, h] = viewport.map(f64::from);
                    DVec2::new((clip.x / clip.w + 1.0) / 2.0 * w, (1.0 - clip.y / clip.w) / 2.0 * h)
                })
            }
        }
    }
}

/// One view's error against the geodetic truth, over the traced pixels.
#[derive(Clone, Debug, Default)]
pub struct EarthErrors {
    /// Per traced pixel: the error in pixels, NaN where not measured.
    pub errors_px: Vec<f32>,
    /// Traced pixels where both show terrain.
    pub terrain_pixels: usize,
    /// Terrain in one image only over ground both surfaces cover: measured.
    pub silhouette: usize,
    /// The display shows terrain where the earth has no data.
    pub lod_only: usize,
    /// The earth shows terrain where the display draws none.
    pub truth_only: usize,
    /// Terrain pixels whose true place no drawn tile covers.
    pub holes: usize,
}

/// What the measure reads besides the two images.
pub struct EarthView<'a> {
    /// How the display drew.
    pub frame: &'a DisplayFrame,
    /// The true camera.
    pub camera: &'a TrueCamera,
    /// The best data on the ellipsoid.
    pub ground: &'a EarthGround,
    /// The display's drawn surface at a chart point, as
    /// [`LodSurface::height_at`] gives it (`None`: no surface drawn there).
    pub surface: &'a (dyn Fn(f64, f64) -> Option<f64> + Sync),
}

/// Measures the display's positions `lod` against the geodetic truth
/// `truth` (see the module doc), into `out`.
pub fn measure_earth(
    view: &EarthView<'_>,
    lod: &PositionImage,
    truth: &EarthImage,
    out: &mut EarthErrors,
) {
    out.errors_px.clear();
    out.errors_px.resize(truth.hits.len(), f32::NAN);
    let width = lod.size.x as usize;
    let counts = out
        .errors_px
        .par_iter_mut()
        .enumerate()
        .map(|(k, error)| {
            let [col, row] = truth.pixel(k);
            let pixel = DVec2::new(col as f64 + 0.5, row as f64 + 0.5);
            let drawn = lod.point(row as usize * width + col as usize);
            let lod_side = drawn.map(|d| view.where_drawn(pixel, d.as_dvec3()));
            let truth_side = truth.hits[k].map(|hit| view.where_true(pixel, hit.post));
            let mut counts = [0usize; 5];
            match (lod_side, truth_side) {
                (Some(a), Some(b)) => {
                    counts[0] += 1;
                    if b.is_none() {
                        counts[4] += 1;
                    }
                    *error = a.unwrap_or(0.0).max(b.unwrap_or(0.0)) as f32;
                }
                (Some(Some(a)), None) => {
                    counts[1] += 1;
                    *error = a as f32;
                }
                (Some(None), None) => counts[2] += 1,
                (None, Some(Some(b))) => {
                    counts[1] += 1;
                    *error = b as f32;
                }
                (None, Some(None)) => counts[3] += 1,
                (None, None) => {}
            }
            counts
        })
        .reduce(|| [0; 5], |a, b| [0, 1, 2, 3, 4].map(|i| a[i] + b[i]));
    [out.terrain_pixels, out.silhouette, out.lod_only, out.truth_only, out.holes] = counts;
}

impl EarthView<'_> {
    /// The error where the display drew `d` at `pixel`: `None` when the
    /// earth has no surface at that place.
    fn where_drawn(&self, pixel: DVec2, d: DVec3) -> Option<f64> {
        let [u, v] = self.frame.place_of(d);
        let height = self.ground.height(u, v)?;
        let point = self.ground.placement().ecef(u, v, height);
        Some(self.camera.pixels_from(pixel, point))
    }

    /// The error where the earth is at `post`, seen at `pixel`: `None` where
    /// the display draws no surface there.
    fn where_true(&self, pixel: DVec2, post: [f64; 2]) -> Option<f64> {
        let [x, y] = self.frame.chart_of(post);
        let drawn = (self.surface)(x, y)?;
        let point = self.frame.point_at(post, drawn);
        Some(match self.frame.pixel_of(point) {
            Some(q) => q.distance(pixel),
            // Behind the display's camera: as far off as anything can be.
            None => 1e6,
        })
    }
}
