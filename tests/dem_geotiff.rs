//! GeoTIFF round trips: int16 and float32, strips (written by the `tiff`
//! crate's encoder) and tiles (written by hand in `dem_support`, as the
//! encoder cannot tile), uncompressed, DEFLATE and LZW, with the horizontal
//! and floating-point predictors; georeference from scale + tie point and
//! from a transformation matrix, PixelIsArea and PixelIsPoint, GDAL nodata;
//! and the shared SRTM tile in `assets/dem`.

use std::path::Path;

use ridgeline::dem::{import_file, ElevationGrid};
use ridgeline::geo::Crs;
use testkit::dem::*;
use tiff::encoder::{colortype, Compression, DeflateLevel, Predictor};
use tiff::tags::Tag;

/// Odd sizes so that the last strip and the edge tiles are partial.
const W: u32 = 45;
const H: u32 = 37;
const SPACING: f64 = 1.0 / 1200.0;
const CORNER: [f64; 2] = [40.0, 40.0];

/// Sample at column `c`, file row `r` (row 0 north), some of them negative.
fn int_sample(c: u32, r: u32) -> i16 {
    ((c * 37 + r * 101) % 3000) as i16 - 200
}

fn float_sample(c: u32, r: u32) -> f32 {
    f32::from(int_sample(c, r)) * 0.25 + 0.125
}

fn file_order<T>(sample: impl Fn(u32, u32) -> T) -> Vec<T> {
    (0..H).flat_map(|r| (0..W).map(move |c| (c, r))).map(|(c, r)| sample(c, r)).collect()
}

/// Checks every height against `sample` (file coordinates; north-up file).
fn check_heights(grid: &ElevationGrid, sample: impl Fn(u32, u32) -> f32) {
    assert_eq!((grid.width, grid.height), (W, H));
    for r in 0..H {
        for c in 0..W {
            assert_eq!(grid.at(c, H - 1 - r), sample(c, r), "file column {c}, row {r}");
        }
    }
}

/// PixelIsArea with the tie point on the north-west outer corner: the
/// south-west post is half a cell east of the corner and half a cell above
/// the southern edge.
fn check_area_georef(grid: &ElevationGrid) {
    assert_eq!(grid.georef.crs, Crs::Geographic);
    assert_eq!(grid.georef.spacing, [SPACING; 2]);
    assert_close(grid.georef.origin[0], CORNER[0] + 0.5 * SPACING, 1e-12, "west post");
    assert_close(
        grid.georef.origin[1],
        CORNER[1] - (f64::from(H) - 0.5) * SPACING,
        1e-12,
        "south post",
    );
}

/// Heights before filling in grid order from file-order values.
fn grid_order(file: &[Option<f64>]) -> Vec<Option<f64>> {
    (0..H).rev().flat_map(|r| file[(r * W) as usize..((r + 1) * W) as usize].to_vec()).collect()
}

#[test]
fn int16_strips_uncompressed_pixel_is_area() {
    let dir = TempDir::new("tif-i16");
    let path = dir.path("plain.tif");
    let geo = GeoTags::geographic(CORNER, SPACING, false);
    let data = file_order(int_sample);
    write_tiff_strips::<colortype::GrayI16>(
        &path,
        [W, H],
        &data,
        Compression::Uncompressed,
        Predictor::None,
        4,
        &geo,
    );
    let grid = import_file(&path).unwrap();
    check_heights(&grid, |c, r| f32::from(int_sample(c, r)));
    check_area_georef(&grid);
    assert_eq!(grid.voids_filled, 0);
}

#[test]
fn int16_strips_deflate_and_lzw_with_horizontal_predictor() {
    let dir = TempDir::new("tif-i16-z");
    let geo = GeoTags::geographic(CORNER, SPACING, false);
    let data = file_order(int_sample);
    for (name, compression) in [
        ("deflate.tif", Compression::Deflate(DeflateLevel::Balanced)),
        ("lzw.tif", Compression::Lzw),
    ] {
        let path = dir.path(name);
        write_tiff_strips::<colortype::GrayI16>(
            &path,
            [W, H],
            &data,
            compression,
            Predictor::Horizontal,
            7,
            &geo,
        );
        let grid = import_file(&path).unwrap();
        check_heights(&grid, |c, r| f32::from(int_sample(c, r)));
        check_area_georef(&grid);
    }
}

