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
    /// What is wrong with it.
    pub problem: Problem,
}

impl ImportError {
    /// The error for `problem` in the file at `path`.
    pub fn new(path: &Path, problem: Problem) -> Self {
        ImportError { path: path.to_path_buf(), problem }
    }
}

/// What is wrong with a file.
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    /// The file could not be read.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// The import was given no files.
    #[error("no input files")]
    NoInput,
    /// Neither the extension nor the first bytes name a format.
    #[error("unknown format: the extension is not .tif/.tiff/.hgt/.dt0/.dt1/.dt2/.asc/.nc/.cdf and the start of the file matches no known magic")]
    UnknownFormat,
    /// The extension names a format whose magic the file lacks.
    #[error("wrong magic for {format}: expected {expected}, found {found:?}")]
    BadMagic {
        /// The format the extension names.
        format: &'static str,
        /// The magic that format starts with.
        expected: &'static str,
        /// What the file starts with.
        found: String,
    },
    /// The file ends before a part that must be there.
    #[error("truncated: {what} needs {needed} bytes but the file has {actual}")]
    Truncated {
        /// The part cut short.
        what: String,
        /// Bytes that part needs.
        needed: u64,
        /// Bytes in the file.
        actual: u64,
    },
    /// The header implies another file size.
    #[error("size does not match the header: the header implies {expected} bytes, the file has {actual}")]
    SizeMismatch {
        /// Bytes the header implies.
        expected: u64,
        /// Bytes in the file.
        actual: u64,
    },
    /// An .hgt file of neither SRTM size.
    #[error("file size {actual} bytes matches neither SRTM3 (1201 x 1201, 2884802 bytes) nor SRTM1 (3601 x 3601, 25934402 bytes)")]
    HgtSize {
        /// Bytes in the file.
        actual: u64,
    },
    #[error(
        "absurd dimensions {width} x {height}: refused (at least 1 x 1, at most {max} samples)"
    )]
    /// The header declares an empty or implausibly large grid.
    AbsurdDimensions {
        /// Posts per row declared.
        width: u64,
        /// Rows declared.
        height: u64,
        /// The most posts accepted.
        max: u64,
    },
    /// A file too large for the in-memory import (the streaming one reads it).
    #[error("{posts} posts: more than the {max} an in-memory import holds; `ridgeline import` streams it")]
    TooLargeInMemory {
        /// Posts the file declares.
        posts: u64,
        /// The most the in-memory import takes.
        max: u64,
    },
    /// A header field is missing, repeated or malformed.
    #[error("bad header: {0}")]
    Header(String),
    /// A valid file using a feature the importer does not read.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// An .hgt file name that does not place the tile.
    #[error("cannot place the tile from its file name {0:?} (expected e.g. N39E040.hgt)")]
    FileName(String),
    /// A height that is NaN, infinite or beyond any terrain, and not the declared no-data value.
    #[error("non-finite or out-of-range height {value} at file row {row}, column {column} (not the declared nodata)")]
    NonFinite {
        /// File row, from the first in the file.
        row: u64,
        /// File column.
        column: u64,
        /// The value read.
        value: f64,
    },
    /// The body has more or fewer heights than the header declares.
    #[error("expected {expected} height values after the header, found {found}")]
    ValueCount {
        /// Heights the header declares.
        expected: u64,
        /// Heights in the body.
        found: u64,
    },
    /// A text height that does not parse.
    #[error("height value {token:?} at file row {row}, column {column} is not a number")]
    NotANumber {
        /// File row.
        row: u64,
        /// File column.
        column: u64,
        /// The text found.
        token: String,
    },
    /// A DTED data record is malformed.
    #[error("DTED data record of column {column}: {what}")]
    DtedRecord {
        /// The record's longitude line.
        column: u32,
        /// What is wrong.
        what: String,
    },
    /// A DTED data record fails its checksum.
    #[error("DTED checksum failure in column {column}: stored {stored}, computed {computed}")]
    DtedChecksum {
        /// The record's longitude line.
        column: u32,
        /// The checksum in the file.
        stored: u32,
        /// The checksum of the bytes read.
        computed: u32,
    },
    /// The TIFF decoder refused the file.
    #[error("TIFF decoding failed: {0}")]
    Tiff(#[from] tiff::TiffError),
    /// Every post is a void.
    #[error("every sample is a void: there is nothing to fill the voids from")]
    AllVoids,
    /// The netCDF-3 header lacks what a height grid needs, or the crate refused it.
    #[error("netCDF-3 header not understood: {0}")]
    NetCdf(String),
    /// An ESRI ASCII grid whose numbers look like degrees has no .prj to say so.
    #[error("the header's numbers look like degrees (corner {x}, {y}, cell size {cell_size}) but there is no .prj sidecar, so they would be read as metres; add a .prj beside the file whose WKT starts with GEOGCS (for example GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]]), or reproject the grid to metres")]
    DegreesWithoutPrj {
        /// The header's x corner.
        x: f64,
        /// The header's y corner.
        y: f64,
        /// The header's cell size.
        cell_size: f64,
    },
    /// The files do not join into one grid (different lattices, overlaps that disagree).
    #[error("cannot join the mosaic: {0}")]
    Mosaic(String),
}
