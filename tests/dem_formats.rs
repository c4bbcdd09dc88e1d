//! Round trips of the small formats (SRTM `.hgt`, DTED 0/1/2, ESRI ASCII
//! grid): synthesise a file, import it, compare heights, georeference, and
//! the filling of voids. GeoTIFF is in `dem_geotiff.rs`.

use proptest::prelude::*;
use ridgeline::dem::{dted, import_file, Format};
use ridgeline::geo::Crs;
use testkit::dem::*;

/// Heights before import in grid order, `None` for a void.
fn before_fill<T: Copy + PartialEq + Into<f64>>(heights: &[T], void: T) -> Vec<Option<f64>> {
    heights.iter().map(|&h| (h != void).then(|| h.into())).collect()
}

/// Voids used in the tile tests: an interior point, an interior block, a run
/// against the west edge and the south-west corner.
fn void_pattern(width: u32, height: u32) -> Vec<(u32, u32)> {
    let mut voids = vec![(width / 2, height / 3), (0, 0), (1, 0), (0, 1)];
    voids.extend((0..6).flat_map(|di| (0..4).map(move |dj| (width / 4 + di, height / 2 + dj))));
    voids.extend((10..20).map(|j| (0, j)));
    voids
}

#[test]
fn hgt_srtm3_round_trip_with_voids() {
    let dir = TempDir::new("hgt3");
    let side = 1201u32;
    let plane = |i: u32, j: u32| 500.0 + 2.0 * f64::from(i) + 3.0 * f64::from(j);
    let mut heights: Vec<i16> =
        (0..side * side).map(|k| plane(k % side, k / side) as i16).collect();
    for (i, j) in void_pattern(side, side) {
        heights[(j * side + i) as usize] = HGT_VOID;
    }
    let path = dir.path("N39E040.hgt");
    write_hgt(&path, side as usize, &heights);
    let grid = import_file(&path).unwrap();
    assert_eq!((grid.width, grid.height), (side, side));
    assert_eq!(grid.georef.crs, Crs::Geographic);
    assert_eq!(grid.georef.origin, [40.0, 39.0]);
    assert_eq!(grid.georef.spacing, [1.0 / 1200.0; 2]);
    check_filled(&grid, &before_fill(&heights, HGT_VOID), Some(&plane));
}

#[test]
fn hgt_srtm1_southern_western_tile() {
    let dir = TempDir::new("hgt1");
    let side = 3601u32;
    let heights: Vec<i16> = (0..side * side).map(|k| ((k % side) as i16 % 1000) - 20).collect();
    let path = dir.path("s05w072.hgt");
    write_hgt(&path, side as usize, &heights);
    let grid = import_file(&path).unwrap();
    assert_eq!((grid.width, grid.height), (side, side));
    assert_eq!(grid.georef.origin, [-72.0, -5.0]);
    assert_eq!(grid.georef.spacing, [1.0 / 3600.0; 2]);
    assert_eq!(grid.voids_filled, 0);
    let expected: Vec<f32> = heights.iter().map(|&h| f32::from(h)).collect();
    assert!(grid.heights == expected, "heights differ");
}

/// Writes a DTED file whose heights follow `plane` with the void pattern
/// and checks the import.
fn dted_round_trip(spec: DtedSpec, name: &str, plane: &dyn Fn(u32, u32) -> f64) {
    let dir = TempDir::new("dted");
    let mut heights: Vec<i32> = (0..spec.columns * spec.rows)
        .map(|k| plane(k % spec.columns, k / spec.columns) as i32)
        .collect();
    for (i, j) in void_pattern(spec.columns, spec.rows) {
        heights[(j * spec.columns + i) as usize] = DTED_VOID;
    }
    assert!(heights.iter().any(|&h| h < 0 && h != DTED_VOID), "test needs negative heights");
    let path = dir.path(name);
    std::fs::write(&path, dted_bytes(spec, &heights)).unwrap();
    let grid = import_file(&path).unwrap();
    assert_eq!((grid.width, grid.height), (spec.columns, spec.rows));
    assert_eq!(grid.georef.crs, Crs::Geographic);
    assert_eq!(grid.georef.origin, spec.origin.map(f64::from));
    let spacing = [spec.lon_tenths, spec.lat_tenths()].map(|t| f64::from(t) / 36_000.0);
    assert_eq!(grid.georef.spacing, spacing);
    check_filled(&grid, &before_fill(&heights, DTED_VOID), Some(plane));
}

#[test]
fn dted_level0_round_trip_negative_heights_and_voids() {
    let spec = DtedSpec { level: 0, origin: [40, 39], lon_tenths: 300, columns: 121, rows: 121 };
    dted_round_trip(spec, "e040_n39.dt0", &|i, j| -300.0 + f64::from(i) + f64::from(j));
}

#[test]
fn dted_level1_round_trip_in_the_6_second_zone() {
    // 55 N lies in zone II: longitude interval 6", 601 lines.
    let spec = DtedSpec { level: 1, origin: [10, 55], lon_tenths: 60, columns: 601, rows: 1201 };
    dted_round_trip(spec, "e010_n55.dt1", &|i, j| -100.0 + f64::from(i) + 2.0 * f64::from(j));
}

#[test]
fn dted_level2_round_trip_southern_western() {
    // Zone I is 1" by 1"; keep the test small with a partial cell of 301 lines.
    let spec = DtedSpec { level: 2, origin: [-30, -12], lon_tenths: 10, columns: 301, rows: 3601 };
    dted_round_trip(spec, "w030_s12.dt2", &|i, j| -50.0 + f64::from(i) + f64::from(j));
}

