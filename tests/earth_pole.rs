//! The geodetic truth's rays near a pole: over a polar cap (a geographic
//! grid from 80 S to the pole, every longitude), from 89.9 S looking across
//! the pole, every traced ray's hit lies on the surface and no ray steps over
//! the ground before its hit (an independent march in 2 m steps checks it).
//! Near the pole a ray crosses thousands of converging meridians in a few
//! hundred metres; the rows' bounds (`EarthGround::rows_top`) let it skip
//! them where it is clear of every row it can reach.

use glam::{DVec2, DVec3};
use ridgeline::accuracy::{trace_earth, EarthGround, EarthImage, TrueCamera};
use ridgeline::camera::Camera;
use ridgeline::earth::GridPlacement;
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::node::{cell_surface, NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// A plateau near 2800 m with swells of 7 and 9 km, a function of the
/// place (ECEF), so the pole row's posts, all one place, agree.
struct PolarCap {
    layout: NodeLayout,
    placement: GridPlacement,
}

impl PolarCap {
    fn new() -> PolarCap {
        let posts = [7201, 201];
        let georef = GeoRef { crs: Crs::Geographic, origin: [0.0, -90.0], spacing: [0.05; 2] };
        let layout = NodeLayout {
            levels: NodeLayout::levels_for(posts, 64),
            node_size: 64,
            border: 1,
            posts,
            spacing_m: georef.spacing_m(posts),
        };
        let placement = GridPlacement::new(&georef, posts, layout.spacing_m);
        PolarCap { layout, placement }
    }

    fn post(&self, i: i64, j: i64) -> f32 {
        let last = self.layout.posts.map(|p| p as i64 - 1);
        let p = self.placement.ecef(i.clamp(0, last[0]) as f64, j.clamp(0, last[1]) as f64, 0.0);
        (2800.0 + 60.0 * (p.x / 7_000.0).sin() * (p.y / 9_000.0).cos()) as f32
    }

    /// The surface at post `(u, v)`: posts joined south-west to north-east.
    fn surface(&self, u: f64, v: f64) -> f64 {
        let period = self.layout.posts[0] as f64 - 1.0;
        let u = u.rem_euclid(period);
        let (i, j) = (u.floor(), v.floor().min(self.layout.posts[1] as f64 - 2.0));
        let h = |di: f64, dj: f64| self.post((i + di) as i64, (j + dj) as i64) as f64;
        cell_surface(h(0., 0.), h(1., 0.), h(0., 1.), h(1., 1.), u - i, v - j)
    }
}

impl NodeSource for PolarCap {
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

/// The ray's height above the cap's surface at `p` (ECEF).
fn above(cap: &PolarCap, p: DVec3) -> f64 {
    let (post, height) = cap.placement.post_of_ecef(p);
    height - cap.surface(post[0], post[1])
}

#[test]
fn rays_across_the_pole_meet_the_surface_and_step_over_nothing() {
    let cap = PolarCap::new();
    let [x, y] = cap.placement.chart_of_geodetic((-89.9f64).to_radians(), 0.0);
    for heading in [180.0, 135.0] {
        let camera = Camera {
            position: DVec3::new(x, y, 4500.0),
            heading_deg: heading,
            pitch_deg: -5.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [320, 180],
        };
        let truth = TrueCamera::new(&camera, &cap.placement);
        let ground = EarthGround::load(&cap, cap.placement, &[truth.eye], 300_000.0).unwrap();
        let mut image = EarthImage::default();
        trace_earth(&truth, &ground, 16, 300_000.0, &mut image);
        let hits = image.hits.iter().flatten().count();
        println!("heading {heading}: {hits} hits of {}, {} steps", image.hits.len(), image.steps);
        assert!(hits > image.hits.len() / 2, "most rays look down on the plateau");
        for (k, hit) in image.hits.iter().enumerate() {
            let [col, row] = image.pixel(k);
            let dir = truth.ray(DVec2::new(col as f64 + 0.5, row as f64 + 0.5));
            let end = match hit {
                Some(hit) => {
                    let off = above(&cap, hit.point);
                    assert!(
                        off.abs() < 0.05,
                        "pixel {col},{row}: the hit is {off} m off the surface"
                    );
                    hit.point.distance(truth.eye)
                }
                None => 150_000.0,
            };
            let mut s = 0.0;
            while s < end - 0.5 {
                let off = above(&cap, truth.eye + dir * s);
                assert!(off > -0.05, "pixel {col},{row}: under the ground {off} m at {s} m");
                s += 2.0;
            }
        }
    }
}
