//! Anywhere on the earth, a view is drawn as precisely as anywhere else.
//! Over the procedural earth (a local grid of 2^24 samples a side, 40 000
//! km, drawn in its chart), a view 10^7 m from the origin is as precise as
//! one next to it: tile corners are placed relative to the camera in f64 and
//! only then narrowed to f32. Over a global geographic grid drawn on the
//! WGS 84 ellipsoid (3.6" posts, 360 001 columns), at the equator, 60 N,
//! next to the antimeridian and 11 km from the north pole, every drawn
//! tile's corners as the vertex shader computes them (f32, about its node's
//! centre: `NodePlace::vertex`) are within a centimetre of the exact f64
//! point, and no place is worse than the equator's by more than a millimetre.

use glam::DVec3;
use ridgeline::clipmap::{Clipmap, ClipmapConfig, LoaderMode, ViewConfig};
use ridgeline::earth::{EarthFrame, GridPlacement};
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::lod::LodConfig;
use ridgeline::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use ridgeline::procedural::{EarthParams, ProceduralEarth};
use ridgeline::scene::{ClipmapTerrain, Scene, SceneConfig, TerrainSummary};
use std::sync::Arc;

/// Largest error, metres, of the f32 tile corners against the exact f64
/// positions for the tiles within `radius` metres of the camera, and how many
/// tiles that was.
fn corner_error(earth: &Arc<ProceduralEarth>, at: (f64, f64), radius: f64) -> (f64, usize) {
    let layout = *earth.layout();
    let summary = TerrainSummary::from_procedural(earth);
    let ground = earth.exact_height(at.0, at.1).unwrap() as f64;
    let eye = DVec3::new(at.0, at.1, ground + 900.0);
    let config = ClipmapConfig {
        atlas_bytes: None,
        atlas_slots: 4096,
        budget: 4096,
        loader: LoaderMode::Inline,
    };
    let mut clipmap = Clipmap::new(earth.clone(), config).unwrap();
    let view = ViewConfig { node_count: 14, view_distance: 5.0, load_distance: 5.5 };
    clipmap.add_view(view, eye).unwrap();
    clipmap.update().unwrap();
    let terrain = ClipmapTerrain { clipmap: &clipmap, summary: &summary };
    let lod = LodConfig { tau_px: 4.0, ..LodConfig::default() };
    let mut scene = Scene::new(SceneConfig { lod, ..SceneConfig::default() }, &terrain).unwrap();
    let camera = testkit::camera([640, 360], eye, 30.0, -10.0);
    scene.frame(&camera, &terrain).unwrap();
    let grid = lod.grid_size as f64;
    let (mut worst, mut tiles) = (0.0f64, 0);
    for tile in &scene.draw_list().tiles {
        let post = (1u64 << tile.key.level) as f64;
        for (i, j) in [(0.0, 0.0), (grid, 0.0), (0.0, grid), (grid, grid)] {
            let exact_x = (tile.key.x as f64 * grid + i) * post * layout.spacing_m[0] - eye.x;
            let exact_y = (tile.key.y as f64 * grid + j) * post * layout.spacing_m[1] - eye.y;
            if exact_x.hypot(exact_y) > radius {
                continue;
            }
            // What the vertex shader computes, in f32.
            let posts = scene.draw_list().uniforms.expect("a drawn frame").posts;
            let [x, y] = tile.post_position(&posts, i as f32, j as f32);
            worst = worst.max((x as f64 - exact_x).abs()).max((y as f64 - exact_y).abs());
            tiles += 1;
        }
    }
    (worst, tiles)
}

#[test]
fn a_view_ten_thousand_km_out_is_as_precise_as_one_at_the_origin() {
    let earth = Arc::new(
        ProceduralEarth::new(EarthParams { border: 2, ..EarthParams::earth(64, 11) }).unwrap(),
    );
    let (near, near_corners) = corner_error(&earth, (20_000.0, 20_000.0), 20_000.0);
    let (far, far_corners) = corner_error(&earth, (1e7 + 20_000.0, 1e7 + 20_000.0), 20_000.0);
    println!("corner error within 20 km: {near:.2e} m at the origin ({near_corners} corners), {far:.2e} m at 10^7 m ({far_corners})");
    assert!(near_corners > 20 && far_corners > 20, "both views see tiles");
    assert!(near < 0.01 && far < 0.01, "vertex positions within a centimetre: {near} and {far} m");
    assert!(
        far <= 2.0 * near + 1e-3,
        "10^7 m out is no worse than at the origin: {far} vs {near} m"
    );
}

/// A global grid of 0.001-degree posts (0 to 360 degrees with its closing
/// column, pole to pole), rolling hills of the post numbers.
struct Globe {
    layout: NodeLayout,
    placement: GridPlacement,
}

impl Globe {
    fn new() -> Globe {
        let georef = GeoRef { crs: Crs::Geographic, origin: [0.0, -90.0], spacing: [0.001; 2] };
        Globe::of(georef, [360_001, 180_001])
    }

    /// A UTM grid of 30 m posts, 600 km on a side, from 200 km east (3.5
    /// degrees west of the central meridian at 39 N) and `northing` north.
    fn utm(epsg: u32, northing: f64) -> Globe {
        let georef = GeoRef {
            crs: Crs::Projected { epsg: Some(epsg) },
            origin: [200_000.0, northing],
            spacing: [30.0; 2],
        };
        Globe::of(georef, [20_001, 20_001])
    }

    fn of(georef: GeoRef, posts: [u32; 2]) -> Globe {
        let spacing_m = georef.spacing_m(posts);
        let levels = NodeLayout::levels_for(posts, 64);
        let layout = NodeLayout { levels, node_size: 64, border: 1, posts, spacing_m };
        Globe { layout, placement: GridPlacement::new(&georef, posts, spacing_m) }
    }

