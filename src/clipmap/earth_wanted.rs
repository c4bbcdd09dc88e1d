//! The wanted set on the ellipsoid ([`EarthMetric`]): for a grid drawn on
//! the earth (geographic, or projected by a known projection), a node is wanted when the distance from the viewer to
//! the nearest point of its footprint, on the earth, is within its level's
//! load radius, and that distance orders the memory budget. The chart
//! (equirectangular at the grid's centre latitude) overstates east-west
//! distances poleward of that latitude (twice at 60 N for a global grid,
//! without bound near a pole), so chart distances load too few fine nodes
//! east and west of the viewer, where the display's rings (measured on the
//! ellipsoid) use them. A grid that wraps is searched a turn west and east
//! too, so the nodes across its seam are wanted next to the viewer. A
//! projected grid's footprint is a rectangle in its projection's plane: its
//! nearest point is taken there (the projections placed are conformal and
//! their scale changes by under 1e-3 across a load radius in a UTM zone),
//! then placed on the ellipsoid, so its distance is the earth's, not the
//! plane's (Web Mercator's plane is twice the earth at 60 N).

use std::f64::consts::FRAC_PI_2;

use glam::DVec3;

use super::quadtree::ClippedQuadtree;
use crate::earth::{ellipsoid, normalize_longitude, GridPlacement, ProjectedLattice};
use crate::node::{NodeId, NodeLayout};

/// Distances on the ellipsoid for one grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct EarthMetric {
    placement: GridPlacement,
    lattice: Lattice,
}

/// How the metric finds a footprint's nearest point.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Lattice {
    /// Longitude and latitude of post (0, 0) and between posts, radians.
    Geographic { origin: [f64; 2], step: [f64; 2] },
    /// A projected grid: nearest in the projection's plane.
    Projected(ProjectedLattice),
}

/// The viewer of one frame on the earth.
struct Viewer {
    post: [f64; 2],
    lat: f64,
    lon: f64,
    eye: DVec3,
    ground_m: f64,
    /// The viewer's height above the ground under it.
    dz: f64,
}

impl EarthMetric {
    /// The metric of a geographic grid or one of a known projection;
    /// `None` for a grid placed by assumption (drawn in the chart, where
    /// chart distances are the display's).
    pub(crate) fn new(placement: GridPlacement) -> Option<EarthMetric> {
        let lattice = match (placement.geographic_lattice(), placement.projected_lattice()) {
            (Some((origin, step)), _) => Lattice::Geographic { origin, step },
            (None, Some(projected)) => Lattice::Projected(projected),
            (None, None) => return None,
        };
        Some(EarthMetric { placement, lattice })
    }

    /// Level-0 posts in one turn of longitude, when the grid wraps.
    pub(crate) fn period_posts(&self) -> Option<f64> {
        self.placement.period_posts()
    }

    /// Calls `want(node, distance_m)` for every node of `view`'s layers
    /// whose footprint (raised to the ground under the viewer) lies within
    /// the layer's load radius of the viewer on the earth.
    pub(crate) fn collect(
        &self,
        view: &ClippedQuadtree,
        layout: &NodeLayout,
        mut want: impl FnMut(NodeId, f64),
    ) {
        let p = view.position();
        let post = self.placement.post_of_chart([p.x, p.y]);
        let (lat, lon) = self.placement.geodetic_of_post(post[0], post[1]);
        let eye = ellipsoid::to_ecef(lat, lon, p.z);
        let viewer =
            Viewer { post, lat, lon, eye, ground_m: view.ground_m(), dz: p.z - view.ground_m() };
        for level in 0..layout.levels {
            let radius = view.load_radius_m(layout, level);
            if viewer.dz.abs() >= radius {
                continue;
            }
            let span = layout.span(level) as f64;
            let nodes = layout.nodes_at(level);
            let (lo, hi) = self.placement.post_window(viewer.post, radius * 1.01);
            let last_row = nodes[1] as f64 - 1.0;
            let rows = (lo[1] / span).floor().max(0.0)..=(hi[1] / span).floor().min(last_row);
            let rows = (*rows.start() as i64)..=(*rows.end() as i64);
            for y in rows {
                self.each_column(lo[0], hi[0], span, nodes[0], |x| {
                    let distance = self.distance_m(&viewer, span, x, y);
                    if distance < radius {
                        want(NodeId::new(level, x as u32, y as u32), distance);
                    }
                });
            }
        }
    }

