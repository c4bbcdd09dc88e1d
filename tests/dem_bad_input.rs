//! Bad input: every corrupt, truncated, mislabelled or absurd file gets an
//! error that names the file and the problem, never a panic, and absurd
//! declarations are refused before anything is allocated (a test that tried
//! to allocate 100000 x 100000 heights would abort, not pass).

use std::path::PathBuf;

use ridgeline::dem::{import_files, Problem};
use testkit::dem::*;
use tiff::encoder::{colortype, Compression, Predictor};
use tiff::tags::Tag;

const SRTM3_BYTES: usize = 1201 * 1201 * 2;

// -------------------------------------------------------------------- HGT

#[test]
fn hgt_of_the_wrong_size_or_truncated() {
    let dir = TempDir::new("bad-hgt");
    for (name, len) in [("N10E010.hgt", 1000), ("N11E010.hgt", SRTM3_BYTES - 2), ("N12E010.hgt", 0)]
    {
        let path = dir.path(name);
        std::fs::write(&path, vec![0u8; len]).unwrap();
        assert!(matches!(import_error(&path), Problem::HgtSize { actual } if actual == len as u64));
    }
}

#[test]
fn hgt_whose_name_gives_no_position() {
    let dir = TempDir::new("bad-hgt-name");
    for name in ["tile.hgt", "X39E040.hgt", "N39E4.hgt", "N95E040.hgt", "N39E190.hgt"] {
        let path = dir.path(name);
        std::fs::write(&path, vec![0u8; SRTM3_BYTES]).unwrap();
        assert!(matches!(import_error(&path), Problem::FileName(_)), "{name}");
    }
}

#[test]
fn hgt_of_nothing_but_voids() {
    let dir = TempDir::new("bad-hgt-void");
    let path = dir.path("N39E040.hgt");
    write_hgt(&path, 1201, &vec![HGT_VOID; 1201 * 1201]);
    assert!(matches!(import_error(&path), Problem::AllVoids));
}

// ------------------------------------------------------------------- DTED

const SPEC: DtedSpec =
    DtedSpec { level: 0, origin: [40, 39], lon_tenths: 300, columns: 121, rows: 121 };

