//! [`measure_view`]: the per-pixel screen-space geometric error of one view,
//! and where the LOD and full-resolution images disagree on coverage. The
//! module doc of [`crate::accuracy`] says what is measured and why.
//!
//! A pixel with terrain in one image only is one of two things:
//! - a *silhouette* pixel: the other surface exists at that ground point but
//!   lies lower there, so the ray passes over it (a ridge against the sky
//!   drawn a pixel higher). That is the surface's error, and it is measured
//!   at the pixel like any other;
//! - a *coverage mismatch*: one render draws terrain over ground the other
//!   has no surface for (past the data's edge, or a hole).

use glam::{DMat4, DVec2, DVec3, DVec4, Vec3};
use rayon::prelude::*;

use super::{LodSurface, PositionImage};
use crate::camera::{Camera, EARTH_RADIUS_M};
use crate::earth::{EarthFrame, GridPlacement};
use crate::node::cell_surface;
use crate::render::FrameUniforms;

/// A LOD pixel on a tile edge drawn further than this from the mirrored
/// surface shows a skirt (metres; the mirror agrees to millimetres on
/// surfaces seen at an angle): below it, the skirt of the tile the mirror
/// reads there; above it, the skirt of the tile across the edge, seen
/// through the crack over the lower side.
pub const SKIRT_TOLERANCE_M: f64 = 0.05;

/// The exact full-resolution height at a local point, metres.
pub type ExactHeight<'a> = &'a (dyn Fn(f64, f64) -> Option<f32> + Sync);

/// How camera-relative points reach the screen in one view.
#[derive(Clone, Copy, Debug)]
pub struct ViewGeometry {
    /// Camera position in the local frame, metres.
    pub eye: DVec3,
    /// The altitude the shader subtracts (the f32 uniform, widened).
    pub altitude: f64,
    /// Projection times the rotation-only view, widened to f64 from the frame's uniforms.
    pub view_projection: DMat4,
    /// Viewport in pixels, width and height.
    pub viewport: [u32; 2],
    /// 1 / (2 R) when the earth's curvature is drawn, else 0 (the shader's u_frame.y).
    pub curvature: f64,
    /// Ulrich's K: pixels per radian at the centre of the screen.
    pub perspective_scale: f64,
    /// Level-0 post spacing, metres east and north (the frame's, widened).
    pub spacing_m: [f64; 2],
    /// For a frame drawn on the ellipsoid, where its camera-relative points
    /// are and the grid's placement ([`Self::on_earth`]); `None`: the chart.
    pub earth: Option<(EarthFrame, GridPlacement)>,
}

impl ViewGeometry {
    /// The geometry `camera` and its frame's uniforms drew with.
    pub fn new(camera: &Camera, frame: &FrameUniforms) -> ViewGeometry {
        let m = frame.view_projection.to_cols_array().map(f64::from);
        ViewGeometry {
            eye: camera.position,
            altitude: frame.camera_altitude as f32 as f64,
            view_projection: DMat4::from_cols_array(&m),
            viewport: frame.viewport,
            curvature: if frame.curvature {
                (1.0 / (2.0 * EARTH_RADIUS_M)) as f32 as f64
            } else {
                0.0
            },
            perspective_scale: camera.perspective_scale(),
            spacing_m: frame.posts.spacing.map(f64::from),
            earth: None,
        }
    }

    /// The geometry of a frame drawn on the ellipsoid (`frame.earth`) over
    /// the grid `placement` places: drawn points are read at their geodetic
    /// place (their post, in the grid's own turn where it wraps, and their
    /// height above the ellipsoid), not through the chart. Unchanged for a
    /// frame drawn in the chart.
    pub fn on_earth(self, frame: &FrameUniforms, placement: Option<GridPlacement>) -> Self {
        let earth = frame.earth.zip(placement);
        ViewGeometry { earth, ..self }
    }

    /// How far a flat cell of a tile of `level` may sag below the curved
    /// surface through its posts, metres (its widest side `c`: `c^2 / 2R`,
    /// more than a triangle's `c^2 / 3R`); 0 in the chart, whose drop the
    /// mirror models.
    pub fn sag_m(&self, level: u8) -> f64 {
        if self.earth.is_none() {
            return 0.0;
        }
        let cell = self.spacing_m[0].max(self.spacing_m[1]) * (1u64 << level.min(40)) as f64;
        cell * cell / (2.0 * EARTH_RADIUS_M)
    }

