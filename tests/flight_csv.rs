//! The camera path CSV: both headers, any column order, every refused input
//! named with file, row and column, writing and reading back, the file reader,
//! and the latitude/longitude mapping.

use std::path::Path;

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use ridgeline::flight::{
    geographic_to_local, local_to_geographic, FlightPath, PathProblem, Pose, Waypoint,
};
use ridgeline::geo::metres_per_degree;
use ridgeline::geo::{Crs, GeoRef};

const FILE: &str = "approach.csv";
const EXTENT: [u32; 2] = [1201, 1201];

fn local() -> GeoRef {
    GeoRef::local([30.0, 30.0])
}

fn geographic() -> GeoRef {
    GeoRef { crs: Crs::Geographic, origin: [40.0, 39.0], spacing: [1.0 / 1200.0, 1.0 / 1200.0] }
}

fn parse(text: &str, georef: &GeoRef) -> Result<FlightPath, ridgeline::flight::PathError> {
    FlightPath::parse_csv(Path::new(FILE), text, georef, EXTENT)
}

fn pose(x: f64, y: f64, alt: f64, heading: f64, pitch: f64, roll: f64) -> Pose {
    Pose { position: DVec3::new(x, y, alt), heading_deg: heading, pitch_deg: pitch, roll_deg: roll }
}

#[test]
fn xy_header_gives_the_rows_in_order() {
    let path = parse(
        "t,x,y,alt,heading,pitch,roll\n0,100,200,1500,45,-3,0\n10,1100,1200,1400,50,-2.5,10\n",
        &local(),
    )
    .unwrap();
    let waypoints = path.waypoints();
    assert_eq!(waypoints.len(), 2);
    assert_eq!(
        waypoints[0],
        Waypoint { t: 0.0, pose: pose(100.0, 200.0, 1500.0, 45.0, -3.0, 0.0) }
    );
    assert_eq!(
        waypoints[1],
        Waypoint { t: 10.0, pose: pose(1100.0, 1200.0, 1400.0, 50.0, -2.5, 10.0) }
    );
}

#[test]
fn columns_may_come_in_any_order_case_and_spacing_with_comments_bom_and_crlf() {
    let text = "\u{feff}# my path\r\n\r\n  Roll , PITCH,heading , alt,y, x ,t\r\n# a comment row\r\n 0 , -3 ,45, 1500 ,200,100, 0\r\n";
    let path = parse(text, &local()).unwrap();
    assert_eq!(
        path.waypoints(),
        &[Waypoint { t: 0.0, pose: pose(100.0, 200.0, 1500.0, 45.0, -3.0, 0.0) }]
    );
}

#[test]
fn lat_lon_header_maps_through_the_equirectangular_frame() {
    let georef = geographic();
    let text =
        "lon,lat,t,alt,heading,pitch,roll\n40.25,39.5,0,2000,90,0,0\n40.0,39.0,1,2000,90,0,0\n";
    let path = parse(text, &georef).unwrap();
    let expected = geographic_to_local(&georef, EXTENT, 39.5, 40.25);
    assert_eq!(path.waypoints()[0].pose.position, expected.extend(2000.0));
    assert_eq!(
        path.waypoints()[1].pose.position,
        DVec3::new(0.0, 0.0, 2000.0),
        "the SW sample is the origin"
    );
    // Centre latitude of this grid is 39.5: half a degree north, a quarter degree east.
    let [east, north] = metres_per_degree(39.5);
    assert!((expected.y - north / 2.0).abs() < 1e-6);
    assert!((expected.x - east / 4.0).abs() < 1e-6);
}

