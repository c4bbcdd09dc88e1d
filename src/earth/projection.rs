//! The map projections Ridgeline places projected grids with: transverse
//! Mercator by Krüger's series (UTM zones on WGS 84, and ETRS89 / UTM,
//! whose GRS 80 ellipsoid differs from WGS 84 by 0.1 mm in its minor axis)
//! and Web Mercator (EPSG:3857).
//!
//! **Why our own transform and not a crate.** The whole job is two series
//! of six terms each (Karney, "Transverse Mercator with an accuracy of a few
//! nanometers", J. Geodesy 85, 2011, eqs. 35-36 with the coefficients to
//! n^6), 5 nm within 3900 km of the central meridian; PROJ's own
//! implementation (Poder/Engsager) is the same series. The crates that
//! wrap PROJ need the C library and its database at run time, which an
//! avionics board does not carry; the pure-Rust ports carry hundreds of
//! systems we do not support. The tests check every system against PROJ
//! 9.5.1 at published places to a millimetre.

use super::ellipsoid::{A, E2, F};

/// A projected coordinate system Ridgeline can place a grid with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Transverse Mercator on WGS 84.
    TransverseMercator(TransverseMercator),
    /// Web Mercator (EPSG:3857): the sphere of radius `a` on WGS 84 latitudes.
    WebMercator,
}

/// A transverse Mercator: central meridian, scale on it, false origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransverseMercator {
    /// Longitude of the central meridian, degrees.
    pub central_meridian_deg: f64,
    /// Scale on the central meridian (0.9996 for UTM).
    pub scale: f64,
    /// Easting of the central meridian, metres.
    pub false_easting: f64,
    /// Northing of the equator, metres.
    pub false_northing: f64,
}

/// Why an EPSG code cannot be placed.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("EPSG:{0} is not a projection Ridgeline places (UTM on WGS 84 326xx/327xx, ETRS89 / UTM 258xx, Web Mercator 3857)")]
pub struct UnsupportedEpsg(pub u32);

impl Projection {
    /// The projection of EPSG code `epsg`: WGS 84 / UTM zones 1-60 north
    /// (32601-32660) and south (32701-32760), ETRS89 / UTM zones 28-38
    /// (25828-25838), Web Mercator (3857).
    pub fn from_epsg(epsg: u32) -> Result<Projection, UnsupportedEpsg> {
        let utm = |zone: u32, south: bool| {
            Projection::TransverseMercator(TransverseMercator {
                central_meridian_deg: zone as f64 * 6.0 - 183.0,
                scale: 0.9996,
                false_easting: 500_000.0,
                false_northing: if south { 10_000_000.0 } else { 0.0 },
            })
        };
        match epsg {
            32601..=32660 => Ok(utm(epsg - 32600, false)),
            32701..=32760 => Ok(utm(epsg - 32700, true)),
            25828..=25838 => Ok(utm(epsg - 25800, false)),
            3857 => Ok(Projection::WebMercator),
            _ => Err(UnsupportedEpsg(epsg)),
        }
    }

    /// The eccentricity squared of the latitude whose isometric form,
    /// with longitude, is conformal to the projection's plane: the
    /// ellipsoid's for a transverse Mercator (a conformal map of the
    /// ellipsoid), 0 for Web Mercator (a conformal map of the sphere, fed
    /// the ellipsoid's latitudes). See [`super::Expansion`].
    pub fn isometric_e2(&self) -> f64 {
        match self {
            Projection::TransverseMercator(_) => E2,
            Projection::WebMercator => 0.0,
        }
    }

    /// Easting and northing, metres, of latitude `lat` and longitude `lon` (radians).
    pub fn forward(&self, lat: f64, lon: f64) -> [f64; 2] {
        match self {
            Projection::TransverseMercator(tm) => tm.forward(lat, lon),
            Projection::WebMercator => {
                let lat = lat.clamp(-MERCATOR_LAT_LIMIT, MERCATOR_LAT_LIMIT);
                [A * lon, A * (std::f64::consts::FRAC_PI_4 + lat / 2.0).tan().ln()]
            }
        }
    }

    /// Latitude and longitude (radians) of easting and northing `[x, y]`, metres.
    pub fn inverse(&self, [x, y]: [f64; 2]) -> (f64, f64) {
        match self {
            Projection::TransverseMercator(tm) => tm.inverse(x, y),
            Projection::WebMercator => ((y / A).sinh().atan(), x / A),
        }
    }
}