    /// The ground point a camera-relative drawn point `p` lies over, and
    /// its height with the altitude added back (the curvature drop stays:
    /// both surfaces are compared as drawn).
    pub fn ground(&self, p: DVec3) -> (DVec2, f64) {
        if let Some((frame, placement)) = &self.earth {
            let (post, height) = placement.post_of_ecef(frame.ecef_of(p));
            return (DVec2::from(placement.chart_of_post(post)), height);
        }
        (self.eye.truncate() + p.truncate(), p.z + self.altitude)
    }

    /// The full-resolution surface as drawn over the ground point `g`:
    /// `exact` lowered by the curvature drop as the truth mesh draws it,
    /// per post and linear across each level-0 cell's triangle (the chord
    /// sags below the curved earth by `s^2 / 8R`: a tenth of a millimetre
    /// over 90 m posts, but 1.7 m over ETOPO5's 9 km ones, 2 px at 1 km).
    pub fn drawn_truth(&self, g: DVec2, exact: f32) -> f64 {
        if self.earth.is_some() {
            // On the ellipsoid heights are read above it: no drop.
            return exact as f64;
        }
        let [sx, sy] = self.spacing_m;
        if !(sx > 0.0 && sy > 0.0) {
            // No post lattice given: the curved surface itself.
            return exact as f64 - (g - self.eye.truncate()).length_squared() * self.curvature;
        }
        let (u, v) = (g.x / sx, g.y / sy);
        let (i, j) = (u.floor(), v.floor());
        let drop = |di: f64, dj: f64| {
            let post = DVec2::new((i + di) * sx, (j + dj) * sy);
            (post - self.eye.truncate()).length_squared() * self.curvature
        };
        let sagged = cell_surface(
            drop(0.0, 0.0),
            drop(1.0, 0.0),
            drop(0.0, 1.0),
            drop(1.0, 1.0),
            u - i,
            v - j,
        );
        exact as f64 - sagged
    }

    /// On-screen length, pixels, of the vertical segment from the
    /// camera-relative point `p` to `dz` metres above it. Where either end
    /// is not in front of the camera, Ulrich's `|dz| K / distance` instead.
    pub fn projected_vertical(&self, p: DVec3, dz: f64) -> f64 {
        match (self.pixel_of(p), self.pixel_of(p + DVec3::Z * dz)) {
            (Some(a), Some(b)) => a.distance(b),
            _ => dz.abs() * self.perspective_scale / p.length().max(1e-3),
        }
    }

    fn pixel_of(&self, p: DVec3) -> Option<DVec2> {
        let clip: DVec4 = self.view_projection * p.extend(1.0);
        (clip.w > 1e-6).then(|| {
            let ndc = DVec2::new(clip.x, clip.y) / clip.w;
            (ndc + 1.0) * 0.5 * DVec2::new(self.viewport[0] as f64, self.viewport[1] as f64)
        })
    }
}

/// One view's measurement; buffers are kept between views.
#[derive(Clone, Debug, Default)]
pub struct ViewErrors {
    /// Per pixel (row-major from the top left): the error in pixels where
    /// both images show terrain, NaN elsewhere.
    pub errors_px: Vec<f32>,
    /// Pixels where both show terrain (and the error was measured).
    pub terrain_pixels: usize,
    /// Pixels with terrain in one image only where the other surface exists
    /// at the ground point shown: a silhouette moved by the surface's error,
    /// which is measured there (in `errors_px`).
    pub silhouette: usize,
    /// Terrain in the LOD image only, over ground without data: a coverage
    /// mismatch.
    pub lod_only: usize,
    /// Terrain in the truth image only, over ground no drawn tile covers
    /// with data: a coverage mismatch.
    pub truth_only: usize,
    /// Terrain pixels whose full-resolution ground point no drawn tile
    /// covers (a hole in the LOD surface; their error is the LOD side's).
    pub holes: usize,
    /// Terrain pixels whose full-resolution ground point a drawn tile covers
    /// without data (it drops the triangle there): a coverage difference at
    /// the data's edge, counted with the coverage mismatch.
    pub no_data: usize,
    /// Terrain pixels (in both images) where the LOD image shows a skirt
    /// (a crack between tiles filled), and the largest error elsewhere.
    pub skirt_pixels: usize,
    /// Largest error, pixels, over terrain pixels that are not on a skirt.
    pub max_surface_px: f64,
    /// The skirt pixel with the largest error (row-major index, error in
    /// pixels), to probe ([`crate::accuracy::SkirtProbe`]).
    pub worst_skirt: Option<(usize, f32)>,
    /// A pixel where the truth shows terrain the LOD does not draw (the
    /// last in row order: the nearest, low in the view), to probe ([`crate::accuracy::CoverageProbe`]).
    pub truth_only_pixel: Option<usize>,
    /// Per LOD terrain pixel off skirts, |drawn height - the CPU mirror's
    /// height| in metres (NaN elsewhere): near 0, a check that the mirror
    /// measures what the GPU drew.
    pub mirror_m: Vec<f32>,
}

