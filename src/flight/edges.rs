//! The built-in flights along data edges (`--flight edges`, `--flight
//! outline`): views at low level along, across and past every edge of a
//! rectangle of data, and along a no-data outline of any shape inside a
//! grid. Each waypoint is one view, one second after the last: the
//! accuracy tool's views (`--views` as many as there are waypoints) land
//! on them exactly, and nothing is flown between them (each view is a jump).
//!
//! Per edge of the rectangle (east, north, west, south), four views at
//! [`ABOVE_GROUND_M`] above the ground under the camera (under the nearest
//! post with data when past the edge):
//! 1. inside the edge by [`INSET_M`], flying along it, nose [`PITCH_ALONG_DEG`] down;
//! 2. inside by twice that, looking out across the edge;
//! 3. outside by [`OUTSIDE_M`], looking back in, low over the last ridges;
//! 4. outside by half that, looking diagonally back in and along the edge.
//!
//! Past an edge the ground is the last post's: a low camera there sees the
//! data's cut face and beneath the surface, where nothing of a correct
//! display may show but the no-data hatching.

use glam::DVec2;

use super::path::{FlightPath, Waypoint};
use super::pose::{normalize_heading, Pose};

/// Metres above the ground under each view.
pub const ABOVE_GROUND_M: f64 = 300.0;
/// How far inside an edge the view flying along it is, metres (at most a
/// tenth of the data across).
pub const INSET_M: f64 = 1_500.0;
/// How far past an edge the view looking back in is, metres.
pub const OUTSIDE_M: f64 = 2_000.0;
/// Nose down flying along an edge, degrees.
pub const PITCH_ALONG_DEG: f64 = -8.0;
/// Nose down looking across an edge, in or out, degrees.
pub const PITCH_ACROSS_DEG: f64 = -6.0;
/// Views a `--flight outline` takes along the outline.
pub const OUTLINE_VIEWS: usize = 16;
/// Cells of the coarse lattice the outline is searched on, per side.
const OUTLINE_LATTICE: usize = 256;

/// The edge flight over the rectangle `extent_m` metres wide whose
/// south-west corner is at `origin_m`; `height_at` is the terrain (`None`
/// where there are no data). Sixteen views, four per edge.
pub fn builtin_edges(
    origin_m: [f64; 2],
    extent_m: [f64; 2],
    height_at: &dyn Fn(f64, f64) -> Option<f32>,
) -> FlightPath {
    let origin = DVec2::from(origin_m);
    let extent = DVec2::from(extent_m).max(DVec2::splat(1.0));
    let inset = INSET_M.min(extent.min_element() / 10.0);
    let ground = Ground { origin, extent, height_at };
    let mut poses = Vec::with_capacity(16);
    // Outward normals and the direction along each edge (counter-clockwise).
    let edges = [
        (DVec2::X, DVec2::Y),
        (DVec2::Y, -DVec2::X),
        (-DVec2::X, -DVec2::Y),
        (-DVec2::Y, DVec2::X),
    ];
    for (outward, along) in edges {
        // The edge's point at `share` of the way along it, `off` metres out.
        let at = |share: f64, off: f64| {
            let centre = origin + extent * 0.5;
            let half = extent * 0.5;
            centre
                + outward * (outward.abs().dot(half) + off)
                + along * (along.abs().dot(half) * (2.0 * share - 1.0))
        };
        let views = [
            (at(0.3, -inset), along, PITCH_ALONG_DEG),
            (at(0.5, -2.0 * inset), outward, PITCH_ACROSS_DEG),
            (at(0.6, OUTSIDE_M), -outward, PITCH_ACROSS_DEG),
            (at(0.8, OUTSIDE_M / 2.0), (along - outward).normalize(), PITCH_ALONG_DEG),
        ];
        for (position, facing, pitch) in views {
            poses.push(ground.pose(position, facing, pitch));
        }
    }
    path_of(poses)
}

