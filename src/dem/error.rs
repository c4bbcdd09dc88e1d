//! Typed import failures: every error names the file it came from and says
//! precisely what is wrong with it, so a user with a folder of tiles can find
//! the bad one.

use std::path::{Path, PathBuf};

/// An input file could not be turned into elevation samples.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct ImportError {
    /// The file at fault (empty only for [`Problem::NoInput`]).
    pub path: PathBuf,
    pub problem: Problem,
}

impl ImportError {
    pub fn new(path: &Path, problem: Problem) -> Self {
        ImportError { path: path.to_path_buf(), problem }
    }
}

/// What is wrong with a file.
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    #[error("no input files")]
    NoInput,
    #[error("unknown format: the extension is not .tif/.tiff/.hgt/.dt0/.dt1/.dt2/.asc/.nc/.cdf and the start of the file matches no known magic")]
    UnknownFormat,
    #[error("wrong magic for {format}: expected {expected}, found {found:?}")]
    BadMagic { format: &'static str, expected: &'static str, found: String },
    #[error("truncated: {what} needs {needed} bytes but the file has {actual}")]
    Truncated { what: String, needed: u64, actual: u64 },
    #[error("size does not match the header: the header implies {expected} bytes, the file has {actual}")]
    SizeMismatch { expected: u64, actual: u64 },
    #[error("file size {actual} bytes matches neither SRTM3 (1201 x 1201, 2884802 bytes) nor SRTM1 (3601 x 3601, 25934402 bytes)")]
    HgtSize { actual: u64 },
    #[error(
        "absurd dimensions {width} x {height}: refused (at least 1 x 1, at most {max} samples)"
    )]
    AbsurdDimensions { width: u64, height: u64, max: u64 },
    #[error("bad header: {0}")]
    Header(String),
    #[error("unsupported: {0}")]
    Unsupported(String),
    #[error("cannot place the tile from its file name {0:?} (expected e.g. N39E040.hgt)")]
    FileName(String),
    #[error("non-finite or out-of-range height {value} at file row {row}, column {column} (not the declared nodata)")]
    NonFinite { row: u64, column: u64, value: f64 },
    #[error("expected {expected} height values after the header, found {found}")]
    ValueCount { expected: u64, found: u64 },
    #[error("height value {token:?} at file row {row}, column {column} is not a number")]
    NotANumber { row: u64, column: u64, token: String },
    #[error("DTED data record of column {column}: {what}")]
    DtedRecord { column: u32, what: String },
    #[error("DTED checksum failure in column {column}: stored {stored}, computed {computed}")]
    DtedChecksum { column: u32, stored: u32, computed: u32 },
    #[error("TIFF decoding failed: {0}")]
    Tiff(#[from] tiff::TiffError),
    #[error("every sample is a void: there is nothing to fill the voids from")]
    AllVoids,
    #[error("netCDF-3 header not understood: {0}")]
    NetCdf(String),
    #[error("the header's numbers look like degrees (corner {x}, {y}, cell size {cell_size}) but there is no .prj sidecar, so they would be read as metres; add a .prj beside the file whose WKT starts with GEOGCS (for example GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]]), or reproject the grid to metres")]
    DegreesWithoutPrj { x: f64, y: f64, cell_size: f64 },
    #[error("cannot join the mosaic: {0}")]
    Mosaic(String),
}
