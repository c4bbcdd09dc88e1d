//! The accuracy tool's measurements: how far, in pixels, the surface the LOD
//! display draws lies from the full-resolution surface, per pixel, over a
//! set of views; the statistics of that error; and its heat map.
//!
//! **What is measured, and why.** Ulrich's bound promises that a tile's
//! geometric error (a vertical distance `delta` between its surface and the
//! full-resolution one) projects to at most tau pixels. The measurable
//! counterpart is, at each pixel, the vertical distance between the two
//! surfaces at the ground point that pixel shows, projected to the screen
//! at that point: the on-screen length of the segment from one surface to the
//! other. It is taken from both sides (`pixel_error`), at the ground point
//! the LOD image shows and at the one the full-resolution image shows; the
//! LOD surface there is read from a CPU mirror of the drawn tiles
//! ([`LodSurface`], checked against the drawn points), except where the
//! LOD image shows a skirt, which is measured as drawn; the pixel's error is
//! the larger. Measuring only the LOD's own points would miss a ridge the LOD
//! drew too low, because the LOD image then shows the ground behind it.
//! Distances between the two images' hit points are not used: along grazing
//! rays a millimetre of height moves the hit point kilometres, which is no
//! error of the surface.
//!
//! **Coverage.** Where only one image shows terrain, the pixel is a
//! *silhouette* when the other surface exists at the ground point shown (a
//! ridge drawn a little higher passes the other ray over it): its error is
//! measured there as above, so a silhouette moved by more than tau counts
//! against the bound. It is a *coverage mismatch* when the other surface has
//! nothing there: terrain drawn past the data's edge, or data not drawn.
//! Coverage mismatches are reported as a share of all pixels.
//!
//! **Against the earth.** That measure compares the display with the full
//! resolution drawn in the display's own frame: it sees the LOD's error
//! only. The *geodetic truth* (`earth_*`) is independent of the display's
//! geometry: each pixel's ray from the true camera pose, cast in ECEF
//! against the best data on the WGS 84 ellipsoid, and the display's error
//! against it measured by where places are on the screen
//! ([`measure_earth`] says exactly how), so that a surface drawn in the
//! wrong place is caught, not only one drawn at the wrong height.
//!
//! | file | owns |
//! |---|---|
//! | `positions` | [`PositionImage`]: a camera-relative surface point per pixel, read back from the GPU |
//! | `lod_surface` | [`LodSurface`]: the drawn LOD surface evaluated on the CPU, morph included |
//! | `tile_triangles` | the drawn tiles' surface triangles from their blocks, by cell, for `lod_surface` |
//! | `pixel_error` | [`measure_view`]: per-pixel error and coverage of one view |
//! | `ray_truth` | [`trace_truth`]: the full-resolution image by each pixel's ray on the CPU, where the mesh is too large to draw |
//! | `skirt_probe` | [`SkirtProbe`]: the tile and edge whose skirt a pixel shows, and what decided it |
//! | `summary` | [`ErrorSummary`]: percentiles over all views |
//! | `verdict` | [`Verdict`]: the bound and the coverage per view the accuracy tool confirms or not |
//! | `heat_map` | the error image of a view as colours |
//! | `earth_ground` | [`EarthGround`]: the best data on the ellipsoid, with the bounds rays skip by |
//! | `earth_rays` | [`TrueCamera`] and [`trace_earth`]: the geodetic truth's image, each pixel's ray in ECEF |
//! | `earth_error` | [`measure_earth`]: the display's error against the geodetic truth, and the [`DisplayFrame`] it reads the display in |

mod earth_error;
mod earth_ground;
mod earth_rays;
mod heat_map;
mod lod_surface;
mod pixel_error;
mod positions;
mod ray_truth;
mod skirt_probe;
mod summary;
mod tile_triangles;
mod verdict;

pub use earth_error::{measure_earth, DisplayFrame, EarthErrors, EarthView};
pub use earth_ground::EarthGround;
pub use earth_rays::{trace_earth, trace_ray, EarthHit, EarthImage, TrueCamera};
pub use heat_map::{heat_map, HEAT_MISMATCH, HEAT_SKY};
pub use lod_surface::LodSurface;
pub use pixel_error::{measure_view, ExactHeight, ViewErrors, ViewGeometry};
pub use positions::PositionImage;
pub use ray_truth::{trace_truth, RayGround, HIT_TOLERANCE_M};
pub use skirt_probe::{CoverageProbe, SkirtProbe};
pub use summary::{percentile, ErrorSummary};
pub use verdict::{MismatchedView, Verdict, VerdictError, MISMATCH_PER_VIEW};
