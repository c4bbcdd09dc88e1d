//! Where a grid's posts are on the earth: [`GridPlacement`] maps a post
//! (fractional `u` east, `v` north, in level-0 posts from the south-west
//! post) to its geodetic latitude and longitude, and back, for every
//! georeference Ridgeline reads:
//!
//! - **geographic** grids (`Crs::Geographic`): posts are
//!   `origin + (u, v) * spacing` degrees; a grid whose columns span 360
//!   degrees *wraps*: posts one period apart are one place;
//! - **projected** grids with an EPSG code [`Projection`] supports: the
//!   projection's inverse of `origin + (u, v) * spacing` metres;
//! - **local** grids (no georeference), and projected ones of an unknown or
//!   unsupported system: placed *as if* by a transverse Mercator of central
//!   meridian 0 degrees with the grid's centre at 0 N 0 E, so the grid keeps
//!   its shape and size in metres; where on the earth it really is is not
//!   known ([`GridPlacement::assumed`] says why).
//!
//! The *chart* is the post lattice scaled by the layout's `spacing_m`
//! (`x = u * spacing_m[0]`, `y = v * spacing_m[1]`): the coordinates the
//! node pyramid, flight paths and the accuracy tool's ground points use.
//! It is only a chart: for a geographic grid it is the equirectangular
//! projection at the grid's centre latitude, so distances in it are not
//! distances on the earth; [`GridPlacement::ecef`] gives those.

use glam::DVec3;

use super::ellipsoid::{self, longitude_from, normalize_longitude};
use super::projection::{Projection, TransverseMercator};
use crate::geo::{Crs, GeoRef};

/// How a grid's coordinates become latitude and longitude.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Degrees of longitude and latitude.
    Geographic,
    /// Metres of a projection.
    Projected(Projection),
}

/// Where a grid's posts are on the WGS 84 ellipsoid (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPlacement {
    kind: Kind,
    /// Coordinates of post (0, 0): degrees (lon, lat) or projected metres.
    origin: [f64; 2],
    /// Coordinates between neighbouring posts, east and north.
    step: [f64; 2],
    /// Chart metres between posts, east and north (the layout's `spacing_m`).
    chart_m: [f64; 2],
    /// Level-0 posts, east and north.
    posts: [u32; 2],
    /// Posts in 360 degrees, when the grid wraps.
    period: Option<f64>,
    /// Why the grid is placed by assumption, if it is.
    assumed: Option<&'static str>,
}

/// A projected grid's posts ([`GridPlacement::projected_lattice`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectedLattice {
    /// The projection.
    pub projection: Projection,
    /// Projected metres of post (0, 0), east and north.
    pub origin: [f64; 2],
    /// Projected metres between neighbouring posts, east and north.
    pub step: [f64; 2],
}

impl ProjectedLattice {
    /// Latitude and longitude, radians, of post `(u, v)` (any fraction):
    /// the exact inverse projection.
    pub fn geodetic(&self, [u, v]: [f64; 2]) -> (f64, f64) {
        self.projection
            .inverse([self.origin[0] + u * self.step[0], self.origin[1] + v * self.step[1]])
    }
}

/// A grid whose columns span this close to 360 degrees wraps.
const WRAP_TOLERANCE_DEG: f64 = 1e-6;

