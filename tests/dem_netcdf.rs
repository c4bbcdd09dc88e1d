//! netCDF-3 grids: a round trip through the `netcdf3` crate's writer, the
//! ETOPO5 georeference rules (drifting coordinates, south row first), the
//! committed ETOPO5 crop, and bad input (truncated, corrupt header, NaN and
//! infinite values, absurd sizes), each refused with an error naming the file.
//! Also the ESRI ASCII grid in degrees without a `.prj`.

use std::path::Path;

use netcdf3::{DataSet, FileWriter, Version};
use ridgeline::dem::{read_raw, Problem};
use ridgeline::geo::Crs;
use testkit::dem::*;

/// Writes a classic netCDF-3 grid `ROSE(lat, lon)`, south row first, with
/// coordinates `lat0 + j * step` and `lon0 + i * step` (plus `drift`).
fn write_grid(path: &Path, size: [usize; 2], origin: [f64; 2], step: f64, heights: &[f32]) {
    let [columns, rows] = size;
    let mut data_set = DataSet::new();
    data_set.add_fixed_dim("lat", rows).unwrap();
    data_set.add_fixed_dim("lon", columns).unwrap();
    data_set.add_var_f64("lat", &["lat"]).unwrap();
    data_set.add_var_f64("lon", &["lon"]).unwrap();
    data_set.add_var_f32("ROSE", &["lat", "lon"]).unwrap();
    data_set.add_var_attr_f32("ROSE", "_FillValue", vec![-1e34]).unwrap();
    let _ = std::fs::remove_file(path);
    let mut writer = FileWriter::create_new(path).unwrap();
    writer.set_def(&data_set, Version::Classic, 0).unwrap();
    // Coordinates drift like ETOPO5's f32 ones, by up to a twentieth of a step.
    let coordinate = |o: f64, n: usize| -> Vec<f64> {
        (0..n).map(|k| o + k as f64 * step + 0.05 * step * (k as f64 * 0.7).sin()).collect()
    };
    writer.write_var_f64("lat", &coordinate(origin[1], rows)).unwrap();
    writer.write_var_f64("lon", &coordinate(origin[0], columns)).unwrap();
    writer.write_var_f32("ROSE", heights).unwrap();
    writer.close().unwrap();
}

fn ramp(size: [usize; 2]) -> Vec<f32> {
    (0..size[0] * size[1]).map(|k| (k % size[0]) as f32 * 10.0 + (k / size[0]) as f32).collect()
}

#[test]
fn a_grid_round_trips_with_a_snapped_georeference() {
    let dir = TempDir::new("nc-round");
    let path = dir.path("grid.nc");
    let size = [13, 7];
    write_grid(&path, size, [37.0, 39.0], 1.0 / 12.0, &ramp(size));
    let grid = read_raw(&path).unwrap();
    assert_eq!((grid.width, grid.height), (13, 7));
    assert_eq!(grid.georef.crs, Crs::Geographic);
    assert_eq!(grid.georef.spacing, [1.0 / 12.0; 2]);
    assert_eq!(grid.georef.origin, [37.0, 39.0]);
    assert_eq!(grid.heights[grid.index(3, 2)], 32.0);
}

#[test]
fn the_committed_etopo5_crop_is_georeferenced_around_the_srtm_tile() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/dem/etopo5_e37_e44_n37_n42.nc");
    let grid = read_raw(&path).unwrap();
    assert_eq!(grid.georef.spacing, [1.0 / 12.0; 2]);
    assert_eq!(grid.georef.origin, [37.0, 37.0]);
    assert_eq!((grid.width, grid.height), (85, 67));
    assert_eq!(grid.void_count(), 0);
    // The Black Sea in the north-west corner, land around the SRTM tile.
    let at = |lon: f64, lat: f64| {
        let (i, j) = (((lon - 37.0) * 12.0).round() as u32, ((lat - 37.0) * 12.0).round() as u32);
        grid.heights[grid.index(i, j)]
    };
    assert!(at(37.9, 42.5) < -1500.0, "Black Sea {}", at(37.9, 42.5));
    for (lon, lat) in [(40.0, 39.25), (40.5, 39.5), (40.75, 39.9)] {
        assert!((1000.0..3500.0).contains(&at(lon, lat)), "({lon}, {lat}) {}", at(lon, lat));
    }
}

/// Writes the committed crop from Debian's ETOPO5 (`ferret-datasets`):
/// `ETOPO5=/usr/share/ferret-vis/data/etopo5.cdf cargo test --test dem_netcdf -- --ignored`.
#[test]
#[ignore]
fn make_etopo5_crop() {
    // 37..44 E, 37..42.5 N
    crop_etopo5([37 * 12, (37 + 90) * 12], [7 * 12 + 1, 5 * 12 + 7], "etopo5_e37_e44_n37_n42.nc");
}

/// Cuts the regional database of `tests/earth_truth.rs` and the
/// accuracy runs at 45-47 N (the Alps, Zurich to Nice: 5-11 E, 43.5-47.5 N)
/// out of the global ETOPO5 grid. Run once by hand, as above.
#[test]
#[ignore = "needs ETOPO5=/usr/share/ferret-vis/data/etopo5.cdf (ferret-datasets)"]
fn make_etopo5_alps_crop() {
    crop_etopo5([5 * 12, (43 + 90) * 12 + 6], [6 * 12 + 1, 4 * 12 + 1], "etopo5_e5_e11_n43_n47.nc");
}

