//! Writers for the elevation formats, used by the `dem_*` tests to
//! synthesise input files: SRTM `.hgt`, DTED, ESRI ASCII grids, and GeoTIFF
//! (stripped through the `tiff` crate's encoder; tiled by hand, because the
//! encoder writes strips only, with the crate's own DEFLATE and LZW
//! compressors and its directory encoder).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use ridgeline::dem::{ElevationGrid, ImportError, Problem};
use tiff::encoder::colortype::ColorType;
use tiff::encoder::compression::{CompressionAlgorithm, Deflate, Lzw};
use tiff::encoder::{
    Compression, DirectoryEncoder, Predictor, TiffEncoder, TiffKindStandard, TiffValue,
};
use tiff::tags::Tag;

/// A scratch directory removed when dropped.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(name: &str) -> TempDir {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("ridgeline-{name}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    pub fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Asserts the error names the file (by its file name) and returns it.
pub fn names_file(err: ImportError, path: &Path) -> ImportError {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    assert!(err.to_string().contains(&name), "error {err} does not name {name}");
    assert_eq!(err.path, path);
    err
}

/// Imports `path` expecting failure; checks the message names the file.
pub fn import_error(path: &Path) -> Problem {
    let err = ridgeline::dem::import_file(path).expect_err("bad input must be refused");
    names_file(err, path).problem
}

pub fn assert_close(actual: f64, expected: f64, tolerance: f64, what: &str) {
    assert!(
        (actual - expected).abs() <= tolerance,
        "{what}: {actual} is not {expected} +- {tolerance}"
    );
}

/// Checks a filled grid against the heights before filling (`None` =
/// void, grid order): valid heights unchanged, the fill count, every filled
/// height inside the range of the nearest valid samples along its row and
/// column, and equal to `plane` (if given) where valid samples enclose it on all four
/// sides (the fill restores planes exactly there).
pub fn check_filled(
    grid: &ElevationGrid,
    before: &[Option<f64>],
    plane: Option<&dyn Fn(u32, u32) -> f64>,
) {
    let (w, h) = (grid.width, grid.height);
    assert_eq!(before.len(), (w * h) as usize);
    let voids = before.iter().filter(|v| v.is_none()).count() as u64;
    assert_eq!(grid.voids_filled, voids, "fill count");
    let at = |i: i64, j: i64| before[(j * i64::from(w) + i) as usize];
    for j in 0..h {
        for i in 0..w {
            let filled = f64::from(grid.at(i, j));
            if let Some(v) = at(i.into(), j.into()) {
                assert_eq!(grid.at(i, j), v as f32, "valid sample ({i}, {j}) changed");
                continue;
            }
            let nearest: Vec<f64> = [(-1, 0), (1, 0), (0, -1), (0, 1)]
                .into_iter()
                .filter_map(|(di, dj)| {
                    let (mut x, mut y) = (i64::from(i) + di, i64::from(j) + dj);
                    while (0..i64::from(w)).contains(&x) && (0..i64::from(h)).contains(&y) {
                        if let Some(v) = at(x, y) {
                            return Some(v);
                        }
                        (x, y) = (x + di, y + dj);
                    }
                    None
                })
                .collect();
            if nearest.is_empty() {
                continue; // filled in the second pass, from filled values
            }
            let lo = nearest.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = nearest.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let slack = 1e-3 * (1.0 + hi.abs());
            assert!(
                filled >= lo - slack && filled <= hi + slack,
                "({i}, {j}) = {filled} outside {lo}..{hi}"
            );
            if let (4, Some(plane)) = (nearest.len(), plane) {
                assert_close(
                    filled,
                    plane(i, j),
                    1e-3 * (1.0 + filled.abs()),
                    "enclosed void on a plane",
                );
            }
        }
    }
}

// ---------------------------------------------------------------- SRTM HGT

/// The SRTM void.
pub const HGT_VOID: i16 = -32768;

/// Writes a square `.hgt` tile from heights in grid order (row 0 south).
pub fn write_hgt(path: &Path, side: usize, heights: &[i16]) {
    assert_eq!(heights.len(), side * side);
    let mut bytes = Vec::with_capacity(2 * side * side);
    for row in heights.chunks_exact(side).rev() {
        row.iter().for_each(|h| bytes.extend_from_slice(&h.to_be_bytes()));
    }
    std::fs::write(path, bytes).unwrap();
}