/// Every refused input, with the words its message must hold besides the file.
fn bad_inputs() -> Vec<(&'static str, String, GeoRef, Vec<&'static str>)> {
    let xy = "t,x,y,alt,heading,pitch,roll";
    let good = "0,100,200,1500,45,-3,0";
    let row = |cells: &str| format!("{xy}\n{good}\n{cells}\n");
    let geo = geographic();
    let projected = GeoRef {
        crs: Crs::Projected { epsg: Some(32637) },
        origin: [0.0, 0.0],
        spacing: [30.0, 30.0],
    };
    vec![
        ("empty file", String::new(), local(), vec!["no header"]),
        ("only comments", "# nothing\n\n".into(), local(), vec!["no header"]),
        ("no rows", format!("{xy}\n"), local(), vec!["no rows", "line 1"]),
        (
            "unknown column",
            "t,x,y,alt,heading,pitch,roll,speed\n".into(),
            local(),
            vec!["header", "column 8", "`speed`"],
        ),
        (
            "missing column",
            "t,x,y,alt,heading,pitch\n".into(),
            local(),
            vec!["header", "`roll`", "missing"],
        ),
        (
            "duplicate column",
            "t,x,y,alt,heading,pitch,pitch,roll\n".into(),
            local(),
            vec!["header", "`pitch`", "twice"],
        ),
        (
            "x with lat",
            "t,x,lat,alt,heading,pitch,roll\n".into(),
            geo,
            vec!["header", "`x,y`", "`lat,lon`"],
        ),
        (
            "lat/lon on local data",
            "t,lat,lon,alt,heading,pitch,roll\n1,2,3,4,5,6,7\n".into(),
            local(),
            vec!["header", "`lat,lon`", "local grid"],
        ),
        (
            "lat/lon on projected data",
            "t,lat,lon,alt,heading,pitch,roll\n".into(),
            projected,
            vec!["header", "`lat,lon`", "EPSG:32637"],
        ),
        (
            "not a number",
            row("1,100,200,1500,45,abc,0"),
            local(),
            vec!["row 2", "line 3", "`pitch`", "`abc` is not a number"],
        ),
        (
            "NaN",
            row("1,NaN,200,1500,45,-3,0"),
            local(),
            vec!["row 2", "`x`", "`NaN` is not a finite"],
        ),
        (
            "infinity",
            row("1,100,200,inf,45,-3,0"),
            local(),
            vec!["row 2", "`alt`", "`inf` is not a finite"],
        ),
        (
            "minus infinity",
            row("1,100,-infinity,1500,45,-3,0"),
            local(),
            vec!["row 2", "`y`", "not a finite"],
        ),
        (
            "overflow to infinity",
            row("1e400,100,200,1500,45,-3,0"),
            local(),
            vec!["row 2", "`t`", "`1e400` is not a finite"],
        ),
        ("empty cell", row("1,100,,1500,45,-3,0"), local(), vec!["row 2", "`y`", "empty"]),
        ("too few cells", row("1,100,200,1500,45"), local(), vec!["row 2", "`pitch`", "5 cells"]),
        (
            "too many cells",
            row("1,100,200,1500,45,-3,0,9"),
            local(),
            vec!["row 2", "column 8", "8 cells"],
        ),
        (
            "same time",
            row("0,100,200,1500,45,-3,0"),
            local(),
            vec!["row 2", "`t`", "strictly increase"],
        ),
        (
            "time going back",
            row("-1,100,200,1500,45,-3,0"),
            local(),
            vec!["row 2", "`t`", "strictly increase"],
        ),
        ("absurd time", row("1e8,100,200,1500,45,-3,0"), local(), vec!["row 2", "`t`", "outside"]),
        (
            "pitch beyond vertical",
            row("1,100,200,1500,45,95,0"),
            local(),
            vec!["row 2", "`pitch`", "outside [-90, 90]"],
        ),
        (
            "pitch below vertical",
            row("1,100,200,1500,45,-90.5,0"),
            local(),
            vec!["row 2", "`pitch`", "outside"],
        ),
        (
            "roll",
            row("1,100,200,1500,45,-3,181"),
            local(),
            vec!["row 2", "`roll`", "outside [-180, 180]"],
        ),
        ("heading", row("1,100,200,1500,400,-3,0"), local(), vec!["row 2", "`heading`", "outside"]),
        ("altitude", row("1,100,200,200000,45,-3,0"), local(), vec!["row 2", "`alt`", "outside"]),
        ("position", row("1,6e7,200,1500,45,-3,0"), local(), vec!["row 2", "`x`", "outside"]),
        (
            "latitude",
            "t,lat,lon,alt,heading,pitch,roll\n0,39.5,40.5,1500,0,0,0\n1,91,40.5,1500,0,0,0\n"
                .into(),
            geographic(),
            vec!["row 2", "`lat`", "outside [-90, 90]"],
        ),
        (
            // [-180, 180] and [0, 360] are both read (and one turn past
            // them, across a seam); beyond that is a typing error.
            "longitude",
            "t,lat,lon,alt,heading,pitch,roll\n0,39.5,-360.5,1500,0,0,0\n".into(),
            geographic(),
            vec!["row 1", "`lon`", "outside [-360, 360]"],
        ),
    ]
}

#[test]
fn every_bad_input_is_refused_naming_file_row_and_column() {
    for (name, text, georef, words) in bad_inputs() {
        let message = match parse(&text, &georef) {
            Ok(path) => panic!("{name}: accepted as {path:?}"),
            Err(error) => error.to_string(),
        };
        assert!(message.contains(FILE), "{name}: {message}");
        for word in words {
            assert!(message.contains(word), "{name}: {message:?} lacks {word:?}");
        }
    }
}