impl GridPlacement {
    /// The placement of a grid of `posts` posts with `georef`, whose chart
    /// has `chart_m` metres between posts (the node layout's `spacing_m`).
    pub fn new(georef: &GeoRef, posts: [u32; 2], chart_m: [f64; 2]) -> GridPlacement {
        let local = |assumed| {
            let centre = [0, 1].map(|k| posts[k].saturating_sub(1) as f64 / 2.0 * chart_m[k]);
            let tm = TransverseMercator {
                central_meridian_deg: 0.0,
                scale: 1.0,
                false_easting: 0.0,
                false_northing: 0.0,
            };
            GridPlacement {
                kind: Kind::Projected(Projection::TransverseMercator(tm)),
                origin: [-centre[0], -centre[1]],
                step: chart_m,
                chart_m,
                posts,
                period: None,
                assumed: Some(assumed),
            }
        };
        match georef.crs {
            Crs::Geographic => {
                let span = georef.spacing[0] * posts[0].saturating_sub(1) as f64;
                let period = 360.0 / georef.spacing[0];
                // With or without a closing column (a copy of the first).
                let wraps = (span - 360.0).abs() < WRAP_TOLERANCE_DEG
                    || (span + georef.spacing[0] - 360.0).abs() < WRAP_TOLERANCE_DEG;
                GridPlacement {
                    kind: Kind::Geographic,
                    origin: georef.origin,
                    step: georef.spacing,
                    chart_m,
                    posts,
                    period: wraps.then_some(period),
                    assumed: None,
                }
            }
            Crs::Projected { epsg: Some(code) } => match Projection::from_epsg(code) {
                Ok(projection) => GridPlacement {
                    kind: Kind::Projected(projection),
                    origin: georef.origin,
                    step: georef.spacing,
                    chart_m,
                    posts,
                    period: None,
                    assumed: None,
                },
                Err(_) => local("its EPSG code is not one Ridgeline places"),
            },
            Crs::Projected { epsg: None } => local("its projection names no EPSG code"),
            Crs::Local => local("it has no georeference"),
        }
    }

    /// For a geographic grid, the longitude and latitude of post (0, 0)
    /// and between neighbouring posts, east and north, radians: what
    /// [`super::EarthFrame`] places a geographic grid's tiles with (a
    /// post's place is linear in its numbers). `None` for projected grids.
    pub fn geographic_lattice(&self) -> Option<([f64; 2], [f64; 2])> {
        match self.kind {
            Kind::Geographic => {
                Some((self.origin.map(f64::to_radians), self.step.map(f64::to_radians)))
            }
            Kind::Projected(_) => None,
        }
    }

    /// For a projected grid of a known projection, its projection and
    /// posts: what [`super::EarthFrame`] places its tiles with and expands
    /// its nodes' posts from ([`super::Expansion`]). `None` for geographic
    /// grids and for grids placed by assumption (drawn in the chart).
    pub fn projected_lattice(&self) -> Option<ProjectedLattice> {
        match self.kind {
            Kind::Projected(projection) if self.assumed.is_none() => {
                Some(ProjectedLattice { projection, origin: self.origin, step: self.step })
            }
            _ => None,
        }
    }

