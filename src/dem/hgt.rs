//! SRTM `.hgt` tiles: a square of big-endian `i16` heights in metres, rows
//! from north to south, -32768 for voids, and no header at all: the size
//! says the resolution (1201 posts a side for 3", 3601 for 1") and the file
//! name says the south-west corner (`N39E040.hgt`: 39 N, 40 E). Posts sit on
//! whole-degree multiples, so the south-west post is exactly that corner.

use std::io::Read;
use std::path::Path;

use super::error::{ImportError, Problem};
use super::mosaic::Footprint;
use super::swath::{rows_per_swath, OpenedFile};
use crate::geo::{Crs, GeoRef};

/// The value SRTM uses for a void.
pub const VOID: i16 = -32768;

/// Posts per side of the two SRTM products.
const SIDES: [u32; 2] = [1201, 3601];

/// An opened `.hgt` tile: placed by its name, sized by its length.
pub struct HgtFile {
    footprint: Footprint,
}

/// Opens an SRTM `.hgt` tile (its name and length; nothing is decoded).
pub fn open(path: &Path) -> Result<HgtFile, ImportError> {
    let corner = corner_from_name(path)?;
    let len = super::raw::file_len(path)?;
    let side = SIDES
        .into_iter()
        .find(|&n| u64::from(n) * u64::from(n) * 2 == len)
        .ok_or_else(|| ImportError::new(path, Problem::HgtSize { actual: len }))?;
    let spacing = 1.0 / f64::from(side - 1);
    let georef = GeoRef { crs: Crs::Geographic, origin: corner, spacing: [spacing, spacing] };
    Ok(HgtFile { footprint: Footprint { path: path.to_path_buf(), georef, size: [side, side] } })
}

impl OpenedFile for HgtFile {
    fn footprint(&self) -> &Footprint {
        &self.footprint
    }

    fn read_into(
        self: Box<Self>,
        out: &mut [f32],
        swath_bytes: usize,
        swath_done: &mut dyn FnMut(),
    ) -> Result<(), ImportError> {
        let path = &self.footprint.path;
        let side = self.footprint.size[0] as usize;
        debug_assert_eq!(out.len(), side * side);
        let mut file = std::fs::File::open(path).map_err(|e| ImportError::new(path, e.into()))?;
        let rows = rows_per_swath(swath_bytes, 2 * side as u64, side);
        let mut bytes = vec![0u8; rows * 2 * side];
        for first in (0..side).step_by(rows) {
            let swath = &mut bytes[..rows.min(side - first) * 2 * side];
            if let Err(e) = file.read_exact(swath) {
                // The file shrank since it was opened: say how far it got.
                let actual = super::raw::file_len(path)?;
                let problem = match e.kind() {
                    std::io::ErrorKind::UnexpectedEof => Problem::HgtSize { actual },
                    _ => e.into(),
                };
                return Err(ImportError::new(path, problem));
            }
            for (k, row) in swath.chunks_exact(2 * side).enumerate() {
                // File row 0 is the northern row; grid row 0 is the southern one.
                let j = side - 1 - (first + k);
                let to = &mut out[j * side..(j + 1) * side];
                for (to, pair) in to.iter_mut().zip(row.chunks_exact(2)) {
                    let raw = i16::from_be_bytes([pair[0], pair[1]]);
                    *to = if raw == VOID { f32::NAN } else { f32::from(raw) };
                }
            }
            swath_done();
        }
        Ok(())
    }
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
