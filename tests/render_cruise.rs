//! The cruise over a global grid shows no no-data hatching below the
//! horizon (issue 21). A bathymetric grid keeps its sea floor (here 4 km
//! down); its horizon, seen level from 10 km, lies about 0.8 degrees below
//! the sea level's. The sky pass drew the no-data hatching below the sea
//! level's horizon, so every ray between the two (which passes over all the
//! terrain there is) showed as a band of hatching 10 to 17 px tall across
//! the screen. Over a grid that covers the earth it now draws them as sky
//! (`scene::horizon_floor_m`).
//!
//! A synthetic quarter-degree grid around the whole earth, sea floor with a
//! continent, is flown level at 10 km over the ocean at 30 N, at 60 N
//! looking north, and across the antimeridian; in every 8th column no
//! pixel below the geometric horizon (the topmost row whose ray meets the
//! WGS 84 ellipsoid, solved in f64 from the true camera) is hatching.

use std::sync::Arc;

use glam::DVec3;
use ridgeline::accuracy::TrueCamera;
use ridgeline::camera::Camera;
use ridgeline::dem::ElevationGrid;
use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::earth::GridPlacement;
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::gl::{GlBackend, GlesVersion};
use ridgeline::pyramid::{BuildOptions, Pyramid};
use ridgeline::scene::{horizon_floor_m, TerrainSummary};
use testkit::gl::take_turn;
use testkit::render::is_hatching;

const VIEWPORT: [u32; 2] = [640, 360];
const FOV_X_DEG: f64 = 60.0;
const SPACING_DEG: f64 = 0.25;
/// 360 degrees with a closing column, pole to pole.
const POSTS: [u32; 2] = [1441, 721];
const ALTITUDE_M: f64 = 10_000.0;

/// Sea floor about 4 km down, with low relief, and one continent (up to
/// 2 km) centred on 45 N 100 E, far from every view.
fn height(lon: f64, lat: f64) -> f32 {
    let floor = -4000.0 + 250.0 * (lon.to_radians() * 7.0).sin() * (lat.to_radians() * 5.0).cos();
    let d = ((lon - 100.0) / 30.0).powi(2) + ((lat - 45.0) / 20.0).powi(2);
    let land = if d < 1.0 { 6000.0 * (1.0 - d) } else { 0.0 };
    (floor + land) as f32
}

fn globe() -> Arc<Pyramid> {
    let origin = [-180.0, -90.0];
    let georef = GeoRef { crs: Crs::Geographic, origin, spacing: [SPACING_DEG; 2] };
    let heights = (0..POSTS[0] * POSTS[1])
        .map(|k| {
            let (u, v) = ((k % POSTS[0]) as f64, (k / POSTS[0]) as f64);
            height(origin[0] + u * SPACING_DEG, origin[1] + v * SPACING_DEG)
        })
        .collect();
    let grid =
        ElevationGrid { width: POSTS[0], height: POSTS[1], heights, georef, voids_filled: 0 };
    let dir = testkit::fresh_dir("cruise-globe");
    testkit::pyramid::build_and_write(&grid, BuildOptions::default(), &dir);
    Arc::new(Pyramid::open(&dir).expect("the globe's pyramid"))
}

/// Pixels below the geometric horizon that show the no-data hatching,
/// seen level from 10 km at `lat`, `lon`, heading `heading_deg`; and the
/// rows between the horizon and the topmost hatching (0: none).
fn hatching_below_horizon(
    pyramid: &Arc<Pyramid>,
    (lat, lon): (f64, f64),
    heading_deg: f64,
) -> (usize, u32) {
    let info = pyramid.info();
    let layout = info.layout;
    let placement = GridPlacement::new(&info.georef, layout.posts, layout.spacing_m);
    assert!(placement.covers_the_earth(), "the test grid covers the earth");
    let mut config = DisplayConfig {
        version: GlesVersion::Es3,
        fov_x_deg: FOV_X_DEG,
        ..DisplayConfig::new(GlBackend::Egl, VIEWPORT.into())
    };
    config.scene.earth = Some(placement);
    let summary = TerrainSummary::from_pyramid(info);
    let mut display = DisplayParts::open(&config, pyramid.clone(), summary).expect("EGL display");
    let post = [(lon + 180.0) / SPACING_DEG, (lat + 90.0) / SPACING_DEG];
    let camera = Camera {
        position: DVec3::new(
            post[0] * layout.spacing_m[0],
            post[1] * layout.spacing_m[1],
            ALTITUDE_M,
        ),
        heading_deg,
        pitch_deg: 0.0,
        roll_deg: 0.0,
        fov_x_deg: FOV_X_DEG,
        viewport: VIEWPORT,
    };
    display.pipeline.settle(&camera, 10_000).expect("settle");
    display.frame(&camera).expect("frame");
    let image = display.context.read_pixels().expect("read back");
    let eye = TrueCamera::new(&camera, &placement);
    let (mut pixels, mut band) = (0, 0);
    for column in (4..VIEWPORT[0]).step_by(8) {
        let horizon = testkit::render::geometric_horizon_row(&eye, column, VIEWPORT[1])
            .expect("the earth is in view");
        let hatched: Vec<u32> = (horizon..VIEWPORT[1])
            .filter(|&row| is_hatching(image.get_pixel(column, row).0))
            .collect();
        pixels += hatched.len();
        if let (Some(first), Some(last)) = (hatched.first(), hatched.last()) {
            band = band.max(last - first + 1);
        }
    }
    (pixels, band)
}

#[test]
fn the_cruise_over_a_global_grid_shows_no_hatching_below_the_horizon() {
    let _turn = take_turn();
    let pyramid = globe();
    let views = [
        ("30 N, east over the ocean", (30.0, -40.0), 90.0),
        ("60 N, north over the ocean", (60.0, -30.0), 0.0),
        ("across the antimeridian", (0.0, 179.8), 90.0),
    ];
    for (name, place, heading) in views {
        let (pixels, band) = hatching_below_horizon(&pyramid, place, heading);
        println!("{name}: {pixels} hatched pixels below the horizon (band {band} rows)");
        assert_eq!(pixels, 0, "{name}: no-data hatching below the horizon, {band} rows tall");
    }
}

/// Past a regional grid's edge the terrain is unknown and may be at sea
/// level, so only a grid around the whole earth lowers the sky's horizon.
#[test]
fn only_a_grid_that_covers_the_earth_lowers_the_horizon_floor() {
    let spacing = [SPACING_DEG; 2];
    let place = |origin: [f64; 2], posts: [u32; 2]| {
        let georef = GeoRef { crs: Crs::Geographic, origin, spacing };
        GridPlacement::new(&georef, posts, [27_800.0; 2])
    };
    let globe = place([-180.0, -90.0], POSTS);
    let band = place([-180.0, -60.0], [POSTS[0], 481]);
    let region = place([30.0, 30.0], [65, 33]);
    assert_eq!(horizon_floor_m(Some(&globe), -4000.0), -4000.0);
    assert_eq!(horizon_floor_m(Some(&globe), 120.0), 0.0, "never above sea level");
    assert_eq!(horizon_floor_m(Some(&band), -4000.0), 0.0, "60 S to 60 N leaves the poles unknown");
    assert_eq!(horizon_floor_m(Some(&region), -4000.0), 0.0);
    assert_eq!(horizon_floor_m(None, -4000.0), 0.0, "the chart");
    assert_eq!(horizon_floor_m(Some(&globe), f32::NAN), 0.0);
}