#[test]
fn float32_strips_compressed_with_nan_nodata_pixel_is_point() {
    let dir = TempDir::new("tif-f32");
    let voids = [(3, 4), (20, 20), (21, 20), (0, 36)];
    let is_void = |c: u32, r: u32| voids.contains(&(c, r));
    let data = file_order(|c, r| if is_void(c, r) { f32::NAN } else { float_sample(c, r) });
    let before =
        grid_order(&file_order(|c, r| (!is_void(c, r)).then(|| f64::from(float_sample(c, r)))));
    let mut geo = GeoTags::geographic(CORNER, SPACING, true);
    geo.nodata = Some("nan".into());
    // The encoder refuses the horizontal predictor for floats.
    for (name, compression) in
        [("f.tif", Compression::Deflate(DeflateLevel::Fast)), ("g.tif", Compression::Lzw)]
    {
        let path = dir.path(name);
        write_tiff_strips::<colortype::Gray32Float>(
            &path,
            [W, H],
            &data,
            compression,
            Predictor::None,
            5,
            &geo,
        );
        let grid = import_file(&path).unwrap();
        check_filled(&grid, &before, None);
        // PixelIsPoint: the tie point is the north-west post itself.
        assert_eq!(grid.georef.origin, [CORNER[0], CORNER[1] - f64::from(H - 1) * SPACING]);
    }
}

#[test]
fn int16_gdal_nodata_marks_voids() {
    let dir = TempDir::new("tif-nodata");
    let path = dir.path("voids.tif");
    let is_void = |c: u32, r: u32| (10..14).contains(&c) && (5..8).contains(&r);
    let data = file_order(|c, r| if is_void(c, r) { -32768 } else { int_sample(c, r) });
    let mut geo = GeoTags::geographic(CORNER, SPACING, false);
    geo.nodata = Some("-32768".into());
    write_tiff_strips::<colortype::GrayI16>(
        &path,
        [W, H],
        &data,
        Compression::Lzw,
        Predictor::Horizontal,
        8,
        &geo,
    );
    let grid = import_file(&path).unwrap();
    let before =
        grid_order(&file_order(|c, r| (!is_void(c, r)).then(|| f64::from(int_sample(c, r)))));
    check_filled(&grid, &before, None);
    assert_eq!(grid.voids_filled, 12);
}

#[test]
fn int16_tiles_every_compression_with_horizontal_predictor() {
    let dir = TempDir::new("tif-tiles-i16");
    let geo = GeoTags::geographic(CORNER, SPACING, false);
    let samples = Samples::I16(file_order(int_sample));
    let cases = [
        ("none.tif", TileCompression::None, 1),
        ("deflate.tif", TileCompression::Deflate, 2),
        ("lzw.tif", TileCompression::Lzw, 2),
    ];
    for (name, compression, predictor) in cases {
        let path = dir.path(name);
        write_tiff_tiles(&path, [W, H], 16, &samples, compression, predictor, &geo);
        let grid = import_file(&path).unwrap();
        check_heights(&grid, |c, r| f32::from(int_sample(c, r)));
        check_area_georef(&grid);
    }
}

#[test]
fn float32_tiles_floating_point_predictor_with_nodata() {
    let dir = TempDir::new("tif-tiles-f32");
    let is_void = |c: u32, r: u32| c == 30 && r < 3;
    let samples =
        Samples::F32(file_order(|c, r| if is_void(c, r) { -9999.0 } else { float_sample(c, r) }));
    let before =
        grid_order(&file_order(|c, r| (!is_void(c, r)).then(|| f64::from(float_sample(c, r)))));
    let mut geo = GeoTags::geographic(CORNER, SPACING, false);
    geo.nodata = Some(" -9999.0 ".into());
    for (name, compression) in
        [("lzw.tif", TileCompression::Lzw), ("deflate.tif", TileCompression::Deflate)]
    {
        let path = dir.path(name);
        write_tiff_tiles(&path, [W, H], 16, &samples, compression, 3, &geo);
        let grid = import_file(&path).unwrap();
        check_filled(&grid, &before, None);
        assert_eq!(grid.voids_filled, 3);
    }
}