#[derive(Clone, Copy, Default)]
struct Counts {
    terrain: usize,
    silhouette: usize,
    lod_only: usize,
    truth_only: usize,
    holes: usize,
    no_data: usize,
    skirt: usize,
    max_surface: f64,
    worst_skirt: Option<(usize, f32)>,
    truth_only_pixel: Option<usize>,
}

impl Counts {
    /// A silhouette pixel `k` with error `px`, written to its `error`.
    fn silhouette(&mut self, k: usize, error: &mut f32, px: f64, skirt: bool) {
        self.silhouette += 1;
        *error = px as f32;
        self.terrain_error(k, *error, skirt);
    }

    /// Pixel `k`'s error, counted against skirts or the surface.
    fn terrain_error(&mut self, k: usize, error: f32, skirt: bool) {
        if skirt {
            self.skirt += 1;
            if self.worst_skirt.is_none_or(|(_, e)| error > e) {
                self.worst_skirt = Some((k, error));
            }
        } else {
            self.max_surface = self.max_surface.max(error as f64);
        }
    }
}

impl std::ops::Add for Counts {
    type Output = Counts;
    fn add(self, o: Counts) -> Counts {
        Counts {
            terrain: self.terrain + o.terrain,
            silhouette: self.silhouette + o.silhouette,
            lod_only: self.lod_only + o.lod_only,
            truth_only: self.truth_only + o.truth_only,
            holes: self.holes + o.holes,
            no_data: self.no_data + o.no_data,
            skirt: self.skirt + o.skirt,
            max_surface: self.max_surface.max(o.max_surface),
            worst_skirt: match (self.worst_skirt, o.worst_skirt) {
                (Some(a), Some(b)) => Some(if b.1 > a.1 { b } else { a }),
                (a, b) => a.or(b),
            },
            truth_only_pixel: o.truth_only_pixel.or(self.truth_only_pixel),
        }
    }
}

/// Measures one view: `lod` and `truth` are the position images of the LOD
/// frame and of the full-resolution mesh, `surface` the LOD frame's tiles
/// (over `staging`), `exact` the full-resolution surface.
pub fn measure_view(
    geometry: &ViewGeometry,
    lod: &PositionImage,
    truth: &PositionImage,
    surface: &LodSurface,
    staging: &[u8],
    exact: ExactHeight<'_>,
    out: &mut ViewErrors,
) {
    debug_assert_eq!(lod.size, truth.size);
    let pixels = lod.pixel_count();
    out.errors_px.clear();
    out.errors_px.resize(pixels, f32::NAN);
    out.mirror_m.clear();
    out.mirror_m.resize(pixels, f32::NAN);
    let width = (lod.size.x as usize).max(1);
    let rows =
        out.errors_px.par_chunks_mut(width).zip(out.mirror_m.par_chunks_mut(width)).enumerate();
    let pixel = Pixel { geometry, surface, staging, exact };
    let counts = rows
        .map(|(row, (errors, mirror))| {
            let mut counts = Counts::default();
            for (col, (error, mirror)) in errors.iter_mut().zip(mirror.iter_mut()).enumerate() {
                let k = row * width + col;
                match (lod.point(k), truth.point(k)) {
                    (Some(p), Some(t)) => {
                        counts.terrain += 1;
                        let lod_side = pixel.at_lod_point(p);
                        *mirror = lod_side.mirror_m;
                        let truth_side = match pixel.at_truth_point(t) {
                            TruthSide::Error(px) => px,
                            TruthSide::Hole => {
                                counts.holes += 1;
                                0.0
                            }
                            TruthSide::NoData => {
                                counts.no_data += 1;
                                0.0
                            }
                        };
                        *error = lod_side.error_px.max(truth_side) as f32;
                        counts.terrain_error(k, *error, lod_side.skirt);
                    }
                    (Some(p), None) => {
                        let lod_side = pixel.at_lod_point(p);
                        *mirror = lod_side.mirror_m;
                        if lod_side.over_data {
                            counts.silhouette(k, error, lod_side.error_px, lod_side.skirt);
                        } else {
                            counts.lod_only += 1;
                        }
                    }
                    (None, Some(t)) => match pixel.at_truth_point(t) {
                        TruthSide::Error(px) => counts.silhouette(k, error, px, false),
                        TruthSide::Hole | TruthSide::NoData => {
                            counts.truth_only += 1;
                            counts.truth_only_pixel = Some(k);
                        }
                    },
                    (None, None) => {}
                }
            }
            counts
        })
        .reduce(Counts::default, |a, b| a + b);
    out.terrain_pixels = counts.terrain;
    out.silhouette = counts.silhouette;
    out.lod_only = counts.lod_only;
    out.truth_only = counts.truth_only;
    out.holes = counts.holes;
    out.no_data = counts.no_data;
    out.skirt_pixels = counts.skirt;
    out.max_surface_px = counts.max_surface;
    out.worst_skirt = counts.worst_skirt;
    out.truth_only_pixel = counts.truth_only_pixel;
}

