//! Which importer reads a file. The extension decides when it is known
//! (case-insensitive): `.tif`/`.tiff` GeoTIFF, `.hgt` SRTM, `.dt0`/`.dt1`/
//! `.dt2` DTED, `.asc` ESRI ASCII grid, `.nc`/`.cdf` netCDF-3. Otherwise the
//! first bytes decide (`CDF\x01`/`CDF\x02` netCDF-3):
//! `II*\0`, `MM\0*` (or the BigTIFF forms) GeoTIFF; `UHL`, or the tape labels
//! `VOL`/`HDR`, DTED; a first word `ncols` or `nrows` ASCII grid. SRTM tiles
//! have no magic, so an `.hgt` file must be named so. A file whose extension
//! and content disagree is refused by that extension's importer with a
//! "wrong magic" error rather than silently read as something else.

use std::path::Path;

use super::error::{ImportError, Problem};
use super::raw::read_prefix;

/// The supported input formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// GeoTIFF (.tif, .tiff): one band of heights with GeoKeys.
    GeoTiff,
    /// SRTM .hgt: 1201² or 3601² big-endian i16, placed by its file name.
    Hgt,
    /// DTED level 0, 1 or 2 (.dt0, .dt1, .dt2).
    Dted,
    /// ESRI ASCII grid (.asc), with an optional .prj sidecar.
    AsciiGrid,
    /// netCDF-3 classic (.nc, .cdf), a 2-D height variable on latitude and longitude.
    NetCdf,
}

/// Picks the format of `path` by extension, else by magic.
pub fn detect(path: &Path) -> Result<Format, ImportError> {
    if let Some(format) = by_extension(path) {
        return Ok(format);
    }
    let start = read_prefix(path, 64)?;
    by_magic(&start).ok_or_else(|| ImportError::new(path, Problem::UnknownFormat))
}

fn by_extension(path: &Path) -> Option<Format> {
    let extension = path.extension()?.to_string_lossy().to_ascii_lowercase();
    match extension.as_str() {
        "tif" | "tiff" => Some(Format::GeoTiff),
        "hgt" => Some(Format::Hgt),
        "dt0" | "dt1" | "dt2" => Some(Format::Dted),
        "asc" => Some(Format::AsciiGrid),
        "nc" | "cdf" => Some(Format::NetCdf),
        _ => None,
    }
}

fn by_magic(start: &[u8]) -> Option<Format> {
    if TIFF_MAGIC.iter().any(|m| start.starts_with(m)) {
        return Some(Format::GeoTiff);
    }
    if super::netcdf::MAGIC.iter().any(|m| start.starts_with(m)) {
        return Some(Format::NetCdf);
    }
    if [b"UHL", b"VOL", b"HDR"].iter().any(|m| start.starts_with(*m)) {
        return Some(Format::Dted);
    }
    let text = String::from_utf8_lossy(start).trim_start().to_ascii_lowercase();
    (text.starts_with("ncols") || text.starts_with("nrows")).then_some(Format::AsciiGrid)
}

/// The TIFF and BigTIFF signatures, shared with the GeoTIFF importer.
pub const TIFF_MAGIC: [&[u8]; 4] = [b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"];
