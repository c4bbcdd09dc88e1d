//! The display on the ellipsoid puts a flat sea's horizon where the earth
//! has it (issue 26, phase B): a sea at 0 m over a geographic grid, seen
//! level from 10 km at 1280 x 720 and 60 degrees, at the built-in's
//! latitude (39.5 N) and at 60 N, looking east and north. In every 32nd
//! column the topmost row the terrain pass drew is within 1 px of the
//! topmost row whose pixel-centre ray meets the WGS 84 ellipsoid (solved
//! exactly, in f64, from the true camera): the geometric horizon, 357 km
//! away and 3.2 degrees below level. The same over a UTM grid (zone 37 N,
//! 1 km posts) seen from 250 km east of its central meridian, drawn by its
//! nodes' series (`earth::Expansion`).

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
use ridgeline::scene::TerrainSummary;
use testkit::gl::take_turn;
use testkit::render::{SENTINEL, SENTINEL_RGBA};

const VIEWPORT: [u32; 2] = [1280, 720];
const FOV_X_DEG: f64 = 60.0;
/// One arc minute between posts; 16 by 8 degrees, past the horizon
/// (357 km from 10 km) every way even at 60 N.
const SPACING_DEG: f64 = 1.0 / 60.0;
const POSTS: [u32; 2] = [961, 481];

/// A flat sea at 0 m centred on `lat_deg` N, 40.5 E, as a pyramid.
fn sea(name: &str, lat_deg: f64) -> Arc<Pyramid> {
    let origin = [40.5 - 8.0, lat_deg - 4.0];
    let georef = GeoRef { crs: Crs::Geographic, origin, spacing: [SPACING_DEG; 2] };
    flat(name, georef, POSTS)
}

/// A flat sea at 0 m over UTM zone 37 N (central meridian 39 E), 1 km
/// posts, 800 km on a side, centred 250 km east of the central meridian
/// at about 39.5 N (its grid north 1.8 degrees off true north there).
fn utm_sea(name: &str) -> Arc<Pyramid> {
    let georef = GeoRef {
        crs: Crs::Projected { epsg: Some(32637) },
        origin: [350_000.0, 3_975_000.0],
        spacing: [1000.0; 2],
    };
    flat(name, georef, [801, 801])
}

/// A flat sea at 0 m of `posts` posts placed by `georef`, as a pyramid.
fn flat(name: &str, georef: GeoRef, posts: [u32; 2]) -> Arc<Pyramid> {
    let heights = vec![0.0f32; (posts[0] * posts[1]) as usize];
    let grid =
        ElevationGrid { width: posts[0], height: posts[1], heights, georef, voids_filled: 0 };
    let dir = testkit::fresh_dir(name);
    testkit::pyramid::build_and_write(&grid, BuildOptions::default(), &dir);
    Arc::new(Pyramid::open(&dir).expect("the sea's pyramid"))
}

/// The sea seen level from 10 km at its centre, heading `heading_deg`:
/// the worst difference, rows, between the drawn and geometric horizons.
fn horizon_offset(pyramid: &Arc<Pyramid>, heading_deg: f64) -> u32 {
    let info = pyramid.info();
    let layout = info.layout;
    let placement = GridPlacement::new(&info.georef, layout.posts, layout.spacing_m);
    let mut config = DisplayConfig {
        version: GlesVersion::Es3,
        sentinel: Some(SENTINEL),
        fov_x_deg: FOV_X_DEG,
        ..DisplayConfig::new(GlBackend::Egl, VIEWPORT.into())
    };
    config.scene.earth = Some(placement);
    let summary = TerrainSummary::from_pyramid(info);
    let mut display = DisplayParts::open(&config, pyramid.clone(), summary).expect("EGL display");
    let centre = [0, 1].map(|k| (layout.posts[k] - 1) as f64 / 2.0 * layout.spacing_m[k]);
    let camera = Camera {
        position: DVec3::new(centre[0], centre[1], 10_000.0),
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
    let mut worst = 0;
    for column in (16..VIEWPORT[0]).step_by(32) {
        let drawn = (0..VIEWPORT[1]).find(|&row| image.get_pixel(column, row).0 != SENTINEL_RGBA);
        let geometric = testkit::render::geometric_horizon_row(&eye, column, VIEWPORT[1]);
        let (Some(drawn), Some(geometric)) = (drawn, geometric) else {
            panic!("column {column}: drawn horizon {drawn:?}, geometric {geometric:?}");
        };
        worst = worst.max(drawn.abs_diff(geometric));
    }
    worst
}

#[test]
fn a_flat_sea_shows_its_horizon_where_the_ellipsoid_has_it() {
    let _turn = take_turn();
    let seas = [
        ("39.5 N", sea("sea-39n", 39.5)),
        ("60 N", sea("sea-60n", 60.0)),
        ("UTM 37 N", utm_sea("sea-utm37n")),
    ];
    for (name, pyramid) in seas {
        for heading in [90.0, 0.0] {
            let offset = horizon_offset(&pyramid, heading);
            println!("{name} heading {heading}: drawn horizon within {offset} rows");
            assert!(offset <= 1, "{name} heading {heading}: {offset} rows off the ellipsoid's");
        }
    }
}