/// Web Mercator's latitudes end here (85.05 degrees: the square map).
const MERCATOR_LAT_LIMIT: f64 = 1.484_422_229_745_332_4;

/// Krüger's series coefficients for WGS 84, to n^6 (Karney 2011, eq. 35
/// for alpha, 36 for beta), and the rectifying radius.
struct Series {
    rectifying_radius: f64,
    alpha: [f64; 6],
    beta: [f64; 6],
}

fn series() -> Series {
    let n = F / (2.0 - F);
    let (n2, n3) = (n * n, n * n * n);
    let (n4, n5, n6) = (n2 * n2, n2 * n3, n3 * n3);
    Series {
        rectifying_radius: A / (1.0 + n) * (1.0 + n2 / 4.0 + n4 / 64.0 + n6 / 256.0),
        alpha: [
            n / 2.0 - 2.0 * n2 / 3.0 + 5.0 * n3 / 16.0 + 41.0 * n4 / 180.0 - 127.0 * n5 / 288.0
                + 7891.0 * n6 / 37800.0,
            13.0 * n2 / 48.0 - 3.0 * n3 / 5.0 + 557.0 * n4 / 1440.0 + 281.0 * n5 / 630.0
                - 1_983_433.0 * n6 / 1_935_360.0,
            61.0 * n3 / 240.0 - 103.0 * n4 / 140.0
                + 15061.0 * n5 / 26880.0
                + 167_603.0 * n6 / 181_440.0,
            49561.0 * n4 / 161_280.0 - 179.0 * n5 / 168.0 + 6_601_661.0 * n6 / 7_257_600.0,
            34729.0 * n5 / 80640.0 - 3_418_889.0 * n6 / 1_995_840.0,
            212_378_941.0 * n6 / 319_334_400.0,
        ],
        beta: [
            n / 2.0 - 2.0 * n2 / 3.0 + 37.0 * n3 / 96.0 - n4 / 360.0 - 81.0 * n5 / 512.0
                + 96199.0 * n6 / 604_800.0,
            n2 / 48.0 + n3 / 15.0 - 437.0 * n4 / 1440.0 + 46.0 * n5 / 105.0
                - 1_118_711.0 * n6 / 3_870_720.0,
            17.0 * n3 / 480.0 - 37.0 * n4 / 840.0 - 209.0 * n5 / 4480.0 + 5569.0 * n6 / 90720.0,
            4397.0 * n4 / 161_280.0 - 11.0 * n5 / 504.0 - 830_251.0 * n6 / 7_257_600.0,
            4583.0 * n5 / 161_280.0 - 108_847.0 * n6 / 3_991_680.0,
            20_648_693.0 * n6 / 638_668_800.0,
        ],
    }
}

/// `tan` of the conformal latitude from `tan` of the geodetic one (Karney's `taupf`).
fn conformal_tan(tau: f64) -> f64 {
    let e = E2.sqrt();
    let tau1 = tau.hypot(1.0);
    let sig = (e * (e * tau / tau1).atanh()).sinh();
    sig.hypot(1.0) * tau - sig * tau1
}

/// The inverse of [`conformal_tan`] by Newton's method (Karney's `tauf`):
/// two or three steps reach f64 precision.
fn geodetic_tan(taup: f64) -> f64 {
    let mut tau = taup / (1.0 - E2);
    for _ in 0..8 {
        let taupa = conformal_tan(tau);
        let step = (taup - taupa) * (1.0 + (1.0 - E2) * tau * tau)
            / ((1.0 - E2) * ((1.0 + tau * tau) * (1.0 + taupa * taupa)).sqrt());
        tau += step;
        if step.abs() <= 1e-15 * tau.abs().max(1.0) {
            break;
        }
    }
    tau
}

impl TransverseMercator {
    /// Easting and northing of `lat`, `lon` (radians).
    pub fn forward(&self, lat: f64, lon: f64) -> [f64; 2] {
        let s = series();
        let dlon = lon - self.central_meridian_deg.to_radians();
        let taup = conformal_tan(lat.tan());
        let (sin_l, cos_l) = dlon.sin_cos();
        let xip = taup.atan2(cos_l);
        let etap = (sin_l / taup.hypot(cos_l)).asinh();
        let (mut xi, mut eta) = (xip, etap);
        for (j, a) in s.alpha.iter().enumerate() {
            let k = 2.0 * (j + 1) as f64;
            xi += a * (k * xip).sin() * (k * etap).cosh();
            eta += a * (k * xip).cos() * (k * etap).sinh();
        }
        let k0a = self.scale * s.rectifying_radius;
        [self.false_easting + k0a * eta, self.false_northing + k0a * xi]
    }