    /// Calls `each(x)` for every node column holding posts `u_lo..=u_hi`
    /// (every column when the window is unbounded; for a grid that wraps,
    /// the window a turn west and east too; a column may come twice).
    fn each_column(
        &self,
        u_lo: f64,
        u_hi: f64,
        span: f64,
        columns: u32,
        mut each: impl FnMut(i64),
    ) {
        let last = columns as f64 - 1.0;
        if !(u_lo.is_finite() && u_hi.is_finite()) || u_hi - u_lo >= last * span {
            (0..columns as i64).for_each(each);
            return;
        }
        let shifts: &[f64] = match self.placement.period_posts() {
            Some(period) => &[0.0, -period, period],
            None => &[0.0],
        };
        for shift in shifts {
            let (lo, hi) = (u_lo + shift, u_hi + shift);
            let first = (lo / span).floor().max(0.0);
            let end = (hi / span).floor().min(last);
            if first <= end {
                (first as i64..=end as i64).for_each(&mut each);
            }
        }
    }

    /// The distance from the viewer's eye to the nearest point of node
    /// `(x, y)`'s footprint (level-0 `span` posts a side) at the height of
    /// the ground under the viewer, metres. The nearest point is found on a
    /// sphere (its latitude toward the viewer's along the nearest edge
    /// meridian), then placed on the ellipsoid.
    fn distance_m(&self, viewer: &Viewer, span: f64, x: i64, y: i64) -> f64 {
        let last = self.placement.posts().map(|p| p.saturating_sub(1) as f64);
        let (u0, u1) = (x as f64 * span, ((x + 1) as f64 * span).min(last[0]));
        let (v0, v1) = (y as f64 * span, ((y + 1) as f64 * span).min(last[1]));
        let (origin, step) = match self.lattice {
            Lattice::Geographic { origin, step } => (origin, step),
            Lattice::Projected(_) => {
                // Nearest in the plane, placed on the ellipsoid.
                let (u, v) = (viewer.post[0].clamp(u0, u1), viewer.post[1].clamp(v0, v1));
                return viewer.eye.distance(self.placement.ecef(u, v, viewer.ground_m));
            }
        };
        let lat_of = |v: f64| (origin[1] + v * step[1]).clamp(-FRAC_PI_2, FRAC_PI_2);
        let (lat_a, lat_b) = (lat_of(v0), lat_of(v1));
        let (lat_lo, lat_hi) = (lat_a.min(lat_b), lat_a.max(lat_b));
        let lon_centre = origin[0] + 0.5 * (u0 + u1) * step[0];
        let half = 0.5 * (u1 - u0) * step[0].abs();
        let off = normalize_longitude((viewer.lon - lon_centre).to_degrees()).to_radians();
        let (lat, lon) = if off.abs() <= half {
            (viewer.lat.clamp(lat_lo, lat_hi), viewer.lon)
        } else {
            let gap = off.abs() - half;
            let toward = if gap.cos() > 1e-12 {
                (viewer.lat.tan() / gap.cos()).atan()
            } else {
                FRAC_PI_2.copysign(viewer.lat)
            };
            (toward.clamp(lat_lo, lat_hi), lon_centre + half.copysign(off))
        };
        viewer.eye.distance(ellipsoid::to_ecef(lat, lon, viewer.ground_m))
    }
}