#[test]
fn dted_signed_magnitude_is_not_twos_complement() {
    assert_eq!(dted::signed_magnitude(0x0005), 5);
    assert_eq!(dted::signed_magnitude(0x8005), -5);
    assert_eq!(dted::signed_magnitude(0x8000), 0);
    assert_eq!(dted::signed_magnitude(0x7FFF), 32767);
    assert_eq!(dted::signed_magnitude(0xFFFF), dted::VOID);
    for h in [-32766, -418, -1, 0, 1, 8848, 32767] {
        assert_eq!(dted::signed_magnitude(signed_magnitude(h)), h);
    }
}

#[test]
fn dted_with_tape_labels_and_detected_by_magic() {
    let dir = TempDir::new("dted-labels");
    let spec = DtedSpec { level: 0, origin: [7, 46], lon_tenths: 300, columns: 121, rows: 121 };
    let heights: Vec<i32> = (0..121 * 121).map(|k| 400 + k % 121).collect();
    let mut bytes = format!("VOL1{:76}HDR1{:76}", "", "").into_bytes();
    bytes.extend(dted_bytes(spec, &heights));
    let path = dir.path("alps.bin");
    std::fs::write(&path, bytes).unwrap();
    assert_eq!(ridgeline::dem::format::detect(&path).unwrap(), Format::Dted);
    let grid = import_file(&path).unwrap();
    assert_eq!(grid.at(120, 0), 520.0);
    assert_eq!(grid.georef.origin, [7.0, 46.0]);
}

#[test]
fn ascii_grid_corner_header_with_nodata() {
    let dir = TempDir::new("asc");
    let path = dir.path("dem.asc");
    let header =
        "ncols 4\nNROWS 3\nxllcorner 1000\nyllcorner 2000\ncellsize 30\nNODATA_value -9999\n";
    // North row first.
    let rows = ["1.5 2 3 4", "5 -9999 7 8", "9 10 11 12.25"];
    let rows: Vec<Vec<String>> =
        rows.iter().map(|r| r.split(' ').map(String::from).collect()).collect();
    write_ascii(&path, header, &rows);
    let grid = import_file(&path).unwrap();
    assert_eq!((grid.width, grid.height), (4, 3));
    assert_eq!(grid.georef.crs, Crs::Local);
    assert_eq!(grid.georef.origin, [1015.0, 2015.0]);
    assert_eq!(grid.georef.spacing, [30.0, 30.0]);
    assert_eq!(grid.at(0, 2), 1.5);
    assert_eq!(grid.at(3, 0), 12.25);
    assert_eq!(grid.voids_filled, 1);
    // The void at (1, 1) sits between 5 and 7 (row) and 2 and 10 (column).
    assert_close(f64::from(grid.at(1, 1)), (5.0 + 7.0 + 2.0 + 10.0) / 4.0, 1e-6, "filled");
}

#[test]
fn ascii_grid_center_header_dx_dy_and_prj_sidecar() {
    let dir = TempDir::new("asc-prj");
    let path = dir.path("geo.txt");
    let header = "NCOLS 3\nNROWS 2\nXLLCENTER -71.5\nYLLCENTER -5.25\nDX 0.5\nDY 0.25\n";
    let rows =
        vec![vec!["1".into(), "2".into(), "3".into()], vec!["4".into(), "5".into(), "6".into()]];
    write_ascii(&path, header, &rows);
    std::fs::write(dir.path("geo.prj"), "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\"]]").unwrap();
    assert_eq!(ridgeline::dem::format::detect(&path).unwrap(), Format::AsciiGrid);
    let grid = import_file(&path).unwrap();
    assert_eq!(grid.georef.crs, Crs::Geographic);
    assert_eq!(grid.georef.origin, [-71.5, -5.25]);
    assert_eq!(grid.georef.spacing, [0.5, 0.25]);
    assert_eq!(grid.heights, vec![4.0, 5.0, 6.0, 1.0, 2.0, 3.0]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Any grid written as text, with any whitespace between values, reads
    /// back exactly (values are f32, written with enough digits).
    #[test]
    fn ascii_grid_round_trips(
        width in 1u32..12,
        height in 1u32..12,
        seed in any::<u64>(),
        separator in prop::sample::select(vec![" ", "  ", "\t", "\n", " \r\n "]),
    ) {
        let dir = TempDir::new("asc-prop");
        let path = dir.path("p.asc");
        let value = |k: u64| ((k.wrapping_mul(6364136223846793005).wrapping_add(seed) >> 40) as f32) / 256.0 - 9000.0;
        let header = format!("ncols {width}\nnrows {height}\nxllcorner 0\nyllcorner 0\ncellsize 10\n");
        let rows: Vec<Vec<String>> = (0..height)
            .map(|r| (0..width).map(|c| format!("{:?}", value(u64::from(r * width + c)))).collect())
            .collect();
        let text = rows.iter().map(|r| r.join(separator)).collect::<Vec<_>>().join(separator);
        std::fs::write(&path, header + &text).unwrap();
        let grid = import_file(&path).unwrap();
        for r in 0..height {
            for c in 0..width {
                prop_assert_eq!(grid.at(c, height - 1 - r), value(u64::from(r * width + c)));
            }
        }
    }
}
