//! Decoding by swaths (`ridgeline::dem::swath`): every streaming format,
//! decoded in swaths far smaller than the file (one row, record, strip or
//! tile at a time), gives bit for bit the heights of one swath covering
//! the whole file, and those are the heights written; the committed real
//! files (GeoTIFFs, ETOPO5 netCDF, ASCII grid) agree the same way.

use std::path::{Path, PathBuf};

use ridgeline::dem::open::{open, read_whole};
use testkit::dem::*;
use tiff::encoder::{colortype, Compression, DeflateLevel, Predictor};

/// Decodes `path` in swaths of `swath_bytes`; returns the heights and
/// the number of swaths.
fn decode(path: &Path, swath_bytes: usize) -> (Vec<f32>, usize) {
    let opened = open(path).unwrap();
    let [w, h] = opened.footprint().size;
    let mut heights = vec![0.0f32; w as usize * h as usize];
    let mut swaths = 0;
    opened.read_into(&mut heights, swath_bytes, &mut || swaths += 1).unwrap();
    (heights, swaths)
}

/// Small swaths and one swath agree bit for bit (NaN voids included),
/// the small ones were many, and both match `expected` when given.
fn check_swaths(path: &Path, expected: Option<&[f32]>) {
    let (small, many) = decode(path, 1);
    let (whole, one) = decode(path, usize::MAX);
    assert!(many > 4, "{}: {many} small swaths", path.display());
    assert!(one <= 2, "{}: {one} swaths of the whole file", path.display());
    let bits = |v: &[f32]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&small), bits(&whole), "{}", path.display());
    if let Some(expected) = expected {
        assert_eq!(bits(&small), bits(expected), "{}", path.display());
    }
    let heap = read_whole(open(path).unwrap()).unwrap();
    assert_eq!(bits(&heap.heights), bits(&whole), "{}: the in-memory read", path.display());
}

/// A height per grid post (row 0 south), some of them voids.
fn height(i: u32, j: u32) -> Option<i16> {
    ((i * 7 + j * 13) % 97 != 5).then_some(((i * 37 + j * 101) % 3000) as i16 - 200)
}

fn grid(w: u32, h: u32) -> Vec<Option<i16>> {
    (0..h).flat_map(|j| (0..w).map(move |i| height(i, j))).collect()
}

fn as_f32(values: &[Option<i16>]) -> Vec<f32> {
    values.iter().map(|v| v.map_or(f32::NAN, f32::from)).collect()
}

/// File order (first row north) of a grid in grid order.
fn north_first<T: Copy>(values: &[T], w: u32) -> Vec<T> {
    values.chunks(w as usize).rev().flatten().copied().collect()
}

#[test]
fn hgt_swaths_match_the_whole_file() {
    let dir = TempDir::new("swath-hgt");
    let path = dir.path("N10E020.hgt");
    let values = grid(1201, 1201);
    let raw: Vec<i16> = values.iter().map(|v| v.unwrap_or(HGT_VOID)).collect();
    write_hgt(&path, 1201, &raw);
    check_swaths(&path, Some(&as_f32(&values)));
}

#[test]
fn dted_swaths_match_the_whole_file() {
    let dir = TempDir::new("swath-dted");
    let path = dir.path("e020n10.dt0");
    let spec = DtedSpec { level: 0, origin: [20, 10], lon_tenths: 300, columns: 121, rows: 121 };
    let values = grid(121, 121);
    let raw: Vec<i32> = values.iter().map(|v| v.map_or(DTED_VOID, i32::from)).collect();
    std::fs::write(&path, dted_bytes(spec, &raw)).unwrap();
    check_swaths(&path, Some(&as_f32(&values)));
}

#[test]
fn geotiff_strip_and_tile_swaths_match_the_whole_file() {
    let dir = TempDir::new("swath-tif");
    let (w, h) = (301u32, 203u32);
    let values = grid(w, h);
    let geo = GeoTags {
        nodata: Some("-32768".into()),
        ..GeoTags::geographic([20.0, 11.0], 1.0 / 1200.0, false)
    };
    let file: Vec<i16> = north_first(&values, w).iter().map(|v| v.unwrap_or(-32768)).collect();
    let strips = dir.path("strips.tif");
    let deflate = Compression::Deflate(DeflateLevel::Fast);
    write_tiff_strips::<colortype::GrayI16>(
        &strips,
        [w, h],
        &file,
        deflate,
        Predictor::Horizontal,
        3,
        &geo,
    );
    check_swaths(&strips, Some(&as_f32(&values)));
    let tiles = dir.path("tiles.tif");
    let samples = Samples::I16(file);
    write_tiff_tiles(&tiles, [w, h], 32, &samples, TileCompression::Lzw, 2, &geo);
    check_swaths(&tiles, Some(&as_f32(&values)));
}