/// What one pixel's measurement reads.
struct Pixel<'a> {
    geometry: &'a ViewGeometry,
    surface: &'a LodSurface,
    staging: &'a [u8],
    exact: ExactHeight<'a>,
}

/// What the LOD image shows at a pixel.
struct LodSide {
    /// Error in pixels (0 where the ground is outside the data).
    error_px: f64,
    /// |drawn height - mirrored surface| in metres (NaN without a tile).
    mirror_m: f32,
    /// The pixel shows a skirt.
    skirt: bool,
    /// The full-resolution surface has data at the ground point.
    over_data: bool,
}

impl Pixel<'_> {
    /// At the ground point under the point the LOD drew. The LOD surface
    /// there is read from the mirror, not from the drawn point's height:
    /// where a ray grazes a far silhouette the interpolated point may sit
    /// 100 m along the ray from where its height belongs (the same in the
    /// truth image, bit for bit), which is no error of the surface. A skirt
    /// (on a tile edge, drawn below the surface) is measured as drawn: it is
    /// what the pixel shows.
    fn at_lod_point(&self, p: Vec3) -> LodSide {
        let p = p.as_dvec3();
        let (ground, drawn) = self.geometry.ground(p);
        let mirror = self.surface.earth_height_at(self.staging, ground.x, ground.y);
        let level = self.surface.level_at(ground.x, ground.y).unwrap_or(0);
        let tolerance = SKIRT_TOLERANCE_M + self.geometry.sag_m(level);
        let skirt = mirror.is_some_and(|m| {
            (drawn - m).abs() > tolerance && self.surface.on_tile_edge(ground.x, ground.y)
        });
        let shown = match mirror {
            Some(m) if !skirt => m,
            _ => drawn,
        };
        let truth = (self.exact)(ground.x, ground.y).map(|h| self.geometry.drawn_truth(ground, h));
        let error_px = truth.map_or(0.0, |h| self.geometry.projected_vertical(p, h - shown));
        // A skirt pixel (counted apart, above or below the mirror) is
        // measured as drawn: the mirror check is of the surface.
        let mirror_m = match mirror {
            Some(m) if !skirt => (m - drawn).abs() as f32,
            _ => f32::NAN,
        };
        LodSide { error_px, mirror_m, skirt, over_data: truth.is_some() }
    }

    /// At the point the full-resolution mesh shows: the LOD surface there
    /// against the exact one, in pixels (0 where the ground is outside the
    /// data).
    fn at_truth_point(&self, t: Vec3) -> TruthSide {
        let t = t.as_dvec3();
        let (ground, _) = self.geometry.ground(t);
        let Some(h) = (self.exact)(ground.x, ground.y) else { return TruthSide::Error(0.0) };
        match self.surface.earth_height_at(self.staging, ground.x, ground.y) {
            Some(lod) => TruthSide::Error(
                self.geometry.projected_vertical(t, lod - self.geometry.drawn_truth(ground, h)),
            ),
            None if self.surface.has_tile(ground.x, ground.y) => TruthSide::NoData,
            None => TruthSide::Hole,
        }
    }
}