    fn summary(&self) -> TerrainSummary {
        let deltas: Vec<f64> = (0..self.layout.levels).map(|l| 0.5 * (1u64 << l) as f64).collect();
        TerrainSummary {
            grid_delta_per_level: deltas.clone(),
            delta_per_level: deltas,
            height_range: (0.0, 400.0),
            map_errors: Default::default(),
            gapless: true,
        }
    }
}

impl NodeSource for Globe {
    fn layout(&self) -> &NodeLayout {
        &self.layout
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        let side = self.layout.stored_side() as i64;
        let (span, stride) = (self.layout.span(id.level) as i64, 1i64 << id.level);
        out.heights.clear();
        for b in 0..side {
            for a in 0..side {
                let i = (id.x as i64 * span + (a - 1) * stride) as f64;
                let j = (id.y as i64 * span + (b - 1) * stride) as f64;
                out.heights.push((200.0 + 150.0 * (i / 97.0).sin() * (j / 131.0).cos()) as f32);
            }
        }
        out.min = 0.0;
        out.max = 400.0;
        Ok(())
    }
}

/// Largest error, metres, of the f32 corners of the tiles drawn within
/// `radius` metres of a camera at `(lat, lon)` degrees, 1300 m, against the
/// exact f64 points on the ellipsoid, and how many corners that was.
fn earth_corner_error(globe: &Arc<Globe>, (lat, lon): (f64, f64), radius: f64) -> (f64, usize) {
    let [x, y] = globe.placement.chart_of_geodetic(lat.to_radians(), lon.to_radians());
    let eye = DVec3::new(x, y, 1300.0);
    let config = ClipmapConfig {
        atlas_bytes: None,
        atlas_slots: 8192,
        budget: 8192,
        loader: LoaderMode::Inline,
    };
    let mut clipmap = Clipmap::new(globe.clone(), config).unwrap();
    clipmap.set_earth(Some(globe.placement));
    let view = ViewConfig { node_count: 14, view_distance: 5.0, load_distance: 5.5 };
    clipmap.add_view(view, eye).unwrap();
    for _ in 0..3 {
        clipmap.update().unwrap();
    }
    let summary = globe.summary();
    let terrain = ClipmapTerrain { clipmap: &clipmap, summary: &summary };
    let lod = LodConfig { tau_px: 4.0, ..LodConfig::default() };
    let scene_config = SceneConfig { lod, earth: Some(globe.placement), ..SceneConfig::default() };
    let mut scene = Scene::new(scene_config, &terrain).unwrap();
    let camera = testkit::camera([640, 360], eye, 30.0, -10.0);
    scene.frame(&camera, &terrain).unwrap();
    let frame = scene.draw_list().uniforms.expect("a drawn frame");
    let earth: EarthFrame = frame.earth.expect("drawn on the ellipsoid");
    let uniforms = earth.uniforms();
    let grid = lod.grid_size as f32;
    let (mut worst, mut corners) = (0.0f64, 0);
    for tile in &scene.draw_list().tiles {
        for (i, j) in [(0.0, 0.0), (grid, 0.0), (0.0, grid), (grid, grid)] {
            let number =
                [tile.first_post[0] + i * tile.post_step, tile.first_post[1] + j * tile.post_step];
            let post = [0, 1].map(|k| (frame.posts.anchor[k] as f64) + number[k] as f64);
            let exact = earth.point(post, 0.0);
            if exact.length() > radius {
                continue;
            }
            let drawn = tile.place.vertex(&uniforms, number, 0.0).as_dvec3();
            worst = worst.max(drawn.distance(exact));
            corners += 1;
        }
    }
    (worst, corners)
}

/// A projected grid is drawn on the ellipsoid by its nodes' series
/// (`earth::Expansion`): the corners within 20 km of views near and far
/// off a UTM zone's central meridian, north and south, within a centimetre
/// of the exact inverse projection's points.
#[test]
fn a_view_over_a_utm_grid_is_as_precise_as_a_geographic_one() {
    for (epsg, northing, places) in [
        (32637, 4_000_000.0, [(39.5, 35.7), (40.2, 39.0), (38.0, 42.3)]),
        (32737, 5_600_000.0, [(-38.0, 36.0), (-36.5, 39.1), (-35.5, 42.0)]),
    ] {
        let globe = Arc::new(Globe::utm(epsg, northing));
        for place in places {
            let (error, corners) = earth_corner_error(&globe, place, 20_000.0);
            println!("EPSG:{epsg} {place:?}: {error:.2e} m over {corners} corners");
            assert!(corners > 20, "{place:?}: the view sees tiles");
            assert!(error < 0.01, "{place:?}: vertex positions within a centimetre: {error} m");
        }
    }
}

#[test]
fn a_view_anywhere_on_the_earth_is_as_precise_as_one_at_the_equator() {
    let globe = Arc::new(Globe::new());
    let (equator, equator_corners) = earth_corner_error(&globe, (0.3, 10.0), 20_000.0);
    println!("equator: {equator:.2e} m over {equator_corners} corners");
    assert!(equator_corners > 20 && equator < 0.01, "{equator} m");
    for place in [(60.0, 10.0), (-65.0, 179.99), (51.5, 359.99), (89.9, 10.0)] {
        let (error, corners) = earth_corner_error(&globe, place, 20_000.0);
        println!("{place:?}: {error:.2e} m over {corners} corners");
        assert!(corners > 20, "{place:?}: the view sees tiles");
        assert!(error < 0.01, "{place:?}: vertex positions within a centimetre: {error} m");
        assert!(error <= equator + 1e-3, "{place:?}: {error} m vs {equator} m at the equator");
    }
}