fn dted_file(dir: &TempDir, name: &str, edit: impl FnOnce(&mut Vec<u8>)) -> PathBuf {
    let heights: Vec<i32> = (0..121 * 121).map(|k| 100 + k % 500).collect();
    let mut bytes = dted_bytes(SPEC, &heights);
    edit(&mut bytes);
    let path = dir.path(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn dted_truncated_in_the_data_or_in_the_headers() {
    let dir = TempDir::new("bad-dted-trunc");
    let path = dted_file(&dir, "short.dt0", |b| b.truncate(b.len() - 100));
    assert!(matches!(import_error(&path), Problem::Truncated { .. }));
    let path = dted_file(&dir, "headers.dt0", |b| b.truncate(1000));
    assert!(matches!(import_error(&path), Problem::Truncated { needed: 3428, actual: 1000, .. }));
}

#[test]
fn dted_with_wrong_magic() {
    let dir = TempDir::new("bad-dted-magic");
    let path = dted_file(&dir, "uhl.dt0", |b| b[0] = b'X');
    assert!(matches!(import_error(&path), Problem::BadMagic { expected: "UHL1", .. }));
    let path = dted_file(&dir, "dsi.dt0", |b| b[80] = b'X');
    assert!(matches!(import_error(&path), Problem::BadMagic { expected: "DSI", .. }));
    let path = dted_file(&dir, "acc.dt0", |b| b[80 + 648] = b'X');
    assert!(matches!(import_error(&path), Problem::BadMagic { expected: "ACC", .. }));
}

#[test]
fn dted_longer_than_its_header_says() {
    let dir = TempDir::new("bad-dted-size");
    let path = dted_file(&dir, "long.dt0", |b| b.extend([0u8; 7]));
    assert!(matches!(import_error(&path), Problem::SizeMismatch { .. }));
}

#[test]
fn dted_declaring_9999_by_9999_in_a_small_file_is_refused_before_allocating() {
    let dir = TempDir::new("bad-dted-huge");
    let path = dted_file(&dir, "huge.dt0", |b| b[47..55].copy_from_slice(b"99999999"));
    let needed = 3428 + 9999 * (12 + 2 * 9999);
    assert!(matches!(import_error(&path), Problem::Truncated { needed: n, .. } if n == needed));
}

#[test]
fn dted_checksum_failure_names_the_column() {
    let dir = TempDir::new("bad-dted-sum");
    // Change one height of column 7 and leave its checksum alone.
    let at = dted_record_offset(SPEC, 7) + 8 + 2 * 60 + 1;
    let path = dted_file(&dir, "sum.dt0", |b| b[at] ^= 0x10);
    let err = ridgeline::dem::import_file(&path).unwrap_err();
    let message = err.to_string();
    assert!(
        message.contains("sum.dt0") && message.contains("checksum") && message.contains("column 7"),
        "{message}"
    );
    assert!(
        matches!(err.problem, Problem::DtedChecksum { column: 7, stored, computed } if computed == stored + 0x10)
    );
}

#[test]
fn dted_record_with_a_bad_sentinel_or_count() {
    let dir = TempDir::new("bad-dted-record");
    let at = dted_record_offset(SPEC, 3);
    // Keep the checksum right so that the sentinel check is what fails.
    let path = dted_file(&dir, "sentinel.dt0", |b| {
        b[at] = 0xAB;
        let end = dted_record_offset(SPEC, 4) - 4;
        let sum = u32::from_be_bytes(b[end..end + 4].try_into().unwrap()) + 1;
        b[end..end + 4].copy_from_slice(&sum.to_be_bytes());
    });
    assert!(matches!(import_error(&path), Problem::DtedRecord { column: 3, .. }));
    // Swap two whole records: checksums hold, longitude counts do not.
    let (a, b_at, len) = (dted_record_offset(SPEC, 1), dted_record_offset(SPEC, 2), 12 + 2 * 121);
    let path = dted_file(&dir, "order.dt0", |b| {
        let first = b[a..a + len].to_vec();
        b.copy_within(b_at..b_at + len, a);
        b[b_at..b_at + len].copy_from_slice(&first);
    });
    assert!(matches!(import_error(&path), Problem::DtedRecord { column: 1, .. }));
}

#[test]
fn dted_headers_that_contradict_themselves() {
    let dir = TempDir::new("bad-dted-header");
    let path = dted_file(&dir, "level.dt0", |b| b[80 + 63] = b'2');
    assert!(matches!(import_error(&path), Problem::Header(m) if m.contains("DTED2")));
    let path = dted_file(&dir, "origin.dt0", |b| b[11] = b'X');
    assert!(matches!(import_error(&path), Problem::Header(m) if m.contains("origin")));
    let path = dted_file(&dir, "count.dt0", |b| b[47..51].copy_from_slice(b"12a4"));
    assert!(matches!(import_error(&path), Problem::Header(_)));
}

// ------------------------------------------------------------- ASCII grid

fn ascii(dir: &TempDir, name: &str, text: &str) -> PathBuf {
    let path = dir.path(name);
    std::fs::write(&path, text).unwrap();
    path
}

const HEADER: &str = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n";

#[test]
fn ascii_with_too_few_or_too_many_values() {
    let dir = TempDir::new("bad-asc-count");
    let path = ascii(&dir, "few.asc", &format!("{HEADER}10 20 30\n40 50\n"));
    assert!(matches!(import_error(&path), Problem::ValueCount { expected: 6, found: 5 }));
    let path = ascii(&dir, "many.asc", &format!("{HEADER}1 2 3\n4 5 6\n7\n"));
    assert!(matches!(import_error(&path), Problem::ValueCount { expected: 6, found: 7 }));
}

#[test]
fn ascii_declaring_absurd_or_impossible_sizes_is_refused_before_allocating() {
    let dir = TempDir::new("bad-asc-huge");
    let text = "ncols 100000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n";
    let path = ascii(&dir, "absurd.asc", text);
    assert!(matches!(
        import_error(&path),
        Problem::AbsurdDimensions { width: 100000, height: 100000, .. }
    ));
    let text = "ncols 1000\nnrows 1000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n";
    let path = ascii(&dir, "short.asc", text);
    assert!(matches!(import_error(&path), Problem::Truncated { .. }));
    let path = ascii(&dir, "zero.asc", "ncols 0\nnrows 5\nxllcorner 0\nyllcorner 0\ncellsize 1\n");
    assert!(matches!(import_error(&path), Problem::AbsurdDimensions { width: 0, .. }));
}

#[test]
fn ascii_with_wrong_magic_or_a_broken_header() {
    let dir = TempDir::new("bad-asc-header");
    let path = ascii(&dir, "magic.asc", "hello world\n1 2 3\n");
    assert!(matches!(import_error(&path), Problem::BadMagic { .. }));
    let path =
        ascii(&dir, "nocell.asc", "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2 3 4 5 6\n");
    assert!(matches!(import_error(&path), Problem::Header(m) if m.contains("cellsize")));
    let path = ascii(
        &dir,
        "both.asc",
        "ncols 1\nnrows 1\nxllcorner 0\nxllcenter 0\nyllcorner 0\ncellsize 1\n5\n",
    );
    assert!(matches!(import_error(&path), Problem::Header(_)));
    let path =
        ascii(&dir, "negative.asc", "ncols 1\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize -1\n5\n");
    assert!(matches!(import_error(&path), Problem::Header(_)));
}

#[test]
fn ascii_nan_inf_and_junk_heights() {
    let dir = TempDir::new("bad-asc-nan");
    for (name, value) in
        [("nan.asc", "NaN"), ("inf.asc", "inf"), ("ninf.asc", "-infinity"), ("big.asc", "1e999")]
    {
        let path = ascii(&dir, name, &format!("{HEADER}1 2 3\n4 {value} 6\n"));
        assert!(
            matches!(import_error(&path), Problem::NonFinite { row: 1, column: 1, .. }),
            "{value}"
        );
    }
    let path = ascii(&dir, "word.asc", &format!("{HEADER}1 2 3\n4 5 6x\n"));
    assert!(matches!(import_error(&path), Problem::NotANumber { row: 1, column: 2, .. }));
    let path = ascii(&dir, "long.asc", &format!("{HEADER}1 2 3\n4 5 {}\n", "7".repeat(300)));
    assert!(matches!(import_error(&path), Problem::Io(_)));
}

#[test]
fn ascii_nan_declared_as_nodata_is_a_void() {
    let dir = TempDir::new("asc-nan-nodata");
    let path = ascii(&dir, "ok.asc", &format!("{HEADER}NODATA_value nan\n1 2 3\n4 nan 6\n"));
    let grid = ridgeline::dem::import_file(&path).unwrap();
    assert_eq!(grid.voids_filled, 1);
}

// ---------------------------------------------------------------- GeoTIFF

/// The tags of a minimal single-strip int16 raster.
fn strip_tags(
    dir: &mut tiff::encoder::DirectoryEncoder<
        '_,
        std::io::BufWriter<std::fs::File>,
        tiff::encoder::TiffKindStandard,
    >,
    size: [u32; 2],
    offset: u32,
    count: u32,
) {
    dir.write_tag(Tag::ImageWidth, size[0]).unwrap();
    dir.write_tag(Tag::ImageLength, size[1]).unwrap();
    dir.write_tag(Tag::BitsPerSample, 16u16).unwrap();
    dir.write_tag(Tag::Compression, 1u16).unwrap();
    dir.write_tag(Tag::PhotometricInterpretation, 1u16).unwrap();
    dir.write_tag(Tag::SamplesPerPixel, 1u16).unwrap();
    dir.write_tag(Tag::SampleFormat, 2u16).unwrap();
    dir.write_tag(Tag::RowsPerStrip, size[1]).unwrap();
    dir.write_tag(Tag::StripOffsets, &[offset][..]).unwrap();
    dir.write_tag(Tag::StripByteCounts, &[count][..]).unwrap();
    dir.write_tag(Tag::ModelPixelScaleTag, &[1.0f64, 1.0, 0.0][..]).unwrap();
    dir.write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0][..]).unwrap();
    dir.write_tag(Tag::GeoKeyDirectoryTag, &projected_keys(32767)[..]).unwrap();
}