/// The outline flight: [`OUTLINE_VIEWS`] views along the outline of the
/// data inside the rectangle `extent_m` metres wide whose south-west corner
/// is at `origin_m` (where `height_at` turns from heights to `None`), in
/// turn inside flying along it and past it looking back in. `None` when
/// the data have no outline inside the rectangle (they fill it).
pub fn builtin_outline(
    origin_m: [f64; 2],
    extent_m: [f64; 2],
    height_at: &dyn Fn(f64, f64) -> Option<f32>,
) -> Option<FlightPath> {
    let origin = DVec2::from(origin_m);
    let extent = DVec2::from(extent_m).max(DVec2::splat(1.0));
    let lattice = Lattice::new(origin, extent, height_at);
    let outline = lattice.outline();
    if outline.is_empty() {
        return None;
    }
    let inset = INSET_M.min(extent.min_element() / 10.0);
    let ground = Ground { origin, extent, height_at };
    // Outline points in order of their angle around the data's centre,
    // spread evenly along that order.
    let centre = lattice.centre();
    let mut points = outline;
    points.sort_by(|a, b| angle(a.0 - centre).total_cmp(&angle(b.0 - centre)));
    let poses = (0..OUTLINE_VIEWS)
        .map(|k| {
            let (point, outward) = points[k * points.len() / OUTLINE_VIEWS];
            let along = outward.perp();
            if k % 2 == 0 {
                ground.pose(point - outward * inset, along, PITCH_ALONG_DEG)
            } else {
                ground.pose(point + outward * (OUTSIDE_M / 2.0), -outward, PITCH_ACROSS_DEG)
            }
        })
        .collect();
    Some(path_of(poses))
}

fn angle(v: DVec2) -> f64 {
    v.y.atan2(v.x)
}

/// The terrain the views are placed over.
struct Ground<'a> {
    origin: DVec2,
    extent: DVec2,
    height_at: &'a dyn Fn(f64, f64) -> Option<f32>,
}

impl Ground<'_> {
    /// A view at `position` facing `facing` (horizontal), pitched `pitch`
    /// degrees, [`ABOVE_GROUND_M`] above the ground there.
    fn pose(&self, position: DVec2, facing: DVec2, pitch: f64) -> Pose {
        let heading = normalize_heading(facing.x.atan2(facing.y).to_degrees());
        let altitude = self.ground(position) + ABOVE_GROUND_M;
        Pose {
            position: position.extend(round_to(altitude, 0.1)),
            heading_deg: round_to(heading, 0.01),
            pitch_deg: pitch,
            roll_deg: 0.0,
        }
    }

    /// The height under `p`, or past the data at the nearest post with
    /// data toward the rectangle's centre (0 m where none is found).
    fn ground(&self, p: DVec2) -> f64 {
        let centre = self.origin + self.extent * 0.5;
        let at = |q: DVec2| (self.height_at)(q.x, q.y).filter(|h| h.is_finite());
        let clamped = p.clamp(self.origin, self.origin + self.extent);
        (0..=64).find_map(|k| at(clamped.lerp(centre, k as f64 / 64.0))).map_or(0.0, |h| h as f64)
    }
}

/// A coarse lattice over the rectangle: which points have data.
struct Lattice {
    origin: DVec2,
    cell: DVec2,
    data: Vec<bool>,
}

impl Lattice {
    fn new(origin: DVec2, extent: DVec2, height_at: &dyn Fn(f64, f64) -> Option<f32>) -> Lattice {
        let n = OUTLINE_LATTICE;
        let cell = extent / n as f64;
        let mut data = Vec::with_capacity((n + 1) * (n + 1));
        for j in 0..=n {
            for i in 0..=n {
                let p = origin + cell * DVec2::new(i as f64, j as f64);
                data.push(height_at(p.x, p.y).is_some_and(f32::is_finite));
            }
        }
        Lattice { origin, cell, data }
    }

    fn has(&self, i: i64, j: i64) -> bool {
        let n = OUTLINE_LATTICE as i64;
        (0..=n).contains(&i) && (0..=n).contains(&j) && self.data[(j * (n + 1) + i) as usize]
    }

    fn point(&self, i: i64, j: i64) -> DVec2 {
        self.origin + self.cell * DVec2::new(i as f64, j as f64)
    }

