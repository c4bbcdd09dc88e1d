//! A synthetic world grid for the import scale table: `W x H` posts of
//! `360 / W` degrees from 180 W and 90 N, as an uncompressed int16 GeoTIFF
//! of strips (PixelIsArea, WGS 84), the form the importer decodes strip by
//! strip. The terrain is deterministic and continuous, a function of
//! longitude with whole frequencies only, so it wraps at 180 degrees with
//! no seam, with oceans below 0 m (about 40 % of the posts). Written by
//! hand, streaming, a strip at a time: the writer never holds the grid.

use std::io::{BufWriter, Write};
use std::path::Path;

use rayon::prelude::*;

/// Rows per strip (GDAL's default for uncompressed rasters is a few rows).
const ROWS_PER_STRIP: u32 = 8;

/// Writes the world grid of `width x height` posts to `path` (through a
/// temporary beside it, renamed into place) unless it is already there.
pub fn write_world(path: &Path, width: u32, height: u32) {
    let (strips, data_bytes) = layout(width, height);
    let ifd_at = 8 + data_bytes;
    let expected_len = ifd_at + ifd_bytes(strips);
    if std::fs::metadata(path).map(|m| m.len()).ok() == Some(expected_len) {
        return;
    }
    let temporary = path.with_extension("tmp");
    let file = std::fs::File::create(&temporary).expect("create the world grid");
    let mut out = BufWriter::with_capacity(4 << 20, file);
    let mut header = b"II*\0".to_vec();
    header.extend((ifd_at as u32).to_le_bytes());
    out.write_all(&header).expect("write the world grid");
    let mut strip = vec![0u8; (2 * width * ROWS_PER_STRIP) as usize];
    for first in (0..height).step_by(ROWS_PER_STRIP as usize) {
        let rows = ROWS_PER_STRIP.min(height - first) as usize;
        let bytes = &mut strip[..rows * 2 * width as usize];
        bytes.par_chunks_mut(2 * width as usize).enumerate().for_each(|(k, row)| {
            for (i, out) in row.chunks_exact_mut(2).enumerate() {
                let h = height_at(i as u32, first + k as u32, width, height);
                out.copy_from_slice(&h.to_le_bytes());
            }
        });
        out.write_all(bytes).expect("write the world grid");
    }
    out.write_all(&ifd(width, height, ifd_at)).expect("write the world grid");
    out.flush().expect("write the world grid");
    drop(out);
    std::fs::rename(&temporary, path).expect("name the world grid");
}

/// Strips and bytes of samples.
fn layout(width: u32, height: u32) -> (u32, u64) {
    (height.div_ceil(ROWS_PER_STRIP), 2 * u64::from(width) * u64::from(height))
}

/// Height at column `i`, file row `r` (row 0 north) of the world grid.
pub fn height_at(i: u32, r: u32, width: u32, height: u32) -> i16 {
    let lon = std::f64::consts::TAU * ((f64::from(i) + 0.5) / f64::from(width) - 0.5);
    let lat = std::f64::consts::PI * (0.5 - (f64::from(r) + 0.5) / f64::from(height));
    let continents = 2600.0 * (2.0 * lon + 0.7).sin() * (3.0 * lat).cos()
        + 1400.0 * (5.0 * lon - 1.1).cos() * (4.0 * lat + 0.3).sin();
    let ranges = 900.0 * (23.0 * lon + 11.0 * lat).sin().abs();
    let hills = 120.0 * (181.0 * lon).sin() * (173.0 * lat).cos();
    // A hash of the post (column taken modulo the width: it wraps too).
    let mut h = u64::from(i % width).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ u64::from(r).wrapping_mul(0xC2B2_AE3D);
    h ^= h >> 29;
    let jitter = (h % 5) as f64 - 2.0;
    (continents + ranges + hills + jitter - 600.0) as i16
}

/// Bytes of the IFD and the arrays after it.
fn ifd_bytes(strips: u32) -> u64 {
    ifd(1, strips * ROWS_PER_STRIP, 0).len() as u64
}

/// The image file directory at byte `at` and the arrays it points to.
fn ifd(width: u32, height: u32, at: u64) -> Vec<u8> {
    const SHORT: u16 = 3;
    const LONG: u16 = 4;
    const DOUBLE: u16 = 12;
    let (strips, _) = layout(width, height);
    let strip_bytes = |s: u32| 2 * width * ROWS_PER_STRIP.min(height - s * ROWS_PER_STRIP);
    let offsets: Vec<u32> = (0..strips).map(|s| 8 + s * 2 * width * ROWS_PER_STRIP).collect();
    let counts: Vec<u32> = (0..strips).map(strip_bytes).collect();
    let spacing = 360.0 / f64::from(width);
    let scale = [spacing, spacing, 0.0];
    let tie = [0.0, 0.0, 0.0, -180.0, 90.0, 0.0];
    // GTModelType geographic, PixelIsArea, WGS 84.
    let keys: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326];
    let entries = 13u64;
    let arrays_at = at + 2 + 12 * entries + 4;
    let mut arrays: Vec<u8> = Vec::new();
    let mut array = |bytes: Vec<u8>| {
        let offset = arrays_at + arrays.len() as u64;
        arrays.extend(bytes);
        offset as u32
    };
    let le32 = |v: &[u32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let le64 = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let offsets_at = array(le32(&offsets));
    let counts_at = array(le32(&counts));
    let scale_at = array(le64(&scale));
    let tie_at = array(le64(&tie));
    let keys_at = array(keys.iter().flat_map(|k| k.to_le_bytes()).collect());
    let table: [(u16, u16, u32, u32); 13] = [
        (256, LONG, 1, width),
        (257, LONG, 1, height),
        (258, SHORT, 1, 16),
        (259, SHORT, 1, 1),
        (262, SHORT, 1, 1),
        (273, LONG, strips, offsets_at),
        (277, SHORT, 1, 1),
        (278, LONG, 1, ROWS_PER_STRIP),
        (279, LONG, strips, counts_at),
        (339, SHORT, 1, 2),
        (33550, DOUBLE, 3, scale_at),
        (33922, DOUBLE, 6, tie_at),
        (34735, SHORT, keys.len() as u32, keys_at),
    ];
    let mut out = (table.len() as u16).to_le_bytes().to_vec();
    for (tag, kind, count, value) in table {
        out.extend(tag.to_le_bytes());
        out.extend(kind.to_le_bytes());
        out.extend(count.to_le_bytes());
        // A count of one SHORT sits inline in the low bytes.
        out.extend(value.to_le_bytes());
    }
    out.extend(0u32.to_le_bytes());
    debug_assert_eq!(out.len() as u64, arrays_at - at);
    out.extend(arrays);
    out
}