/// Writes `size` posts of the global ETOPO5 grid from post `[i0, j0]`
/// (columns from 0 E, rows from 90 S, 12 a degree) to `assets/dem/name`.
fn crop_etopo5([i0, j0]: [u32; 2], size: [usize; 2], name: &str) {
    let source = std::env::var("ETOPO5").expect("ETOPO5=path/to/etopo5.cdf");
    let global = read_raw(Path::new(&source)).unwrap();
    assert_eq!((global.width, global.height), (4320, 2161));
    assert_eq!(global.georef.origin, [0.0, -90.0]);
    let mut heights = Vec::new();
    for j in 0..size[1] {
        for i in 0..size[0] {
            heights.push(global.heights[global.index(i0 + i as u32, j0 + j as u32)]);
        }
    }
    let origin = [i0 as f64 / 12.0, j0 as f64 / 12.0 - 90.0];
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/dem").join(name);
    write_grid(&out, size, origin, 1.0 / 12.0, &heights);
}

// ------------------------------------------------------------- bad input

fn good_file(dir: &TempDir, name: &str) -> (std::path::PathBuf, Vec<u8>) {
    let path = dir.path(name);
    let size = [9, 5];
    write_grid(&path, size, [37.0, 39.0], 1.0 / 12.0, &ramp(size));
    let bytes = std::fs::read(&path).unwrap();
    (path, bytes)
}

#[test]
fn truncated_netcdf_is_refused() {
    let dir = TempDir::new("nc-trunc");
    let (path, bytes) = good_file(&dir, "short.nc");
    for keep in [bytes.len() - 4, bytes.len() / 2, 40, 3, 0] {
        std::fs::write(&path, &bytes[..keep]).unwrap();
        let problem = import_error(&path);
        assert!(
            matches!(
                problem,
                Problem::Truncated { .. }
                    | Problem::NetCdf(_)
                    | Problem::Header(_)
                    | Problem::BadMagic { .. }
            ),
            "{keep}: {problem:?}"
        );
    }
}

#[test]
fn corrupt_netcdf_headers_are_refused_without_panic() {
    let dir = TempDir::new("nc-corrupt");
    let (path, bytes) = good_file(&dir, "bad.nc");
    let mut wrong = bytes.clone();
    wrong[0] = b'X';
    std::fs::write(&path, &wrong).unwrap();
    assert!(matches!(import_error(&path), Problem::BadMagic { format: "netCDF-3", .. }));
    // Every header byte flipped in turn: an error or a grid, never a panic.
    let header_len = bytes.len() - 9 * 5 * 4 - (9 + 5) * 8;
    for at in 4..header_len {
        let mut bad = bytes.clone();
        bad[at] ^= 0xFF;
        std::fs::write(&path, &bad).unwrap();
        if let Err(err) = read_raw(&path) {
            assert_eq!(err.path, path, "byte {at}");
        }
    }
}

#[test]
fn absurd_netcdf_sizes_are_refused_before_allocating() {
    let dir = TempDir::new("nc-huge");
    let (path, bytes) = good_file(&dir, "huge.nc");
    // The header's dim list: "lat" size 5 and "lon" size 9 as big-endian u32s.
    let mut bad = bytes.clone();
    let at = bytes.windows(4).position(|w| w == [0, 0, 0, 9]).expect("lon size");
    bad[at..at + 4].copy_from_slice(&100_000u32.to_be_bytes());
    let at5 = bytes.windows(4).position(|w| w == [0, 0, 0, 5]).expect("lat size");
    bad[at5..at5 + 4].copy_from_slice(&100_000u32.to_be_bytes());
    std::fs::write(&path, &bad).unwrap();
    let problem = import_error(&path);
    assert!(
        matches!(
            problem,
            Problem::AbsurdDimensions { .. } | Problem::Truncated { .. } | Problem::NetCdf(_)
        ),
        "{problem:?}"
    );
}

#[test]
fn nan_and_infinite_netcdf_heights_are_refused() {
    let dir = TempDir::new("nc-nan");
    let size = [4, 3];
    for (name, value) in [("nan.nc", f32::NAN), ("inf.nc", f32::INFINITY)] {
        let mut heights = ramp(size);
        heights[5] = value;
        let path = dir.path(name);
        write_grid(&path, size, [37.0, 39.0], 1.0 / 12.0, &heights);
        assert!(
            matches!(import_error(&path), Problem::NonFinite { row: 1, column: 1, .. }),
            "{name}"
        );
    }
    // The declared fill is a void, not an error.
    let mut heights = ramp(size);
    heights[5] = -1e34;
    let path = dir.path("fill.nc");
    write_grid(&path, size, [37.0, 39.0], 1.0 / 12.0, &heights);
    assert_eq!(read_raw(&path).unwrap().void_count(), 1);
}

// ----------------------------------------------- ASCII grid in degrees

#[test]
fn an_ascii_grid_in_degrees_without_prj_is_refused_saying_how_to_fix_it() {
    let dir = TempDir::new("asc-degrees");
    let path = dir.path("n39e040.asc");
    let header = "ncols 3\nnrows 2\nxllcorner 40.0\nyllcorner 39.0\ncellsize 0.000833333\n";
    std::fs::write(&path, format!("{header}1 2 3\n4 5 6\n")).unwrap();
    let err = ridgeline::dem::import_file(&path).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err.problem, Problem::DegreesWithoutPrj { .. }));
    assert!(message.contains("n39e040.asc") && message.contains(".prj"), "{message}");
    assert!(message.contains("GEOGCS"), "{message}");
    // With a GEOGCS sidecar the same grid is read, in degrees.
    std::fs::write(path.with_extension("prj"), "GEOGCS[\"WGS 84\"]").unwrap();
    assert_eq!(ridgeline::dem::import_file(&path).unwrap().georef.crs, Crs::Geographic);
}
