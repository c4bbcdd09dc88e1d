//! SRTM `.hgt` tiles: a square of big-endian `i16` heights in metres, rows
//! from north to south, -32768 for voids, and no header at all: the size
//! says the resolution (1201 posts a side for 3", 3601 for 1") and the file
//! name says the south-west corner (`N39E040.hgt`: 39 N, 40 E). Posts sit on
//! whole-degree multiples, so the south-west post is exactly that corner.

use std::path::Path;

use super::error::{ImportError, Problem};
use super::raw::{read_bounded, RawGrid};
use crate::geo::{Crs, GeoRef};

/// The value SRTM uses for a void.
pub const VOID: i16 = -32768;

/// Posts per side of the two SRTM products.
const SIDES: [u32; 2] = [1201, 3601];

/// Reads an SRTM `.hgt` tile.
pub fn read(path: &Path) -> Result<RawGrid, ImportError> {
    let corner = corner_from_name(path)?;
    let len = super::raw::file_len(path)?;
    let side = SIDES
        .into_iter()
        .find(|&n| u64::from(n) * u64::from(n) * 2 == len)
        .ok_or_else(|| ImportError::new(path, Problem::HgtSize { actual: len }))?;
    let bytes = read_bounded(path, len)?;
    if bytes.len() as u64 != len {
        // The file changed under us; report what we got.
        return Err(ImportError::new(path, Problem::HgtSize { actual: bytes.len() as u64 }));
    }
    let spacing = 1.0 / f64::from(side - 1);
    let georef = GeoRef { crs: Crs::Geographic, origin: corner, spacing: [spacing, spacing] };
    let mut grid = RawGrid::voids(path, side, side, georef);
    for (file_row, row) in bytes.chunks_exact(2 * side as usize).enumerate() {
        // File row 0 is the northern row; grid row 0 is the southern one.
        let j = side - 1 - file_row as u32;
        for (i, pair) in row.chunks_exact(2).enumerate() {
            let raw = i16::from_be_bytes([pair[0], pair[1]]);
            let index = grid.index(i as u32, j);
            grid.heights[index] = if raw == VOID { f32::NAN } else { f32::from(raw) };
        }
    }
    grid.debug_check();
    Ok(grid)
}

/// The south-west corner `[longitude, latitude]` named by the first seven
/// characters of the file name, case-insensitive (`N39E040`, `s05w072.hgt`,
/// `N39E040.SRTMGL1.hgt`).
pub fn corner_from_name(path: &Path) -> Result<[f64; 2], ImportError> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let bad = || ImportError::new(path, Problem::FileName(name.clone()));
    let upper = name.to_ascii_uppercase();
    let code = upper.get(..7).ok_or_else(bad)?.as_bytes();
    let lat_sign = match code[0] {
        b'N' => 1.0,
        b'S' => -1.0,
        _ => return Err(bad()),
    };
    let lon_sign = match code[3] {
        b'E' => 1.0,
        b'W' => -1.0,
        _ => return Err(bad()),
    };
    let digits = |s: &[u8]| -> Option<f64> {
        s.iter().all(u8::is_ascii_digit).then(|| std::str::from_utf8(s).ok()?.parse().ok())?
    };
    let lat = lat_sign * digits(&code[1..3]).ok_or_else(bad)?;
    let lon = lon_sign * digits(&code[4..7]).ok_or_else(bad)?;
    // The tile spans one degree north and east of its corner.
    if !(-90.0..=89.0).contains(&lat) || !(-180.0..=179.0).contains(&lon) {
        return Err(bad());
    }
    Ok([lon, lat])
}