/// What the LOD surface is at a point the full-resolution mesh shows.
enum TruthSide {
    /// Its error there, pixels.
    Error(f64),
    /// No drawn tile covers it: a hole in the mesh.
    Hole,
    /// A tile covers it but drops the triangle there for a post without data
    /// (a coarse tile's last cell at the data's edge): a coverage difference.
    NoData,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::DrawList;
    use glam::UVec2;

    /// Looking due north, level, from 1000 m over a flat sea at 0 m.
    fn geometry() -> (Camera, ViewGeometry) {
        let camera = Camera {
            position: DVec3::new(5000.0, 5000.0, 1000.0),
            heading_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [64, 64],
        };
        let frame = FrameUniforms {
            view_projection: camera.projection(1.0, 1e5) * camera.view(),
            camera_altitude: 1000.0,
            sun_direction: glam::Vec3::Z,
            curvature: false,
            horizon_floor_m: 0.0,
            morph_start_share: 0.7,
            warning_above_m: 0.0,
            caution_below_m: 0.0,
            viewport: camera.viewport,
            fog_distance_m: 1e5,
            posts: crate::render::PostFrame::new(camera.position.truncate(), [90.0, 90.0]),
            last_post: [1 << 20; 2],
            slices: crate::render::DepthSlices::new(&camera, 1.0, 1e5, (0.0, 0.0)),
            earth: None,
        };
        (camera, ViewGeometry::new(&camera, &frame))
    }

    #[test]
    fn a_vertical_segment_straight_ahead_projects_to_ulrichs_length() {
        let (camera, geometry) = geometry();
        let p = DVec3::new(0.0, 2000.0, 0.0);
        let expected = 10.0 * camera.perspective_scale() / 2000.0;
        assert!((geometry.projected_vertical(p, 10.0) - expected).abs() < 1e-6 * expected);
        // Behind the camera: Ulrich's formula with the distance.
        let behind = DVec3::new(0.0, -2000.0, 0.0);
        assert!((geometry.projected_vertical(behind, 10.0) - expected).abs() < 1e-9);
    }

    /// Pixel 0: the LOD drew 10 m above a flat sea at 2 km, and the truth
    /// shows the sea there: the LOD side's error is Ulrich's; with no tile
    /// under the truth's point that pixel is also a hole. Pixel 1: the LOD
    /// shows terrain 5 m above the sea at 2.2 km where the truth's ray
    /// passed over it: a silhouette, measured. Pixel 2: the LOD shows
    /// terrain past the data's edge (y beyond 7500 m): a coverage mismatch.
    /// Pixel 3: the truth shows terrain no tile covers: a coverage mismatch.
    #[test]
    fn errors_holes_and_mismatches_of_synthetic_images() {
        let (camera, geometry) = geometry();
        let image = |points: [Option<[f32; 3]>; 4]| PositionImage {
            size: UVec2::new(4, 1),
            texels: points.iter().map(|p| p.map_or([0.0; 4], |[x, y, z]| [x, y, z, 1.0])).collect(),
        };
        let lod = image([
            Some([0.0, 2000.0, -990.0]),
            Some([0.0, 2200.0, -995.0]),
            Some([0.0, 3000.0, -1000.0]),
            None,
        ]);
        let truth = image([Some([0.0, 2000.0, -1000.0]), None, None, Some([0.0, 2000.0, -1000.0])]);
        let surface = LodSurface::new(&DrawList::default(), &[], 32, [90.0, 90.0], DVec2::ZERO);
        let sea = |_: f64, y: f64| (y < 7500.0).then_some(0.0f32);
        let mut out = ViewErrors::default();
        measure_view(&geometry, &lod, &truth, &surface, &[], &sea, &mut out);
        let expected = 10.0 * camera.perspective_scale() / 2000.0;
        assert!(
            (out.errors_px[0] as f64 - expected).abs() < 1e-3,
            "{} vs {expected}",
            out.errors_px[0]
        );
        let silhouette = 5.0 * camera.perspective_scale() / 2200.0;
        assert!((out.errors_px[1] as f64 - silhouette).abs() < 1e-3, "{}", out.errors_px[1]);
        assert!(out.errors_px[2].is_nan() && out.errors_px[3].is_nan());
        let counts = (out.terrain_pixels, out.silhouette, out.lod_only, out.truth_only, out.holes);
        assert_eq!(counts, (1, 1, 1, 1, 1));
    }
}