    /// Latitude and longitude (radians) of easting `x`, northing `y`.
    pub fn inverse(&self, x: f64, y: f64) -> (f64, f64) {
        let s = series();
        let k0a = self.scale * s.rectifying_radius;
        let (xi, eta) = ((y - self.false_northing) / k0a, (x - self.false_easting) / k0a);
        let (mut xip, mut etap) = (xi, eta);
        for (j, b) in s.beta.iter().enumerate() {
            let k = 2.0 * (j + 1) as f64;
            xip -= b * (k * xi).sin() * (k * eta).cosh();
            etap -= b * (k * xi).cos() * (k * eta).sinh();
        }
        let (sinh_e, cos_x) = (etap.sinh(), xip.cos());
        let taup = xip.sin() / sinh_e.hypot(cos_x);
        let lat = geodetic_tan(taup).atan();
        let lon = self.central_meridian_deg.to_radians() + sinh_e.atan2(cos_x);
        (lat, lon)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PROJ 9.5.1 (pyproj 3.7.2, from EPSG:4326): Paris, Zurich, 60 N on
    /// and 9 degrees (500 km) off a central meridian, Sydney, near the
    /// north pole, Web Mercator.
    const REFERENCE: [(u32, f64, f64, f64, f64); 9] = [
        (32631, 48.85826, 2.2945, 448_251.857_056_710_75, 5_411_939.347_352_915),
        (32632, 47.3769, 8.5417, 465_403.284_465_976_7, 5_247_150.839_424_513),
        (32633, 60.0, 15.0, 500_000.000_000_000_9, 6_651_411.190_362_714),
        (32633, 60.0, 24.0, 1_000_961.404_520_612_2, 6_685_590.893_531_71),
        (32756, -33.8568, 151.2153, 334_900.569_652_264_24, 6_252_288.752_888_294),
        (32601, 89.0, -170.0, 513_605.942_882_194_53, 9_887_147.804_654_438),
        (3857, 48.85826, 2.2945, 255_422.571_625_166_22, 6_250_845.213_714_003),
        (3857, -60.0, -170.0, -18_924_313.434_856_508, -8_399_737.889_818_357),
        (25832, 47.3769, 8.5417, 465_403.284_465_668_8, 5_247_150.839_302_885),
    ];

    #[test]
    fn forward_and_inverse_match_proj_to_a_millimetre() {
        for (epsg, lat, lon, x, y) in REFERENCE {
            let p = Projection::from_epsg(epsg).unwrap();
            let [fx, fy] = p.forward(lat.to_radians(), lon.to_radians());
            assert!((fx - x).abs() < 1e-3 && (fy - y).abs() < 1e-3, "{epsg}: {fx} {fy} vs {x} {y}");
            let (blat, blon) = p.inverse([x, y]);
            let metres = (blat.to_degrees() - lat).abs() * 111_000.0
                + (blon.to_degrees() - lon).abs() * 111_000.0 * lat.to_radians().cos();
            assert!(metres < 1e-3, "{epsg}: inverse off by {metres} m");
        }
    }

    #[test]
    fn unsupported_codes_are_named() {
        assert_eq!(Projection::from_epsg(2056), Err(UnsupportedEpsg(2056)));
        assert!(UnsupportedEpsg(2056).to_string().contains("EPSG:2056"));
    }

    /// Round trips over a whole UTM zone and 1000 km past it.
    #[test]
    fn round_trip_over_a_zone_and_beyond() {
        let p = Projection::from_epsg(32633).unwrap();
        for lat in (-80..=84).step_by(4) {
            for dlon in [-12.0, -3.0, 0.0, 0.5, 3.0, 9.0, 12.0] {
                let (lat, lon) = ((lat as f64).to_radians(), (15.0f64 + dlon).to_radians());
                let (blat, blon) = p.inverse(p.forward(lat, lon));
                assert!((blat - lat).abs() < 1e-12 && (blon - lon).abs() < 1e-12);
            }
        }
    }
}