#[test]
fn projected_model_transformation_and_epsg() {
    let dir = TempDir::new("tif-utm");
    let path = dir.path("utm.tiff");
    let geo = GeoTags {
        transformation: Some([
            30.0,
            0.0,
            0.0,
            500_000.0, //
            0.0,
            -30.0,
            0.0,
            4_400_000.0, //
            0.0,
            0.0,
            0.0,
            0.0, //
            0.0,
            0.0,
            0.0,
            1.0,
        ]),
        keys: projected_keys(32637),
        ..GeoTags::default()
    };
    let data = file_order(float_sample);
    write_tiff_strips::<colortype::Gray32Float>(
        &path,
        [W, H],
        &data,
        Compression::Uncompressed,
        Predictor::None,
        37,
        &geo,
    );
    let grid = import_file(&path).unwrap();
    check_heights(&grid, float_sample);
    assert_eq!(grid.georef.crs, Crs::Projected { epsg: Some(32637) });
    assert_eq!(grid.georef.spacing, [30.0, 30.0]);
    assert_eq!(grid.georef.origin, [500_015.0, 4_400_000.0 - 30.0 * f64::from(H) + 15.0]);
}

#[test]
fn south_up_raster_keeps_its_row_order() {
    let dir = TempDir::new("tif-south-up");
    let path = dir.path("south_up.tif");
    let mut matrix = [0.0; 16];
    (matrix[0], matrix[3], matrix[5], matrix[7], matrix[15]) = (2.0, 100.0, 2.0, 200.0, 1.0);
    let geo =
        GeoTags { transformation: Some(matrix), keys: projected_keys(32767), ..GeoTags::default() };
    let data = file_order(int_sample);
    write_tiff_strips::<colortype::GrayI16>(
        &path,
        [W, H],
        &data,
        Compression::Uncompressed,
        Predictor::None,
        9,
        &geo,
    );
    let grid = import_file(&path).unwrap();
    // File row 0 is the southern row here.
    for r in 0..H {
        for c in 0..W {
            assert_eq!(grid.at(c, r), f32::from(int_sample(c, r)));
        }
    }
    assert_eq!(grid.georef.crs, Crs::Projected { epsg: None });
    assert_eq!(grid.georef.origin, [101.0, 201.0]);
}

/// The first and last samples of a stripped little-endian int16 TIFF, read
/// straight from the bytes (independently of the importer's row handling).
fn first_and_last_samples(path: &Path) -> (f32, f32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..2], b"II");
    let mut decoder = tiff::decoder::Decoder::new(std::fs::File::open(path).unwrap()).unwrap();
    let offsets = decoder.get_tag_u64_vec(Tag::StripOffsets).unwrap();
    let counts = decoder.get_tag_u64_vec(Tag::StripByteCounts).unwrap();
    let at = |k: u64| f32::from(i16::from_le_bytes([bytes[k as usize], bytes[k as usize + 1]]));
    (at(offsets[0]), at(offsets.last().unwrap() + counts.last().unwrap() - 2))
}

#[test]
fn shared_srtm_tile_imports_with_its_georeference() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/dem/srtm3_n39e040_1000.tif");
    let grid = import_file(&path).unwrap();
    assert_eq!((grid.width, grid.height), (1000, 1000));
    assert_eq!(grid.georef.crs, Crs::Geographic);
    let s = grid.georef.spacing;
    assert_close(s[0], 1.0 / 1200.0, 1e-12, "east spacing");
    assert_close(s[1], 1.0 / 1200.0, 1e-12, "north spacing");
    // Tie point (0, 0) -> (40 E, 40 N) is the outer north-west corner
    // (PixelIsArea): posts are half a cell inside it.
    assert_close(grid.georef.origin[0], 40.0 + 0.5 * s[0], 1e-9, "west post");
    assert_close(grid.georef.origin[1], 40.0 - 999.5 * s[1], 1e-9, "south post");
    assert_close(grid.georef.origin[1], 39.167083, 1e-6, "south post in degrees");
    let north_post = grid.georef.origin[1] + 999.0 * s[1];
    assert_close(north_post, 40.0 - 0.5 / 1200.0, 1e-9, "north post");
    let min = grid.heights.iter().copied().fold(f32::INFINITY, f32::min);
    let max = grid.heights.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    assert_eq!((min, max), (1111.0, 3270.0));
    assert_eq!(grid.voids_filled, 0);
    let (north_west, south_east) = first_and_last_samples(&path);
    assert_eq!(grid.at(0, 999), north_west);
    assert_eq!(grid.at(999, 0), south_east);
}

