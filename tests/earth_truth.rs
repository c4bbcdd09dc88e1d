//! The geodetic truth (`accuracy::trace_earth`, `accuracy::measure_earth`)
//! is independent of the display's geometry: it sees what the local planar
//! frame (equirectangular at the grid's centre latitude, the earth's
//! curvature as `d^2 / 2R`) gets wrong away from the centre latitude, and
//! reads next to nothing where that frame is right. GL-free: the planar
//! display's picture is the full resolution drawn in its frame, by rays
//! (`accuracy::trace_truth`), so its LOD error is zero and all that is
//! measured is the frame.

use glam::{DVec2, DVec3};
use ridgeline::accuracy::{
    measure_earth, trace_earth, trace_ray, trace_truth, DisplayFrame, EarthErrors, EarthGround,
    EarthImage, EarthView, ErrorSummary, PositionImage, RayGround, TrueCamera, ViewGeometry,
};
use ridgeline::camera::Camera;
use ridgeline::earth::GridPlacement;
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::node::{cell_surface, NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use ridgeline::render::{DepthSlices, FrameUniforms, PostFrame};

/// Smooth hills on a geographic grid, computed post by post (or a flat
/// sea at 0 m).
struct Hills {
    layout: NodeLayout,
    georef: GeoRef,
    flat: bool,
}

impl Hills {
    fn new(origin: [f64; 2], spacing_deg: f64, posts: [u32; 2]) -> Hills {
        let georef = GeoRef { crs: Crs::Geographic, origin, spacing: [spacing_deg; 2] };
        let layout = NodeLayout {
            levels: NodeLayout::levels_for(posts, 64),
            node_size: 64,
            border: 1,
            posts,
            spacing_m: georef.spacing_m(posts),
        };
        Hills { layout, georef, flat: false }
    }

    fn placement(&self) -> GridPlacement {
        GridPlacement::new(&self.georef, self.layout.posts, self.layout.spacing_m)
    }

    fn post(&self, i: i64, j: i64) -> f32 {
        if self.flat {
            return 0.0;
        }
        let last = self.layout.posts.map(|p| p as i64 - 1);
        let (i, j) = (i.clamp(0, last[0]) as f64, j.clamp(0, last[1]) as f64);
        let (x, y) = (i * self.layout.spacing_m[0], j * self.layout.spacing_m[1]);
        (700.0 + 500.0 * (x / 7_000.0).sin() * (y / 9_000.0).cos() + 200.0 * (x / 2_300.0).cos())
            as f32
    }

    /// The exact surface at a chart point: posts joined south-west to north-east.
    fn exact(&self, x: f64, y: f64) -> Option<f32> {
        let [sx, sy] = self.layout.spacing_m;
        let (u, v) = (x / sx, y / sy);
        let last = self.layout.posts.map(|p| (p - 1) as f64);
        if !(0.0..=last[0]).contains(&u) || !(0.0..=last[1]).contains(&v) {
            return None;
        }
        let (i, j) = (u.floor().min(last[0] - 1.0), v.floor().min(last[1] - 1.0));
        let h = |di: f64, dj: f64| self.post((i + di) as i64, (j + dj) as i64) as f64;
        Some(cell_surface(h(0., 0.), h(1., 0.), h(0., 1.), h(1., 1.), u - i, v - j) as f32)
    }
}

impl NodeSource for Hills {
    fn layout(&self) -> &NodeLayout {
        &self.layout
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        let side = self.layout.stored_side() as i64;
        let (span, stride) = (self.layout.span(id.level) as i64, 1i64 << id.level);
        let border = self.layout.border as i64;
        out.heights.clear();
        for b in 0..side {
            for a in 0..side {
                let i = id.x as i64 * span + (a - border) * stride;
                let j = id.y as i64 * span + (b - border) * stride;
                out.heights.push(self.post(i, j));
            }
        }
        out.min = out.heights.iter().copied().fold(f32::INFINITY, f32::min);
        out.max = out.heights.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        Ok(())
    }
}

/// The planar display's full-resolution picture of `camera`'s view, its
/// frame, and its drawn surface as a function of the chart point.
fn planar_view(hills: &Hills, camera: &Camera) -> (PositionImage, FrameUniforms, ViewGeometry) {
    let frame = FrameUniforms {
        view_projection: camera.projection(1.0, 400_000.0) * camera.view(),
        camera_altitude: camera.position.z,
        sun_direction: glam::Vec3::Z,
        curvature: true,
        horizon_floor_m: 0.0,
        morph_start_share: 0.7,
        warning_above_m: 0.0,
        caution_below_m: 0.0,
        viewport: camera.viewport,
        fog_distance_m: 4e5,
        posts: PostFrame::new(camera.position.truncate(), hills.layout.spacing_m),
        last_post: hills.layout.posts.map(|p| p as i64 - 1),
        slices: DepthSlices::new(camera, 1.0, 4e5, (0.0, 1500.0)),
        earth: None,
    };
    let geometry = ViewGeometry::new(camera, &frame);
    let exact = |x: f64, y: f64| hills.exact(x, y);
    let ground = RayGround {
        exact: &exact,
        slope: 0.6,
        top_m: 1400.0,
        spacing_m: hills.layout.spacing_m[0].min(hills.layout.spacing_m[1]),
    };
    let mut image = PositionImage::default();
    trace_truth(&geometry, &ground, &mut image);
    (image, frame, geometry)
}

/// The planar display's error against the geodetic truth over a view from
/// `(lat, lon)` at 2500 m, heading `heading`, and the traced pixels' count.
fn planar_error(hills: &Hills, lat: f64, lon: f64, heading: f64) -> (ErrorSummary, EarthErrors) {
    let placement = hills.placement();
    let [x, y] = placement.chart_of_geodetic(lat.to_radians(), lon.to_radians());
    let camera = Camera {
        position: DVec3::new(x, y, 2500.0),
        heading_deg: heading,
        pitch_deg: -4.0,
        roll_deg: 0.0,
        fov_x_deg: 60.0,
        viewport: [256, 144],
    };
    let (lod, frame, geometry) = planar_view(hills, &camera);
    let truth_camera = TrueCamera::new(&camera, &placement);
    let ground = EarthGround::load(hills, placement, &[truth_camera.eye], 400_000.0).unwrap();
    let mut truth = EarthImage::default();
    trace_earth(&truth_camera, &ground, 2, 400_000.0, &mut truth);
    let display = DisplayFrame::planar(placement, &camera, &frame);
    let surface =
        |x: f64, y: f64| hills.exact(x, y).map(|h| geometry.drawn_truth(glam::DVec2::new(x, y), h));
    let view =
        EarthView { frame: &display, camera: &truth_camera, ground: &ground, surface: &surface };
    let mut errors = EarthErrors::default();
    measure_earth(&view, &lod, &truth, &mut errors);
    let mut values: Vec<f32> = errors.errors_px.iter().copied().filter(|e| !e.is_nan()).collect();
    (ErrorSummary::of(&mut values), errors)
}

/// Over a small grid (0.2 degrees, 22 km) the planar frame's east-west
/// scale is right to 0.2 % at its edges, and the geodetic truth reads
/// a tenth of a pixel. Over a regional
/// grid, 44.0 to 47.0 N, the frame is 2.6 % off east-west at its north end,
/// which the truth sees on every pixel as bearing error; looking north from
/// its centre latitude, only the far points off the meridian are off.
#[test]
fn the_geodetic_truth_flags_the_planar_frame_away_from_its_centre_latitude() {
    let small = Hills::new([7.4, 45.4], 0.0005, [401, 401]);
    let (right, _) = planar_error(&small, 45.5, 7.5, 30.0);
    println!("small grid, heading 30: {right:?}");
    let regional = Hills::new([6.0, 44.0], 0.005, [601, 601]);
    let (centre, _) = planar_error(&regional, 45.5, 7.5, 0.0);
    println!("regional, centre latitude, heading 0: {centre:?}");
    let (north, _) = planar_error(&regional, 46.9, 6.3, 45.0);
    println!("regional, 46.9 N, heading 45: {north:?}");
    assert!(right.pixels > 2000 && centre.pixels > 2000 && north.pixels > 2000);
    assert!(right.p999_px < 0.3, "where the frame is right the truth agrees: {right:?}");
    assert!(centre.p50_px < 0.2 && centre.p999_px > 1.0, "far and off the meridian: {centre:?}");
    assert!(north.p50_px > 2.0, "the frame's east-west stretch, on every pixel: {north:?}");
}

/// The first row from the top whose pixel centre shows terrain, in column
/// `col` of a `rows`-row image, by bisection (sky above, terrain below).
fn horizon_row(rows: u32, terrain: impl Fn(u32) -> bool) -> u32 {
    let (mut sky, mut ground) = (0u32, rows - 1);
    assert!(!terrain(sky) && terrain(ground), "the horizon is in view");
    while ground - sky > 1 {
        let mid = (sky + ground) / 2;
        if terrain(mid) {
            ground = mid;
        } else {
            sky = mid;
        }
    }
    ground
}

/// A flat sea at 0 m seen level from 10 km at 60 N (a 30-degree band of a
/// global grid's latitudes): the planar display's horizon against the
/// geometric one (the geodetic truth's), column by column, looking east and
/// north, 1280 x 720 over 60 degrees. The planar display's sea is its
/// paraboloid `-d^2 / 2R` (mean radius, as its shader lowers vertices), whose
/// horizon is where rays dip by `atan(sqrt(2 h / R))`: within a pixel of the
/// earth's already (the `d^2 / 2R` model is good near the eye).
#[test]
fn a_flat_sea_from_ten_km_shows_its_horizon_where_the_earth_does() {
    let mut sea = Hills::new([0.0, 45.0], 0.05, [7201, 601]);
    sea.flat = true;
    let placement = sea.placement();
    for heading in [90.0, 0.0] {
        let [x, y] = placement.chart_of_geodetic(60f64.to_radians(), 180f64.to_radians());
        let camera = Camera {
            position: DVec3::new(x, y, 10_000.0),
            heading_deg: heading,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [1280, 720],
        };
        let truth_camera = TrueCamera::new(&camera, &placement);
        let ground = EarthGround::load(&sea, placement, &[truth_camera.eye], 600_000.0).unwrap();
        let dip = (2.0 * 10_000.0 / ridgeline::camera::EARTH_RADIUS_M).sqrt().atan();
        let half_y = (camera.fov_y() / 2.0).tan();
        let mut worst: f64 = 0.0;
        for col in (0..1280).step_by(160) {
            let earth = horizon_row(720, |row| {
                let pixel = DVec2::new(col as f64 + 0.5, row as f64 + 0.5);
                trace_ray(&truth_camera, &ground, pixel, 600_000.0).is_some()
            });
            // The planar display's horizon in this column: the pixel row
            // whose centre's ray dips below the level by `dip`.
            let x_ndc = (col as f64 + 0.5) / 640.0 - 1.0;
            let half_x = (camera.fov_x_deg.to_radians() / 2.0).tan();
            let tan_down = dip.tan() * (1.0 + (x_ndc * half_x).powi(2)).sqrt();
            let planar_edge = 360.0 * (1.0 + tan_down / half_y);
            let planar = (planar_edge - 0.5).ceil();
            worst = worst.max((earth as f64 - planar).abs());
            println!("heading {heading}, column {col}: earth row {earth}, planar row {planar}");
        }
        assert!(worst <= 1.0, "heading {heading}: {worst} px apart");
    }
}

/// Seen from outside the data and below its edge, a ray meets the data's
/// cut face (the display's curtain: no data, drawn as hatching), not the
/// surface: the truth has no terrain there, and a ray that meets the
/// surface meets it on top. Before, a ray entering the grid below the
/// edge's surface was a hit at the edge, hundreds of metres under the
/// surface drawn there, and every such pixel erred by hundreds of pixels
/// against the earth (the Grenoble DSM from 1 km south of its edge: p50
/// 218 px).
#[test]
fn a_ray_into_the_data_below_its_edge_meets_the_cut_face_not_the_surface() {
    let hills = Hills::new([5.0, 45.0], 0.002, [401, 401]);
    let placement = hills.placement();
    let camera = Camera {
        position: DVec3::new(20_000.0, -3_000.0, 900.0),
        heading_deg: 0.0,
        pitch_deg: -2.0,
        roll_deg: 0.0,
        fov_x_deg: 60.0,
        viewport: [128, 72],
    };
    let truth_camera = TrueCamera::new(&camera, &placement);
    let ground = EarthGround::load(&hills, placement, &[truth_camera.eye], 100_000.0).unwrap();
    let (mut on_top, mut cut_face) = (0, 0);
    for row in (0..72).step_by(3) {
        for col in (0..128).step_by(4) {
            let pixel = DVec2::new(col as f64 + 0.5, row as f64 + 0.5);
            let ray = truth_camera.ray(pixel);
            let Some(hit) = trace_ray(&truth_camera, &ground, pixel, 100_000.0) else {
                // No hit: sky, or the cut face. The ray's height where it
                // crosses the south edge tells which.
                let entry = (0..4000)
                    .map(|k| truth_camera.eye + ray * (k as f64 * 10.0))
                    .find(|&p| placement.post_of_ecef(p).0[1] >= 0.0);
                if let Some(p) = entry {
                    let (post, height) = placement.post_of_ecef(p);
                    let edge = ground.height(post[0], 0.0);
                    if edge.is_some_and(|z| height < z - 5.0) {
                        cut_face += 1;
                    }
                }
                continue;
            };
            let (post, height) = placement.post_of_ecef(hit.point);
            let surface = ground.height(post[0], post[1]).expect("a hit has data under it");
            assert!(
                (height - surface).abs() < 1.0,
                "pixel ({col}, {row}): hit {:.1} m off the surface at post {post:?}",
                height - surface
            );
            on_top += 1;
        }
    }
    assert!(
        on_top > 50 && cut_face > 50,
        "{on_top} rays on the surface, {cut_face} at the cut face"
    );
}