// -------------------------------------------------------------------- DTED

pub const DTED_VOID: i32 = -32767;

/// The header values of a synthetic DTED file.
#[derive(Clone, Copy, Debug)]
pub struct DtedSpec {
    pub level: u8,
    /// South-west corner in whole degrees: longitude, latitude.
    pub origin: [i32; 2],
    /// Longitude interval in tenths of seconds (the latitude one follows the level).
    pub lon_tenths: u32,
    pub columns: u32,
    pub rows: u32,
}

impl DtedSpec {
    pub fn lat_tenths(&self) -> u32 {
        [300, 30, 10][self.level as usize]
    }
}

/// Encodes a height as DTED signed magnitude.
pub fn signed_magnitude(h: i32) -> u16 {
    assert!(h.abs() <= 0x7FFF);
    if h < 0 {
        0x8000 | (-h) as u16
    } else {
        h as u16
    }
}

fn dddmmssh(degrees: i32, positive: char, negative: char) -> String {
    let hemisphere = if degrees < 0 { negative } else { positive };
    format!("{:03}0000{hemisphere}", degrees.abs())
}

fn padded(mut text: String, len: usize) -> Vec<u8> {
    assert!(text.len() <= len);
    text.extend(std::iter::repeat_n(' ', len - text.len()));
    text.into_bytes()
}

/// A complete DTED file; `heights[j * columns + i]`, row 0 south.
pub fn dted_bytes(spec: DtedSpec, heights: &[i32]) -> Vec<u8> {
    assert_eq!(heights.len(), (spec.columns * spec.rows) as usize);
    let uhl = format!(
        "UHL1{}{}{:04}{:04}NA  U  {:12}{:04}{:04}0",
        dddmmssh(spec.origin[0], 'E', 'W'),
        dddmmssh(spec.origin[1], 'N', 'S'),
        spec.lon_tenths,
        spec.lat_tenths(),
        "",
        spec.columns,
        spec.rows
    );
    let mut bytes = padded(uhl, 80);
    let dsi = format!("DSIU{:55}DTED{}", "", spec.level);
    bytes.extend(padded(dsi, 648));
    bytes.extend(padded("ACC".into(), 2700));
    for i in 0..spec.columns {
        let start = bytes.len();
        bytes.push(0xAA);
        bytes.extend_from_slice(&i.to_be_bytes()[1..]);
        bytes.extend_from_slice(&signed_magnitude(i as i32).to_be_bytes());
        bytes.extend_from_slice(&[0, 0]);
        for j in 0..spec.rows {
            let h = heights[(j * spec.columns + i) as usize];
            bytes.extend_from_slice(&signed_magnitude(h).to_be_bytes());
        }
        let sum: u32 = bytes[start..].iter().map(|&b| u32::from(b)).sum();
        bytes.extend_from_slice(&sum.to_be_bytes());
    }
    bytes
}

/// Offset of the data record of `column` in a file from [`dted_bytes`].
pub fn dted_record_offset(spec: DtedSpec, column: u32) -> usize {
    80 + 648 + 2700 + column as usize * (12 + 2 * spec.rows as usize)
}

// --------------------------------------------------------------- ASCII grid