    /// Why the grid is placed by assumption (centred on 0 N 0 E), if it is.
    pub fn assumed(&self) -> Option<&'static str> {
        self.assumed
    }

    /// Level-0 posts in one turn of longitude, when the grid's columns span
    /// 360 degrees: post `u` and post `u + period` are one place.
    pub fn period_posts(&self) -> Option<f64> {
        self.period
    }

    /// Whether the grid covers the whole earth: it wraps in longitude and
    /// its rows reach both poles (to within a row).
    pub fn covers_the_earth(&self) -> bool {
        let rows = self.posts[1].saturating_sub(1) as f64;
        let (south, north) = (self.origin[1], self.origin[1] + self.step[1] * rows);
        let (south, north) = (south.min(north), south.max(north));
        let row = self.step[1].abs();
        self.period.is_some() && south <= -90.0 + row && north >= 90.0 - row
    }

    /// Level-0 posts, east and north.
    pub fn posts(&self) -> [u32; 2] {
        self.posts
    }

    /// Chart metres between posts, east and north.
    pub fn chart_spacing_m(&self) -> [f64; 2] {
        self.chart_m
    }

    /// Geodetic latitude and longitude, radians, of post `(u, v)`.
    pub fn geodetic_of_post(&self, u: f64, v: f64) -> (f64, f64) {
        let x = self.origin[0] + u * self.step[0];
        let y = self.origin[1] + v * self.step[1];
        match self.kind {
            Kind::Geographic => (y.clamp(-90.0, 90.0).to_radians(), x.to_radians()),
            Kind::Projected(p) => p.inverse([x, y]),
        }
    }

    /// Post `(u, v)` of latitude `lat` and longitude `lon` (radians). For a
    /// geographic grid the longitude is taken in the turn that holds the
    /// grid (from its west edge for a wrapping grid, else nearest its
    /// centre), so a place just west of a grid starting at 0 degrees is
    /// at `u` below 0 unless the grid wraps.
    pub fn post_of_geodetic(&self, lat: f64, lon: f64) -> [f64; 2] {
        match self.kind {
            Kind::Geographic => {
                let lon = lon.to_degrees();
                let lon = match self.period {
                    Some(_) => longitude_from(lon, self.origin[0]),
                    None => {
                        let centre = self.origin[0]
                            + self.step[0] * self.posts[0].saturating_sub(1) as f64 / 2.0;
                        centre + normalize_longitude(lon - centre)
                    }
                };
                [
                    (lon - self.origin[0]) / self.step[0],
                    (lat.to_degrees() - self.origin[1]) / self.step[1],
                ]
            }
            Kind::Projected(p) => {
                let [x, y] = p.forward(lat, lon);
                [(x - self.origin[0]) / self.step[0], (y - self.origin[1]) / self.step[1]]
            }
        }
    }

    /// ECEF metres of post `(u, v)` at `height` metres.
    pub fn ecef(&self, u: f64, v: f64, height: f64) -> DVec3 {
        let (lat, lon) = self.geodetic_of_post(u, v);
        ellipsoid::to_ecef(lat, lon, height)
    }

    /// Post `(u, v)` and height of an ECEF point.
    pub fn post_of_ecef(&self, p: DVec3) -> ([f64; 2], f64) {
        let (lat, lon, h) = ellipsoid::from_ecef(p);
        (self.post_of_geodetic(lat, lon), h)
    }

    /// The chart point (metres east and north of the south-west post) of post `(u, v)`.
    pub fn chart_of_post(&self, [u, v]: [f64; 2]) -> [f64; 2] {
        [u * self.chart_m[0], v * self.chart_m[1]]
    }

    /// The post of a chart point.
    pub fn post_of_chart(&self, [x, y]: [f64; 2]) -> [f64; 2] {
        [x / self.chart_m[0], y / self.chart_m[1]]
    }

    /// Latitude and longitude, radians, of a chart point.
    pub fn geodetic_of_chart(&self, chart: [f64; 2]) -> (f64, f64) {
        let [u, v] = self.post_of_chart(chart);
        self.geodetic_of_post(u, v)
    }

    /// The chart point of latitude `lat` and longitude `lon` (radians).
    pub fn chart_of_geodetic(&self, lat: f64, lon: f64) -> [f64; 2] {
        self.chart_of_post(self.post_of_geodetic(lat, lon))
    }

    /// `u` brought into the grid's columns `[0, period)` when the grid
    /// wraps (unchanged otherwise).
    pub fn wrap_u(&self, u: f64) -> f64 {
        match self.period {
            Some(period) => u.rem_euclid(period),
            None => u,
        }
    }

    /// ECEF metres of a chart point at `height`.
    pub fn ecef_of_chart(&self, chart: [f64; 2], height: f64) -> DVec3 {
        let [u, v] = self.post_of_chart(chart);
        self.ecef(u, v, height)
    }

    /// Level-0 posts `(u, v)` around `post` that hold every post within
    /// `reach_m` metres of it on the ellipsoid (lowest corner, highest
    /// corner; may reach past the grid, or wrap).
    pub fn post_window(&self, post: [f64; 2], reach_m: f64) -> ([f64; 2], [f64; 2]) {
        match self.kind {
            Kind::Geographic => {
                // A degree of latitude is at least 110.5 km.
                let dv = reach_m / (110_500.0 * self.step[1]);
                let lat = self.origin[1] + post[1] * self.step[1];
                let reach_deg = reach_m / 110_500.0;
                let poleward = lat.abs() + reach_deg;
                if poleward >= 89.99 {
                    return ([f64::NEG_INFINITY, post[1] - dv], [f64::INFINITY, post[1] + dv]);
                }
                let east_m = 111_000.0 * poleward.to_radians().cos() * self.step[0];
                let du = reach_m / (0.99 * east_m);
                ([post[0] - du, post[1] - dv], [post[0] + du, post[1] + dv])
            }
            Kind::Projected(projection) => {
                // A transverse Mercator's metres are within 10 % of the
                // earth's where grids are placed (its scale is 1.08 at
                // 3400 km from the central meridian); Web Mercator's
                // stretch by the secant of the latitude.
                let mut scale = 1.1;
                if projection == Projection::WebMercator {
                    let (lat, _) = self.geodetic_of_post(post[0], post[1]);
                    let poleward = lat.abs().to_degrees() + reach_m / 110_500.0;
                    scale /= poleward.min(85.1).to_radians().cos();
                }
                let [du, dv] = self.step.map(|s| scale * reach_m / s);
                ([post[0] - du, post[1] - dv], [post[0] + du, post[1] + dv])
            }
        }
    }

    /// How far a cell of `cell_posts` level-0 posts drawn as two flat
    /// triangles (split south-west to north-east) strays from the grid's
    /// own surface, metres: the largest distance, over cells sampled on a
    /// 9 x 9 lattice over the grid and points sampled in each triangle,
    /// between a point of the flat triangle and the point of the same grid
    /// coordinates on the earth (both at height 0). It holds the sag of the
    /// chord below the curved earth and, near the poles, the shift across
    /// a cell whose width changes along it. What a level whose cells are
    /// that size adds to its delta when drawn on the ellipsoid.
    pub fn flat_cell_error_m(&self, cell_posts: f64) -> f64 {
        let [w, h] = self.posts.map(|p| p.saturating_sub(1) as f64);
        let mut worst: f64 = 0.0;
        for a in 0..=8 {
            for b in 0..=8 {
                let u = ((w - cell_posts) * a as f64 / 8.0).max(0.0);
                let v = ((h - cell_posts) * b as f64 / 8.0).max(0.0);
                let corner =
                    |du: f64, dv: f64| self.ecef(u + du * cell_posts, v + dv * cell_posts, 0.0);
                let [sw, se, nw, ne] =
                    [corner(0.0, 0.0), corner(1.0, 0.0), corner(0.0, 1.0), corner(1.0, 1.0)];
                for i in 0..=6 {
                    for j in 0..=6 {
                        let (fu, fv) = (i as f64 / 6.0, j as f64 / 6.0);
                        let flat = if fu >= fv {
                            sw + (se - sw) * fu + (ne - se) * fv
                        } else {
                            sw + (nw - sw) * fv + (ne - nw) * fu
                        };
                        let true_point = self.ecef(u + fu * cell_posts, v + fv * cell_posts, 0.0);
                        worst = worst.max(flat.distance(true_point));
                    }
                }
            }
        }
        worst
    }

    /// The largest distance on the ellipsoid between neighbouring posts,
    /// east and north, anywhere on the grid, metres (sampled on a lattice
    /// of 9 x 9 places, then 1 % added): what sizes a tile in the LOD's
    /// distance rings.
    pub fn max_post_spacing_m(&self) -> [f64; 2] {
        let [w, h] = self.posts.map(|p| p.saturating_sub(1).max(1) as f64);
        let mut most = [0.0f64; 2];
        for a in 0..=8 {
            for b in 0..=8 {
                let (u, v) = (w * a as f64 / 8.0, h * b as f64 / 8.0);
                let here = self.ecef(u, v, 0.0);
                let east = self.ecef(u + if a == 8 { -1.0 } else { 1.0 }, v, 0.0);
                let north = self.ecef(u, v + if b == 8 { -1.0 } else { 1.0 }, 0.0);
                most[0] = most[0].max(here.distance(east));
                most[1] = most[1].max(here.distance(north));
            }
        }
        most.map(|m| m * 1.01)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn global(closing_column: bool) -> GridPlacement {
        let spacing = 5.0 / 60.0;
        let columns = if closing_column { 4321 } else { 4320 };
        let georef =
            GeoRef { crs: Crs::Geographic, origin: [0.0, -90.0], spacing: [spacing, spacing] };
        GridPlacement::new(&georef, [columns, 2161], [9276.6, 9262.7])
    }

    #[test]
    fn a_global_grid_wraps_with_or_without_its_closing_column() {
        for closing in [false, true] {
            let p = global(closing);
            assert_eq!(p.period_posts(), Some(4320.0));
            // Just west of Greenwich is the grid's east end.
            let [u, v] = p.post_of_geodetic(51.5f64.to_radians(), (-0.5f64).to_radians());
            assert!((u - 4314.0).abs() < 1e-9 && (v - 1698.0).abs() < 1e-9, "{u} {v}");
            // Post 0 and post 4320 are one place.
            assert!(p.ecef(0.0, 1698.0, 0.0).distance(p.ecef(4320.0, 1698.0, 0.0)) < 1e-6);
        }
        let regional = GridPlacement::new(
            &GeoRef { crs: Crs::Geographic, origin: [5.0, 45.0], spacing: [0.01, 0.01] },
            [301, 201],
            [786.0, 1111.0],
        );
        assert_eq!(regional.period_posts(), None);
        let [u, _] = regional.post_of_geodetic(46f64.to_radians(), 4.0f64.to_radians());
        assert!((u + 100.0).abs() < 1e-9, "west of the grid stays west: {u}");
    }

    #[test]
    fn posts_round_trip_through_ecef() {
        let utm = GridPlacement::new(
            &GeoRef {
                crs: Crs::Projected { epsg: Some(32632) },
                origin: [400_000.0, 5_200_000.0],
                spacing: [25.0, 25.0],
            },
            [4001, 4001],
            [25.0, 25.0],
        );
        let local = GridPlacement::new(&GeoRef::local([90.0, 90.0]), [1201, 1201], [90.0, 90.0]);
        assert!(utm.assumed().is_none() && local.assumed().is_some());
        for p in [global(true), utm, local] {
            for (u, v) in [(0.0, 0.0), (17.25, 1000.5), (1200.0, 1200.0)] {
                let e = p.ecef(u, v, 1234.5);
                let ([bu, bv], h) = p.post_of_ecef(e);
                assert!((bu - u).abs() < 1e-6 && (bv - v).abs() < 1e-6, "{u} {v}: {bu} {bv}");
                assert!((h - 1234.5).abs() < 1e-6);
            }
        }
        // A local grid keeps its metres: posts 90 m apart at its centre.
        let d = local.ecef(600.0, 600.0, 0.0).distance(local.ecef(601.0, 600.0, 0.0));
        assert!((d - 90.0).abs() < 1e-6, "{d}");
    }

    /// 90 m cells stray a third of a millimetre, a level-6 cell of 90 m
    /// data (5.8 km) 1.3 m, ETOPO5's 9 km cells 3.4 m (their sag), and a
    /// level-6 ETOPO5 cell (5.3 degrees) kilometres.
    #[test]
    fn flat_cells_stray_from_the_earth_by_their_sag() {
        let srtm = GridPlacement::new(
            &GeoRef { crs: Crs::Geographic, origin: [40.0, 39.0], spacing: [1.0 / 1200.0; 2] },
            [1201, 1201],
            [71.0, 92.5],
        );
        let fine = srtm.flat_cell_error_m(1.0);
        let coarse = srtm.flat_cell_error_m(64.0);
        let etopo = global(true).flat_cell_error_m(1.0);
        let etopo_6 = global(true).flat_cell_error_m(64.0);
        println!("{fine} {coarse} {etopo} {etopo_6}");
        assert!(fine < 1e-3 && (0.5..3.0).contains(&coarse), "{fine} {coarse}");
        assert!((1.0..10.0).contains(&etopo) && etopo_6 > 1000.0, "{etopo} {etopo_6}");
    }

    #[test]
    fn the_largest_spacing_of_a_global_grid_is_at_the_equator_east_and_the_poles_north() {
        let [east, north] = global(true).max_post_spacing_m();
        assert!((east / 1.01 - 9276.6).abs() < 1.0, "{east}");
        assert!(north / 1.01 > 9300.0 && north / 1.01 < 9330.0, "{north}");
    }
}
