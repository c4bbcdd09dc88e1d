//! The valid life on the ellipsoid (issue 26): over a global grid, a flight
//! north from 60 N to 64 N selects with kept split tests exactly what a
//! full re-evaluation selects, frame by frame. The chart's north-south
//! scale is the equator's (110.57 km a degree), the earth's at 60-64 N is
//! 111.4 km, so chart travel understates the real travel by 0.8 %; and the
//! selector's boxes are in the camera's axes, which turn with the eye
//! (about 1.6e-4 rad a kilometre), moving far boxes by more than the eye
//! moved. A valid life that measured the eye's travel in the chart, and
//! only its travel, kept stale tests here.

use glam::DVec3;
use ridgeline::camera::{Camera, Frustum};
use ridgeline::earth::{EarthFrame, GridPlacement};
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::lod::select::{EarthView, SelectedTile, TileBounds, View};
use ridgeline::lod::{LevelRings, LodConfig, TileKey, TileSelector};
use ridgeline::node::NodeLayout;
use ridgeline::scene::ring_inputs;

/// A global grid of 30" posts (0 to 360 degrees, closed), heights 0 to
/// 2000 m everywhere, finer data under every tile.
struct Globe {
    layout: NodeLayout,
    placement: GridPlacement,
}

impl Globe {
    fn new() -> Globe {
        let posts = [43_201, 21_601];
        let georef =
            GeoRef { crs: Crs::Geographic, origin: [0.0, -90.0], spacing: [1.0 / 120.0; 2] };
        let spacing_m = georef.spacing_m(posts);
        let layout = NodeLayout {
            levels: NodeLayout::levels_for(posts, 256),
            node_size: 256,
            border: 1,
            posts,
            spacing_m,
        };
        Globe { layout, placement: GridPlacement::new(&georef, posts, spacing_m) }
    }
}

impl TileBounds for Globe {
    fn posts(&self) -> [u32; 2] {
        self.layout.posts
    }
    fn spacing_m(&self) -> [f64; 2] {
        self.layout.spacing_m
    }
    fn height_bounds(&self, _: TileKey, _: u32) -> (f32, f32) {
        (0.0, 2000.0)
    }
    fn has_finer_data(&self, tile: TileKey, _: u32) -> bool {
        tile.level > 0
    }
}

/// The tiles `selector` picks for `camera` on the ellipsoid.
fn select(selector: &mut TileSelector, globe: &Globe, camera: &Camera) -> Vec<SelectedTile> {
    let lod = *selector.config();
    let deltas: Vec<f64> = (0..globe.layout.levels).map(|l| 4.0 * (1u64 << l) as f64).collect();
    let inputs = ring_inputs(&globe.layout, lod.grid_size, &deltas, 2000.0, camera);
    let rings = LevelRings::new(&lod, inputs);
    let frustum = Frustum::from_view_projection(camera.projection(1.0, 600_000.0) * camera.view());
    let frame = EarthFrame::new(&globe.placement, camera.position, [0, 0]).expect("placed");
    let view = View {
        eye: camera.position,
        frustum: &frustum,
        rings: &rings,
        curvature: true,
        horizon: None,
        earth: Some(EarthView { frame, horizon: None }),
    };
    selector.select(&view, globe).to_vec()
}

/// The flight: 300 frames north from 60 N at 1 km of chart a frame, 4000 m
/// up, heading north, looking 4 degrees down.
fn flight(globe: &Globe) -> Vec<Camera> {
    let [x, y] = globe.placement.chart_of_geodetic(60f64.to_radians(), 30f64.to_radians());
    let heading = 0f64.to_radians();
    (0..300)
        .map(|k| Camera {
            position: DVec3::new(
                x + 1000.0 * k as f64 * heading.sin(),
                y + 1000.0 * k as f64 * heading.cos(),
                4000.0,
            ),
            heading_deg: 0.0,
            pitch_deg: -4.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [1280, 720],
        })
        .collect()
}

/// Flies `cameras` with a full re-evaluation and with a valid life of
/// declared travel `travel_m`; the share of tests the life kept.
fn fly(globe: &Globe, cameras: &[Camera], travel_m: f64) -> f64 {
    let config = LodConfig::default();
    let mut full = TileSelector::new(config);
    let mut life = TileSelector::new(LodConfig { max_travel_m: Some(travel_m), ..config });
    let (mut tested, mut candidates) = (0u64, 0u64);
    for (frame, camera) in cameras.iter().enumerate() {
        let expected = select(&mut full, globe, camera);
        let got = select(&mut life, globe, camera);
        assert_eq!(got, expected, "frame {frame}: a kept split test went stale");
        let stats = life.life_stats().expect("a valid life");
        tested += stats.re_evaluated as u64;
        candidates += stats.candidates as u64;
    }
    1.0 - tested as f64 / candidates as f64
}

/// The most the eye moves on the earth between two frames, metres.
fn earth_travel(globe: &Globe, cameras: &[Camera]) -> f64 {
    let ecef = |c: &Camera| {
        let (lat, lon) = globe.placement.geodetic_of_chart([c.position.x, c.position.y]);
        ridgeline::earth::ellipsoid::to_ecef(lat, lon, c.position.z)
    };
    cameras.windows(2).map(|w| ecef(&w[0]).distance(ecef(&w[1]))).fold(0.0, f64::max)
}

/// Declared travel as the chart measures it (1 km a frame): the earth's
/// travel is 0.8 % more, so every frame re-tests everything, and the
/// selection stays exact.
#[test]
fn chart_travel_understating_the_earths_keeps_no_stale_test() {
    let globe = Globe::new();
    let cameras = flight(&globe);
    let real = earth_travel(&globe, &cameras);
    assert!(real > 1000.0 * 1.005, "the earth's travel {real} m is over the chart's 1000 m");
    let kept = fly(&globe, &cameras, 1000.0 * 1.001);
    println!("declared in the chart: kept {:.1} % of split tests", 100.0 * kept);
}

/// Declared travel as the earth measures it: tests are kept, and none goes
/// stale although far boxes move more than the eye as its axes turn.
#[test]
fn earth_travel_keeps_tests_and_none_goes_stale() {
    let globe = Globe::new();
    let cameras = flight(&globe);
    let travel = earth_travel(&globe, &cameras) * 1.001;
    let kept = fly(&globe, &cameras, travel);
    println!("declared on the earth ({travel:.1} m): kept {:.1} % of split tests", 100.0 * kept);
    assert!(kept > 0.3, "the valid life kept only {:.1} % of tests", 100.0 * kept);
}