#[test]
fn tiff_with_wrong_magic() {
    let dir = TempDir::new("bad-tif-magic");
    let path = ascii(&dir, "text.tif", "this is not a TIFF file at all");
    assert!(matches!(import_error(&path), Problem::BadMagic { format: "TIFF", .. }));
}

#[test]
fn tiff_declaring_100000_by_100000_in_200_bytes_is_refused_before_allocating() {
    let dir = TempDir::new("bad-tif-huge");
    let path = dir.path("huge.tif");
    write_tiff_raw(&path, &[0u8; 16], |d, offset| strip_tags(d, [100_000, 100_000], offset, 16));
    assert!(std::fs::metadata(&path).unwrap().len() < 400);
    assert!(matches!(
        import_error(&path),
        Problem::AbsurdDimensions { width: 100_000, height: 100_000, .. }
    ));
}

#[test]
fn tiff_strips_past_the_end_or_smaller_than_the_image() {
    let dir = TempDir::new("bad-tif-size");
    let path = dir.path("past_end.tif");
    write_tiff_raw(&path, &[0u8; 32], |d, offset| strip_tags(d, [4, 4], offset, 1_000_000));
    assert!(matches!(import_error(&path), Problem::Truncated { .. }));
    let path = dir.path("small_strip.tif");
    write_tiff_raw(&path, &[0u8; 32], |d, offset| strip_tags(d, [8, 8], offset, 32));
    assert!(matches!(import_error(&path), Problem::SizeMismatch { expected: 128, actual: 32 }));
}