#[test]
fn written_csv_reads_back_as_the_same_path() {
    let path = FlightPath::new(vec![
        Waypoint { t: -0.5, pose: pose(0.1, 1e-7, 1234.5678, 359.99, -89.5, 179.0) },
        Waypoint { t: 1.0 / 3.0, pose: pose(-2.0e7, 123456.789, -10.0, -360.0, 90.0, -180.0) },
    ])
    .unwrap();
    assert_eq!(parse(&path.to_csv(), &local()).unwrap(), path);
}

fn waypoints() -> impl Strategy<Value = Vec<Waypoint>> {
    let value = |range: std::ops::RangeInclusive<f64>| range;
    let row = (
        0.001..100.0,
        (value(-2.5e7..=2.5e7), value(-2.5e7..=2.5e7), value(-11_000.0..=100_000.0)),
        (value(-360.0..=360.0), value(-90.0..=90.0), value(-180.0..=180.0)),
    );
    prop::collection::vec(row, 1..20).prop_map(|rows| {
        let mut t = -50.0;
        rows.into_iter()
            .map(|(dt, (x, y, alt), (heading, pitch, roll))| {
                t += dt;
                Waypoint { t, pose: pose(x, y, alt, heading, pitch, roll) }
            })
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn any_valid_path_round_trips_through_csv(waypoints in waypoints()) {
        let path = FlightPath::new(waypoints).unwrap();
        prop_assert_eq!(parse(&path.to_csv(), &local()).unwrap(), path);
    }

    #[test]
    fn lat_lon_round_trips_through_local_metres(lat in -60.0..60.0f64, lon in -179.9..179.9f64, south in -70.0..69.0f64) {
        let georef = GeoRef { crs: Crs::Geographic, origin: [lon.floor(), south], spacing: [1.0 / 3600.0, 1.0 / 3600.0] };
        let local = geographic_to_local(&georef, [3601, 3601], lat, lon);
        let back = local_to_geographic(&georef, [3601, 3601], local);
        prop_assert!((back.lat - lat).abs() < 1e-9 && (back.lon - lon).abs() < 1e-9, "{lat} {lon} -> {local} -> {back:?}");
        let again = geographic_to_local(&georef, [3601, 3601], back.lat, back.lon);
        prop_assert!((again - local).length() < 1e-6);
    }
}

#[test]
fn samples_land_on_the_spacing_the_pyramid_uses() {
    let georef = geographic();
    let spacing_m = georef.spacing_m(EXTENT);
    for (i, j) in [(0u32, 0u32), (1, 0), (0, 1), (600, 600), (1200, 37), (5, 1200)] {
        let lon = georef.origin[0] + i as f64 * georef.spacing[0];
        let lat = georef.origin[1] + j as f64 * georef.spacing[1];
        let local = geographic_to_local(&georef, EXTENT, lat, lon);
        let expected = DVec2::new(i as f64 * spacing_m[0], j as f64 * spacing_m[1]);
        assert!((local - expected).length() < 1e-6, "sample ({i}, {j}): {local} vs {expected}");
    }
    // Three arc-seconds at 39.5 N on WGS 84: 92.52 m north, 71.68 m east.
    assert!(
        (spacing_m[1] - 92.52).abs() < 0.01 && (spacing_m[0] - 71.68).abs() < 0.01,
        "{spacing_m:?}"
    );
}

#[test]
fn longitudes_across_the_antimeridian_stay_neighbours() {
    let georef = GeoRef {
        crs: Crs::Geographic,
        origin: [179.5, 0.0],
        spacing: [1.0 / 1200.0, 1.0 / 1200.0],
    };
    let local = geographic_to_local(&georef, [1201, 1], 0.0, -179.75);
    assert!((local.x - 0.75 * metres_per_degree(0.0)[0]).abs() < 1e-6, "{local}");
    let back = local_to_geographic(&georef, [1201, 1], local);
    assert!((back.lon + 179.75).abs() < 1e-9, "{back:?}");
}

#[test]
fn read_names_the_file_and_refuses_oversized_ones_before_reading() {
    let dir = std::env::temp_dir().join(format!("ridgeline-flight-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("good.csv");
    std::fs::write(&good, "t,x,y,alt,heading,pitch,roll\n0,1,2,3,4,5,6\n").unwrap();
    assert_eq!(FlightPath::read(&good, &local(), EXTENT).unwrap().waypoints().len(), 1);

    let huge = dir.join("huge.csv");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(ridgeline::flight::csv::MAX_FILE_BYTES + 1)
        .unwrap();
    let error = FlightPath::read(&huge, &local(), EXTENT).unwrap_err();
    assert!(matches!(error.problem, PathProblem::TooLarge { .. }), "{error}");
    assert!(error.to_string().contains("huge.csv"));

    let missing = dir.join("missing.csv");
    let error = FlightPath::read(&missing, &local(), EXTENT).unwrap_err();
    assert!(
        matches!(error.problem, PathProblem::Io(_)) && error.to_string().contains("missing.csv"),
        "{error}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