/// Writes an ESRI ASCII grid: `header` lines, then `rows` (north first).
pub fn write_ascii(path: &Path, header: &str, rows: &[Vec<String>]) {
    let mut text = header.to_string();
    for row in rows {
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

// ----------------------------------------------------------------- GeoTIFF

/// The georeferencing tags of a synthetic GeoTIFF.
#[derive(Clone, Debug, Default)]
pub struct GeoTags {
    pub scale: Option<[f64; 3]>,
    pub tiepoint: Option<[f64; 6]>,
    pub transformation: Option<[f64; 16]>,
    /// GeoKey directory, header included.
    pub keys: Vec<u16>,
    pub nodata: Option<String>,
}

/// GeoKey directories.
pub fn geographic_keys(pixel_is_point: bool) -> Vec<u16> {
    let raster = if pixel_is_point { 2 } else { 1 };
    vec![1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, raster, 2048, 0, 1, 4326]
}

pub fn projected_keys(epsg: u16) -> Vec<u16> {
    vec![1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, epsg]
}

impl GeoTags {
    /// Scale and tie point (raster (0, 0) -> `corner`), geographic.
    pub fn geographic(corner: [f64; 2], spacing: f64, pixel_is_point: bool) -> GeoTags {
        GeoTags {
            scale: Some([spacing, spacing, 0.0]),
            tiepoint: Some([0.0, 0.0, 0.0, corner[0], corner[1], 0.0]),
            keys: geographic_keys(pixel_is_point),
            ..GeoTags::default()
        }
    }

    fn write(&self, dir: &mut DirectoryEncoder<'_, BufWriter<File>, TiffKindStandard>) {
        if let Some(scale) = self.scale {
            dir.write_tag(Tag::ModelPixelScaleTag, &scale[..]).unwrap();
        }
        if let Some(tie) = self.tiepoint {
            dir.write_tag(Tag::ModelTiepointTag, &tie[..]).unwrap();
        }
        if let Some(matrix) = self.transformation {
            dir.write_tag(Tag::ModelTransformationTag, &matrix[..]).unwrap();
        }
        if !self.keys.is_empty() {
            dir.write_tag(Tag::GeoKeyDirectoryTag, &self.keys[..]).unwrap();
        }
        if let Some(nodata) = &self.nodata {
            dir.write_tag(Tag::GdalNodata, nodata.as_str()).unwrap();
        }
    }
}

/// Writes a stripped GeoTIFF with the `tiff` encoder; `data` in file order
/// (first row north).
pub fn write_tiff_strips<C: ColorType>(
    path: &Path,
    size: [u32; 2],
    data: &[C::Inner],
    compression: Compression,
    predictor: Predictor,
    rows_per_strip: u32,
    geo: &GeoTags,
) where
    [C::Inner]: TiffValue,
{
    let file = BufWriter::new(File::create(path).unwrap());
    let mut encoder =
        TiffEncoder::new(file).unwrap().with_compression(compression).with_predictor(predictor);
    let mut image = encoder.new_image::<C>(size[0], size[1]).unwrap();
    image.rows_per_strip(rows_per_strip).unwrap();
    geo.write(image.encoder());
    image.write_data(data).unwrap();
}

/// Samples of a hand-built tiled TIFF, in file order.
pub enum Samples {
    I16(Vec<i16>),
    F32(Vec<f32>),
}

impl Samples {
    fn bits_and_format(&self) -> (u16, u16) {
        match self {
            Samples::I16(_) => (16, 2),
            Samples::F32(_) => (32, 3),
        }
    }
}

/// Compression of a hand-built tiled TIFF (TIFF compression codes).
#[derive(Clone, Copy, Debug)]
pub enum TileCompression {
    None = 1,
    Lzw = 5,
    Deflate = 8,
}

/// Writes a tiled GeoTIFF by hand: `tile x tile` tiles, edge tiles padded
/// with zeros, each predicted (`predictor` 1 none, 2 horizontal for int16,
/// 3 floating point for float32) and compressed.
pub fn write_tiff_tiles(
    path: &Path,
    size: [u32; 2],
    tile: u32,
    samples: &Samples,
    compression: TileCompression,
    predictor: u16,
    geo: &GeoTags,
) {
    let file = BufWriter::new(File::create(path).unwrap());
    let mut encoder = TiffEncoder::new(file).unwrap();
    let mut dir = encoder.image_directory().unwrap();
    let (across, down) = (size[0].div_ceil(tile), size[1].div_ceil(tile));
    let (mut offsets, mut counts) = (Vec::new(), Vec::new());
    for t in 0..across * down {
        let bytes = tile_bytes(size, tile, [t % across, t / across], samples, predictor);
        let compressed = compress(compression, &bytes);
        offsets.push(dir.write_data(&compressed[..]).unwrap() as u32);
        counts.push(compressed.len() as u32);
    }
    let (bits, format) = samples.bits_and_format();
    dir.write_tag(Tag::ImageWidth, size[0]).unwrap();
    dir.write_tag(Tag::ImageLength, size[1]).unwrap();
    dir.write_tag(Tag::BitsPerSample, bits).unwrap();
    dir.write_tag(Tag::Compression, compression as u16).unwrap();
    dir.write_tag(Tag::PhotometricInterpretation, 1u16).unwrap();
    dir.write_tag(Tag::SamplesPerPixel, 1u16).unwrap();
    dir.write_tag(Tag::SampleFormat, format).unwrap();
    dir.write_tag(Tag::TileWidth, tile).unwrap();
    dir.write_tag(Tag::TileLength, tile).unwrap();
    dir.write_tag(Tag::TileOffsets, &offsets[..]).unwrap();
    dir.write_tag(Tag::TileByteCounts, &counts[..]).unwrap();
    dir.write_tag(Tag::Predictor, predictor).unwrap();
    geo.write(&mut dir);
    dir.finish().unwrap();
}

fn compress(compression: TileCompression, bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    match compression {
        TileCompression::None => out.extend_from_slice(bytes),
        TileCompression::Lzw => drop(Lzw.write_to(&mut out, bytes).unwrap()),
        TileCompression::Deflate => drop(Deflate::default().write_to(&mut out, bytes).unwrap()),
    }
    out
}

/// The predicted, native-endian bytes of tile `at` (column, row of tiles).
fn tile_bytes(
    size: [u32; 2],
    tile: u32,
    at: [u32; 2],
    samples: &Samples,
    predictor: u16,
) -> Vec<u8> {
    let mut bytes = Vec::new();
    for r in 0..tile {
        let (row, c0) = (at[1] * tile + r, at[0] * tile);
        let inside = |c: u32| row < size[1] && c0 + c < size[0];
        let index = |c: u32| (row * size[0] + c0 + c) as usize;
        match samples {
            Samples::I16(v) => {
                let line: Vec<i16> =
                    (0..tile).map(|c| if inside(c) { v[index(c)] } else { 0 }).collect();
                bytes.extend(predict_i16(&line, predictor));
            }
            Samples::F32(v) => {
                let line: Vec<f32> =
                    (0..tile).map(|c| if inside(c) { v[index(c)] } else { 0.0 }).collect();
                bytes.extend(predict_f32(&line, predictor));
            }
        }
    }
    bytes
}

fn predict_i16(line: &[i16], predictor: u16) -> Vec<u8> {
    let mut values = line.to_vec();
    if predictor == 2 {
        for k in (1..values.len()).rev() {
            values[k] = values[k].wrapping_sub(values[k - 1]);
        }
    }
    values.iter().flat_map(|v| v.to_ne_bytes()).collect()
}

/// TIFF floating-point predictor (Adobe technical note 3): the row's bytes
/// regrouped most significant byte plane first, then differenced bytewise.
fn predict_f32(line: &[f32], predictor: u16) -> Vec<u8> {
    if predictor != 3 {
        return line.iter().flat_map(|v| v.to_ne_bytes()).collect();
    }
    let n = line.len();
    let mut planes = vec![0u8; 4 * n];
    for (i, v) in line.iter().enumerate() {
        for (k, b) in v.to_be_bytes().into_iter().enumerate() {
            planes[k * n + i] = b;
        }
    }
    for k in (1..planes.len()).rev() {
        planes[k] = planes[k].wrapping_sub(planes[k - 1]);
    }
    planes
}

/// Writes a TIFF whose directory is whatever `tags` writes, after `data`.
pub fn write_tiff_raw(
    path: &Path,
    data: &[u8],
    tags: impl FnOnce(&mut DirectoryEncoder<'_, BufWriter<File>, TiffKindStandard>, u32),
) {
    let file = BufWriter::new(File::create(path).unwrap());
    let mut encoder = TiffEncoder::new(file).unwrap();
    let mut dir = encoder.image_directory().unwrap();
    let offset = dir.write_data(data).unwrap() as u32;
    tags(&mut dir, offset);
    dir.finish().unwrap();
}

/// Flushes and truncates a file to `len` bytes.
pub fn truncate(path: &Path, len: u64) {
    let file = std::fs::OpenOptions::new().write(true).open(path).unwrap();
    file.set_len(len).unwrap();
    let _ = (&file).flush();
}