#[test]
fn tiff_cut_in_half() {
    let dir = TempDir::new("bad-tif-cut");
    let path = dir.path("cut.tif");
    let geo = GeoTags::geographic([40.0, 40.0], 0.001, false);
    let data = vec![7i16; 100 * 100];
    write_tiff_strips::<colortype::GrayI16>(
        &path,
        [100, 100],
        &data,
        Compression::Uncompressed,
        Predictor::None,
        10,
        &geo,
    );
    let len = std::fs::metadata(&path).unwrap().len();
    truncate(&path, len / 2);
    // The directory sits at the end, so the decoder's own read fails first.
    assert!(matches!(import_error(&path), Problem::Tiff(_) | Problem::Truncated { .. }));
}

#[test]
fn tiff_nan_and_infinity_that_are_not_the_nodata() {
    let dir = TempDir::new("bad-tif-nan");
    let mut data = vec![1.5f32; 6 * 5];
    data[2 * 6 + 4] = f32::NAN;
    let path = dir.path("nan.tif");
    let geo = GeoTags::geographic([40.0, 40.0], 0.001, false);
    write_tiff_strips::<colortype::Gray32Float>(
        &path,
        [6, 5],
        &data,
        Compression::Lzw,
        Predictor::None,
        5,
        &geo,
    );
    assert!(matches!(import_error(&path), Problem::NonFinite { row: 2, column: 4, .. }));
    data[2 * 6 + 4] = f32::INFINITY;
    let path = dir.path("inf.tif");
    let geo = GeoTags { nodata: Some("nan".into()), ..geo };
    write_tiff_strips::<colortype::Gray32Float>(
        &path,
        [6, 5],
        &data,
        Compression::Lzw,
        Predictor::None,
        5,
        &geo,
    );
    assert!(matches!(import_error(&path), Problem::NonFinite { row: 2, column: 4, .. }));
}

#[test]
fn tiff_without_usable_georeference_or_with_colour() {
    let dir = TempDir::new("bad-tif-geo");
    let data = vec![1i16; 16];
    let path = dir.path("plain.tif");
    let none = GeoTags::default();
    write_tiff_strips::<colortype::GrayI16>(
        &path,
        [4, 4],
        &data,
        Compression::Uncompressed,
        Predictor::None,
        4,
        &none,
    );
    assert!(matches!(import_error(&path), Problem::Header(m) if m.contains("GeoKeyDirectory")));
    let path = dir.path("rotated.tif");
    let mut matrix = [0.0; 16];
    (matrix[0], matrix[1], matrix[4], matrix[5], matrix[15]) = (1.0, 0.5, 0.5, -1.0, 1.0);
    let rotated =
        GeoTags { transformation: Some(matrix), keys: projected_keys(32633), ..GeoTags::default() };
    write_tiff_strips::<colortype::GrayI16>(
        &path,
        [4, 4],
        &data,
        Compression::Uncompressed,
        Predictor::None,
        4,
        &rotated,
    );
    assert!(matches!(import_error(&path), Problem::Unsupported(m) if m.contains("rotated")));
    let path = dir.path("rgb.tif");
    let rgb = vec![1u8; 4 * 4 * 3];
    let geo = GeoTags::geographic([40.0, 40.0], 0.001, false);
    write_tiff_strips::<colortype::RGB8>(
        &path,
        [4, 4],
        &rgb,
        Compression::Uncompressed,
        Predictor::None,
        4,
        &geo,
    );
    assert!(matches!(import_error(&path), Problem::Unsupported(_)));
}

// ------------------------------------------------------ files and mosaics