#[test]
fn ascii_grid_swaths_match_the_whole_file() {
    let dir = TempDir::new("swath-asc");
    let path = dir.path("grid.asc");
    let (w, h) = (157u32, 91u32);
    let values = grid(w, h);
    let rows: Vec<Vec<String>> = north_first(&values, w)
        .chunks(w as usize)
        .map(|r| r.iter().map(|v| v.map_or("-9999".into(), |h| h.to_string())).collect())
        .collect();
    let header = format!("ncols {w}\nnrows {h}\nxllcorner 0\nyllcorner 0\ncellsize 30\n");
    write_ascii(&path, &header, &rows);
    check_swaths(&path, Some(&as_f32(&values)));
}

#[test]
fn the_committed_files_decode_the_same_in_any_swath() {
    let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/dem");
    for name in [
        "srtm3_n39e040_1000.tif",
        "rhine_basin_30s.tif",
        "etopo5_e37_e44_n37_n42.nc",
        "etopo5_e5_e11_n43_n47.nc",
        "jacksboro_fault_3s.asc",
    ] {
        check_swaths(&assets.join(name), None);
    }
}

/// Posts a side of the file the memory test imports: 4200^2 heights take
/// 70 MB as `f32` (plus 35 MB of int16 bytes) decoded whole.
const BIG_SIDE: u32 = 4200;
/// The bound the import must hold, as `--memory-mb 64` does.
const BOUND_MB: u64 = 64;

/// The child of [`a_streaming_import_stays_under_64_mb`]: imports the file
/// named by `RIDGELINE_MEMORY_CHILD` into spills and a pyramid with a
/// 64 MB bound (bands of a quarter of it), then prints its `VmHWM`.
#[test]
#[ignore = "run by a_streaming_import_stays_under_64_mb in a child process"]
fn memory_child() {
    use ridgeline::pyramid::{build_streaming, spilled::spill_layers, BuildOptions, Silent};
    use ridgeline::pyramid::{StreamOptions, FILE_NAME};
    let Ok(file) = std::env::var("RIDGELINE_MEMORY_CHILD") else { return };
    let file = PathBuf::from(file);
    let out = file.with_extension("cache");
    std::fs::create_dir_all(&out).unwrap();
    let scratch = ridgeline::spill::ScratchDir::create(&out).unwrap();
    let layers = spill_layers(&[file], &scratch, &Silent).unwrap();
    let views: Vec<_> = layers.iter().map(|l| l.view()).collect();
    let options =
        StreamOptions { build: BuildOptions::default(), band_bytes: (BOUND_MB << 20) / 4 };
    let release = || layers.iter().for_each(|l| l.heights.release());
    build_streaming(&views, &scratch, &options, &out.join(FILE_NAME), &release, &Silent).unwrap();
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let hwm = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap();
    println!("child {hwm}");
}

/// A file that takes more than 64 MB decoded whole is imported (decoded
/// swath by swath into a spill, the pyramid cut in bands) by a child
/// process whose peak resident memory stays under 64 MB.
#[test]
fn a_streaming_import_stays_under_64_mb() {
    if !Path::new("/proc/self/status").exists() {
        return;
    }
    let dir = TempDir::new("swath-memory");
    let path = dir.path("big.tif");
    let side = BIG_SIDE;
    let file: Vec<i16> =
        (0..side * side).map(|k| ((k % side) / 3 + (k / side) / 5) as i16 % 3000).collect();
    let geo = GeoTags::geographic([20.0, 11.0], 1.0 / 3600.0, false);
    write_tiff_strips::<colortype::GrayI16>(
        &path,
        [side, side],
        &file,
        Compression::Uncompressed,
        Predictor::None,
        4,
        &geo,
    );
    drop(file);
    let output = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "memory_child", "--ignored", "--nocapture", "--test-threads=1"])
        .env("RIDGELINE_MEMORY_CHILD", &path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}{}", String::from_utf8_lossy(&output.stderr));
    // The harness prints "test memory_child ... " before the child's line.
    let at = stdout.find("child VmHWM:").expect("the child's peak");
    let kb: u64 = stdout[at..].split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!(kb < BOUND_MB << 10, "the import peaked at {} MB, over {BOUND_MB}", kb >> 10);
}