/// Resamples the shared SRTM tile (bilinear, in its posts) onto a UTM
/// zone 37 N grid of 75 m posts inside it (central meridian 39 E, so the
/// grid's north is 0.64 degrees off true north there) and writes it as a
/// float32 GeoTIFF tagged EPSG:32637, for the accuracy runs of projected
/// grids on the ellipsoid (docs/earth.md). Run by hand:
/// `OUT=/tmp/srtm3_utm37n.tif cargo test --test dem_geotiff -- --ignored make_srtm_utm37n`,
/// then `ridgeline import --out cache/srtm_utm37n /tmp/srtm3_utm37n.tif`.
#[test]
#[ignore = "writes a file for the accuracy runs: OUT=path"]
fn make_srtm_utm37n() {
    use ridgeline::earth::Projection;
    const SPACING: f64 = 75.0;
    let out = std::env::var("OUT").expect("OUT=path/to/write.tif");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/dem/srtm3_n39e040_1000.tif");
    let srtm = import_file(&path).unwrap();
    let utm = Projection::from_epsg(32637).unwrap();
    let [s, w] = [srtm.georef.spacing, srtm.georef.origin];
    let last = [srtm.width - 1, srtm.height - 1].map(|n| n as f64);
    // The projected rectangle inside the tile: its edges sampled (they are
    // not straight in the projection).
    let (mut lo, mut hi) = ([f64::NEG_INFINITY; 2], [f64::INFINITY; 2]);
    for k in 0..=20 {
        let f = k as f64 / 20.0;
        let at = |u: f64, v: f64| {
            utm.forward((w[1] + v * s[1]).to_radians(), (w[0] + u * s[0]).to_radians())
        };
        lo[0] = lo[0].max(at(0.0, f * last[1])[0]);
        hi[0] = hi[0].min(at(last[0], f * last[1])[0]);
        lo[1] = lo[1].max(at(f * last[0], 0.0)[1]);
        hi[1] = hi[1].min(at(f * last[0], last[1])[1]);
    }
    let origin = lo.map(|x| (x / SPACING).ceil() * SPACING);
    let size = [0, 1].map(|k| ((hi[k] - origin[k]) / SPACING).floor() as u32 + 1);
    let mut data = Vec::new();
    for r in 0..size[1] {
        for c in 0..size[0] {
            let north = origin[1] + (size[1] - 1 - r) as f64 * SPACING;
            let (lat, lon) = utm.inverse([origin[0] + c as f64 * SPACING, north]);
            let u = ((lon.to_degrees() - w[0]) / s[0]).clamp(0.0, last[0]);
            let v = ((lat.to_degrees() - w[1]) / s[1]).clamp(0.0, last[1]);
            let (i, j) =
                ((u.floor() as u32).min(srtm.width - 2), (v.floor() as u32).min(srtm.height - 2));
            let (fu, fv) = (u - i as f64, v - j as f64);
            let h = |a: u32, b: u32| srtm.at(i + a, j + b) as f64;
            let south = h(0, 0) * (1.0 - fu) + h(1, 0) * fu;
            let north = h(0, 1) * (1.0 - fu) + h(1, 1) * fu;
            data.push((south * (1.0 - fv) + north * fv) as f32);
        }
    }
    // PixelIsArea: the tie point is the north-west post's outer corner.
    let top = origin[1] + (size[1] - 1) as f64 * SPACING;
    let geo = GeoTags {
        scale: Some([SPACING, SPACING, 0.0]),
        tiepoint: Some([0.0, 0.0, 0.0, origin[0] - SPACING / 2.0, top + SPACING / 2.0, 0.0]),
        keys: projected_keys(32637),
        ..GeoTags::default()
    };
    write_tiff_strips::<colortype::Gray32Float>(
        Path::new(&out),
        size,
        &data,
        Compression::Uncompressed,
        Predictor::None,
        16,
        &geo,
    );
    eprintln!("{out}: {size:?} posts from {origin:?} (UTM 37 N), 75 m");
}
