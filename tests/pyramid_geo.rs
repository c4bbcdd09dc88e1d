//! Degrees to metres for the pyramid's local frame, against published WGS 84
//! lengths of a degree.

use ridgeline::geo::{Crs, GeoRef};

fn geographic(origin: [f64; 2], spacing: [f64; 2]) -> GeoRef {
    GeoRef { crs: Crs::Geographic, origin, spacing }
}

#[test]
fn a_degree_has_its_wgs84_length_at_the_centre_latitude() {
    // Lengths of one degree (m): equator 111 319.49 east, 110 574.27 north;
    // 45° 78 846.84 east, 111 131.75 north; 60° 55 799.98 east, 111 412.24 north.
    let cases = [
        (0.0, 111_319.49, 110_574.27),
        (45.0, 78_846.84, 111_131.75),
        (60.0, 55_799.98, 111_412.24),
    ];
    for (lat, east, north) in cases {
        // Three samples one degree apart centred on `lat`.
        let spacing = geographic([10.0, lat - 1.0], [1.0, 1.0]).spacing_m([3, 3]);
        assert!((spacing[0] - east).abs() < 0.05, "{lat}: east {} vs {east}", spacing[0]);
        assert!((spacing[1] - north).abs() < 0.05, "{lat}: north {} vs {north}", spacing[1]);
    }
}

#[test]
fn planar_spacing_is_already_metres_and_has_no_degrees() {
    let utm = GeoRef {
        crs: Crs::Projected { epsg: Some(32632) },
        origin: [5e5, 5e6],
        spacing: [25.0, 30.0],
    };
    assert_eq!(utm.spacing_m([10, 10]), [25.0, 30.0]);
    assert_eq!(utm.bounds_deg([10, 10]), None);
    assert_eq!(GeoRef::local([2.0, 3.0]).spacing_m([5, 5]), [2.0, 3.0]);
}

#[test]
fn bounds_span_the_outermost_posts() {
    let srtm =
        geographic([40.0, 39.0], [1.0 / 1200.0; 2]).bounds_deg([1201, 1201]).expect("geographic");
    assert_eq!((srtm.west, srtm.south), (40.0, 39.0));
    assert!((srtm.east - 41.0).abs() < 1e-12 && (srtm.north - 40.0).abs() < 1e-12);
}

#[test]
fn impossible_georeferences_are_named() {
    assert!(geographic([0.0, 89.5], [0.1, 0.1]).problem([3, 20]).is_some(), "past the pole");
    assert!(geographic([0.0, 0.0], [0.0, 0.1]).problem([3, 3]).is_some(), "zero spacing");
    assert!(geographic([f64::NAN, 0.0], [0.1, 0.1]).problem([3, 3]).is_some(), "NaN origin");
    assert!(geographic([0.0, 10.0], [0.1, 0.1]).problem([3, 3]).is_none());
}