    /// Lattice points with data next to one without, inside the rectangle
    /// (its own border is the rectangle's edge, not an outline), each with
    /// its outward direction: toward the points without data around it.
    fn outline(&self) -> Vec<(DVec2, DVec2)> {
        let n = OUTLINE_LATTICE as i64;
        let mut out = Vec::new();
        for j in 1..n {
            for i in 1..n {
                if !self.has(i, j) {
                    continue;
                }
                let mut outward = DVec2::ZERO;
                for dj in -2..=2 {
                    for di in -2..=2 {
                        if !self.has(i + di, j + dj) && (di != 0 || dj != 0) {
                            outward += DVec2::new(di as f64, dj as f64) * self.cell;
                        }
                    }
                }
                let beside = [(1, 0), (-1, 0), (0, 1), (0, -1)];
                if beside.iter().any(|&(di, dj)| !self.has(i + di, j + dj))
                    && outward.length() > 0.0
                {
                    out.push((self.point(i, j), outward.normalize()));
                }
            }
        }
        out
    }

    /// The mean of the points with data.
    fn centre(&self) -> DVec2 {
        let n = OUTLINE_LATTICE as i64;
        let (mut sum, mut count) = (DVec2::ZERO, 0.0);
        for j in 0..=n {
            for i in 0..=n {
                if self.has(i, j) {
                    sum += self.point(i, j);
                    count += 1.0;
                }
            }
        }
        if count > 0.0 {
            sum / count
        } else {
            self.origin
        }
    }
}

/// One waypoint a second.
fn path_of(poses: Vec<Pose>) -> FlightPath {
    let waypoints =
        poses.into_iter().enumerate().map(|(k, pose)| Waypoint { t: k as f64, pose }).collect();
    FlightPath::new(waypoints).expect("edge views keep every value inside the path rules")
}

fn round_to(value: f64, step: f64) -> f64 {
    (value / step).round() * step
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_views_four_past_each_edge_300_m_above_the_ground() {
        // A plane rising 1 m per 100 m east, 10 km by 20 km.
        let height = |x: f64, y: f64| {
            ((0.0..=10_000.0).contains(&x) && (0.0..=20_000.0).contains(&y))
                .then_some((x / 100.0) as f32)
        };
        let path = builtin_edges([0.0, 0.0], [10_000.0, 20_000.0], &height);
        let points = path.waypoints();
        assert_eq!(points.len(), 16);
        let outside = |p: DVec2| p.x < 0.0 || p.x > 10_000.0 || p.y < 0.0 || p.y > 20_000.0;
        assert_eq!(points.iter().filter(|w| outside(w.pose.position.truncate())).count(), 8);
        // East edge, inside: 1 km in (a tenth of the width), flying north.
        let first = points[0].pose;
        assert_eq!(first.position.x, 9_000.0);
        assert_eq!(first.heading_deg, 0.0);
        assert!((first.position.z - (90.0 + 300.0)).abs() < 0.2, "{}", first.position.z);
        // Past the east edge looking back west, over the last post's height.
        let past = points[2].pose;
        assert_eq!((past.position.x, past.heading_deg), (12_000.0, 270.0));
        assert!((past.position.z - (100.0 + 300.0)).abs() < 0.2, "{}", past.position.z);
    }

    #[test]
    fn the_outline_flight_follows_a_disc_of_data() {
        // Data on a disc of 8 km radius inside a 20 km square.
        let height = |x: f64, y: f64| {
            (DVec2::new(x, y).distance(DVec2::splat(10_000.0)) < 8_000.0).then_some(100.0f32)
        };
        let path = builtin_outline([0.0, 0.0], [20_000.0, 20_000.0], &height).expect("an outline");
        assert_eq!(path.waypoints().len(), OUTLINE_VIEWS);
        for (k, w) in path.waypoints().iter().enumerate() {
            let r = w.pose.position.truncate().distance(DVec2::splat(10_000.0));
            let expected = if k % 2 == 0 { 8_000.0 - INSET_M } else { 8_000.0 + OUTSIDE_M / 2.0 };
            assert!((r - expected).abs() < 200.0, "view {k} at {r} m from the centre");
            assert!((w.pose.position.z - 400.0).abs() < 0.2);
        }
        let full = |_: f64, _: f64| Some(1.0f32);
        assert!(builtin_outline([0.0, 0.0], [1.0e4, 1.0e4], &full).is_none());
    }
}
