//! Decoding by swaths: every importer first *opens* a file (reads and checks
//! its header against the file's length, decodes no height), then decodes
//! its heights a *swath* at a time (a few rows, records, strips or tiles,
//! about [`SWATH_BYTES`] of the file) straight into a slice the caller
//! provides: a `Vec` for the in-memory import, a memory-mapped
//! [`crate::spill::Spill`] for the streaming one, whose pages the
//! `swath_done` callback drops. So no format holds a whole file in
//! memory; what one swath holds is the format's unit (a GeoTIFF strip or
//! tile is decoded whole, as the `tiff` crate does).

//! Opening a file of any format and decoding it whole are in
//! [`super::open`], which depends on every format; this module depends on
//! none, so the formats can use it.

use super::error::ImportError;
use super::mosaic::Footprint;

/// Bytes of a file decoded per swath (a multiple of any format's row
/// stays under a few MB of decoded heights).
pub const SWATH_BYTES: usize = 4 << 20;

/// A file whose header is read and checked, its heights not yet decoded.
pub trait OpenedFile {
    /// The file, its georeference and its size in posts.
    fn footprint(&self) -> &Footprint;

    /// Decodes every post into `out` (`width * height` heights, row 0
    /// southern, voids NaN), writing each post once, about `swath_bytes`
    /// of the file (at least one row, record, strip or tile) at a time,
    /// and calls `swath_done` after every swath.
    fn read_into(
        self: Box<Self>,
        out: &mut [f32],
        swath_bytes: usize,
        swath_done: &mut dyn FnMut(),
    ) -> Result<(), ImportError>;
}

/// Rows of `row_bytes` each in a swath of `swath_bytes`: at least one,
/// at most the file's `rows`.
pub fn rows_per_swath(swath_bytes: usize, row_bytes: u64, rows: usize) -> usize {
    (swath_bytes as u64 / row_bytes.max(1)).clamp(1, rows.max(1) as u64) as usize
}