#[test]
fn missing_unknown_and_no_files() {
    let dir = TempDir::new("bad-files");
    let path = dir.path("N10E010.hgt");
    assert!(matches!(import_error(&path), Problem::Io(_)));
    let path = ascii(&dir, "mystery.dat", "\u{1}\u{2} not any format");
    assert!(matches!(import_error(&path), Problem::UnknownFormat));
    let err = import_files(&[]).unwrap_err();
    assert!(matches!(err.problem, Problem::NoInput));
}

/// A 3 x 3 ASCII grid with the given lower-left post and spacing.
fn small_grid(dir: &TempDir, name: &str, x: f64, y: f64, spacing: f64) -> PathBuf {
    let header = format!("ncols 3\nnrows 3\nxllcenter {x}\nyllcenter {y}\ncellsize {spacing}\n");
    ascii(dir, name, &(header + "1 2 3\n4 5 6\n7 8 9\n"))
}

#[test]
fn mosaic_of_files_that_do_not_fit_together() {
    let dir = TempDir::new("bad-mosaic");
    let first = small_grid(&dir, "a.asc", 0.0, 0.0, 10.0);
    let cases = [
        (small_grid(&dir, "spacing.asc", 20.0, 0.0, 10.5), "spacing"),
        (small_grid(&dir, "lattice.asc", 23.0, 0.0, 10.0), "lattice"),
        (small_grid(&dir, "far.asc", 1e9, 1e9, 10.0), "mosaic would be"),
    ];
    for (second, what) in cases {
        let err = names_file(import_files(&[first.clone(), second.clone()]).unwrap_err(), &second);
        assert!(matches!(&err.problem, Problem::Mosaic(m) if m.contains(what)), "{err}");
    }
    let geographic = small_grid(&dir, "geo.asc", 20.0, 0.0, 10.0);
    std::fs::write(dir.path("geo.prj"), "GEOGCS[\"WGS 84\"]").unwrap();
    let err = names_file(import_files(&[first, geographic.clone()]).unwrap_err(), &geographic);
    assert!(matches!(&err.problem, Problem::Mosaic(m) if m.contains("coordinate system")), "{err}");
}

// ------------------------------------------------------ random corruption

/// A small valid file of each format, as bytes, with its file name.
fn valid_files(dir: &TempDir) -> Vec<(&'static str, Vec<u8>)> {
    let heights: Vec<i32> = (0..121 * 121).map(|k| k % 700 - 50).collect();
    let dted = dted_bytes(SPEC, &heights);
    let ascii = format!("{HEADER}1 2 3\n4 -9999 6.5\n").into_bytes();
    let geo = GeoTags {
        nodata: Some("-32768".into()),
        ..GeoTags::geographic([40.0, 40.0], 0.001, false)
    };
    let samples = Samples::I16((0..20 * 19).map(|k| (k % 97) as i16).collect());
    let tiled = dir.path("tiled.tif");
    write_tiff_tiles(&tiled, [20, 19], 16, &samples, TileCompression::Deflate, 2, &geo);
    let stripped = dir.path("strips.tif");
    let data: Vec<f32> = (0..20 * 19).map(|k| k as f32 * 0.5).collect();
    write_tiff_strips::<colortype::Gray32Float>(
        &stripped,
        [20, 19],
        &data,
        Compression::Lzw,
        Predictor::None,
        3,
        &geo,
    );
    vec![
        ("x.dt0", dted),
        ("x.asc", ascii),
        ("tiled.tif", std::fs::read(tiled).unwrap()),
        ("strips.tif", std::fs::read(stripped).unwrap()),
    ]
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

    /// Flipped bytes or a cut anywhere in a valid file never panic: the
    /// import succeeds or fails with an error naming the file.
    #[test]
    fn corrupt_files_never_panic(
        which in 0usize..4,
        flips in proptest::collection::vec((proptest::prelude::any::<proptest::sample::Index>(), 1u8..=255), 0..4),
        cut in proptest::option::of(proptest::prelude::any::<proptest::sample::Index>()),
    ) {
        let dir = TempDir::new("corrupt");
        let (name, mut bytes) = valid_files(&dir).swap_remove(which);
        for (at, mask) in flips {
            let k = at.index(bytes.len());
            bytes[k] ^= mask;
        }
        if let Some(cut) = cut {
            bytes.truncate(cut.index(bytes.len()));
        }
        let path = dir.path(&format!("corrupt-{name}"));
        std::fs::write(&path, &bytes).unwrap();
        if let Err(err) = ridgeline::dem::import_file(&path) {
            names_file(err, &path);
        }
    }
}
