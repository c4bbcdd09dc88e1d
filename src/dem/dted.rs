//! DTED levels 0, 1 and 2 (MIL-PRF-89020B): an 80-byte User Header Label
//! (UHL), a 648-byte Data Set Identification (DSI) record and a 2700-byte
//! Accuracy (ACC) record, all ASCII, then one binary data record per
//! longitude line (column), west to east, each running south to north:
//!
//! | bytes | field |
//! |---|---|
//! | 1 | sentinel 0xAA |
//! | 3 | data block count |
//! | 2 | longitude count (column index) |
//! | 2 | latitude count (0) |
//! | 2 x n | heights, signed magnitude big-endian, -32767 = void |
//! | 4 | checksum: the unsigned sum of every preceding byte of the record |
//!
//! The levels differ only in their intervals (latitude 30", 3", 1"; the
//! longitude interval widens with latitude zone); both intervals and the
//! south-west origin (a post) are read from the UHL. Tape copies may put
//! 80-byte `VOL` and `HDR` labels before the UHL; they are skipped.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::error::{ImportError, Problem};
use super::mosaic::Footprint;
use super::raw::check_dimensions;
use super::swath::{rows_per_swath, OpenedFile};
use crate::geo::{Crs, GeoRef};

const UHL_LEN: usize = 80;
const DSI_LEN: usize = 648;
const ACC_LEN: usize = 2700;
const HEADERS_LEN: usize = UHL_LEN + DSI_LEN + ACC_LEN;
/// An 80-byte tape label that may precede the UHL.
const LABEL_LEN: usize = 80;
/// Bytes of a data record around its heights: sentinel, counts, checksum.
const RECORD_OVERHEAD: usize = 12;
const SENTINEL: u8 = 0xAA;
/// The void value, after signed-magnitude decoding.
pub const VOID: i32 = -32767;

/// What the three headers say about the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DtedHeader {
    /// 0, 1 or 2, from the DSI.
    pub level: u8,
    /// South-west post `[longitude, latitude]` in degrees.
    pub origin: [f64; 2],
    /// Longitude and latitude intervals in tenths of arc seconds.
    pub interval_tenths: [u32; 2],
    /// Number of longitude lines (columns) and of points per line (rows).
    pub columns: u32,
    /// Points per longitude line (rows).
    pub rows: u32,
}

impl DtedHeader {
    fn record_len(&self) -> usize {
        RECORD_OVERHEAD + 2 * self.rows as usize
    }
}

/// An opened DTED file: its headers checked against its length.
pub struct DtedFile {
    footprint: Footprint,
    header: DtedHeader,
    /// Where the first data record starts.
    records_start: u64,
}

/// Opens a DTED file of level 0, 1 or 2: its headers (4 KiB at most) are
/// read first, so a header declaring a size the file does not have is
/// refused before anything else is read.
pub fn open(path: &Path) -> Result<DtedFile, ImportError> {
    let prefix = super::raw::read_prefix(path, (2 * LABEL_LEN + HEADERS_LEN) as u64)?;
    let start = skip_tape_labels(&prefix);
    let header = parse_headers(path, prefix.get(start..).unwrap_or_default())?;
    let (columns, rows) = check_dimensions(path, header.columns.into(), header.rows.into())?;
    let records_start = (start + HEADERS_LEN) as u64;
    let expected = records_start + u64::from(columns) * header.record_len() as u64;
    let actual = super::raw::file_len(path)?;
    if actual != expected {
        let problem = if actual < expected {
            Problem::Truncated {
                what: format!("{columns} columns of {rows} posts"),
                needed: expected,
                actual,
            }
        } else {
            Problem::SizeMismatch { expected, actual }
        };
        return Err(ImportError::new(path, problem));
    }
    let footprint =
        Footprint { path: path.to_path_buf(), georef: georef(&header), size: [columns, rows] };
    Ok(DtedFile { footprint, header, records_start })
}

impl OpenedFile for DtedFile {
    fn footprint(&self) -> &Footprint {
        &self.footprint
    }

    /// Swaths of whole data records (columns).
    fn read_into(
        self: Box<Self>,
        out: &mut [f32],
        swath_bytes: usize,
        swath_done: &mut dyn FnMut(),
    ) -> Result<(), ImportError> {
        let path = &self.footprint.path;
        let fail = |problem| ImportError::new(path, problem);
        let [columns, _] = self.footprint.size;
        let (width, record_len) = (columns as usize, self.header.record_len());
        let mut file = std::fs::File::open(path).map_err(|e| fail(e.into()))?;
        file.seek(SeekFrom::Start(self.records_start)).map_err(|e| fail(e.into()))?;
        let per_swath = rows_per_swath(swath_bytes, record_len as u64, width);
        let mut bytes = vec![0u8; per_swath * record_len];
        for first in (0..width).step_by(per_swath) {
            let swath = &mut bytes[..per_swath.min(width - first) * record_len];
            file.read_exact(swath).map_err(|e| fail(e.into()))?;
            for (k, record) in swath.chunks_exact(record_len).enumerate() {
                let column = (first + k) as u32;
                let heights = check_record(record, column).map_err(fail)?;
                for (j, h) in heights.enumerate() {
                    out[j * width + column as usize] = if h == VOID { f32::NAN } else { h as f32 };
                }
            }
            swath_done();
        }
        Ok(())
    }
}

fn georef(header: &DtedHeader) -> GeoRef {
    let [lon, lat] = header.interval_tenths.map(|t| f64::from(t) / 36_000.0);
    GeoRef { crs: Crs::Geographic, origin: header.origin, spacing: [lon, lat] }
}

/// Where the UHL starts: after any `VOL` and `HDR` tape labels.
fn skip_tape_labels(bytes: &[u8]) -> usize {
    let mut start = 0;
    for label in [b"VOL", b"HDR"] {
        if bytes.get(start..).is_some_and(|rest| rest.starts_with(label)) {
            start += LABEL_LEN;
        }
    }
    start
}

/// Parses and cross-checks the UHL, DSI and ACC records at the start of `bytes`.
pub fn parse_headers(path: &Path, bytes: &[u8]) -> Result<DtedHeader, ImportError> {
    let fail = |problem| ImportError::new(path, problem);
    if bytes.len() < HEADERS_LEN {
        let what = "the UHL, DSI and ACC headers".to_string();
        return Err(fail(Problem::Truncated {
            what,
            needed: HEADERS_LEN as u64,
            actual: bytes.len() as u64,
        }));
    }
    let (uhl, rest) = bytes.split_at(UHL_LEN);
    let (dsi, acc) = rest.split_at(DSI_LEN);
    for (record, magic) in [(uhl, "UHL1"), (dsi, "DSI"), (acc, "ACC")] {
        if !record.starts_with(magic.as_bytes()) {
            let found = String::from_utf8_lossy(&record[..magic.len()]).into_owned();
            return Err(fail(Problem::BadMagic { format: "DTED", expected: magic, found }));
        }
    }
    let header = parse_uhl(uhl, dsi).map_err(|msg| fail(Problem::Header(msg)))?;
    Ok(header)
}

fn parse_uhl(uhl: &[u8], dsi: &[u8]) -> Result<DtedHeader, String> {
    let lon = angle(&uhl[4..12], b'E', b'W', 180)?;
    let lat = angle(&uhl[12..20], b'N', b'S', 90)?;
    let lon_tenths = number(&uhl[20..24], "UHL longitude interval")?;
    let lat_tenths = number(&uhl[24..28], "UHL latitude interval")?;
    let columns = number(&uhl[47..51], "UHL number of longitude lines")?;
    let rows = number(&uhl[51..55], "UHL number of latitude points")?;
    let level = level(&dsi[59..64])?;
    // Table I of the specification: the latitude interval is the level's.
    let level_tenths = [300, 30, 10][level as usize];
    if lat_tenths != level_tenths {
        return Err(format!(
            "DSI says DTED{level} (latitude interval {level_tenths} tenths of a second) \
             but the UHL says {lat_tenths}"
        ));
    }
    if lon_tenths == 0 {
        return Err("UHL longitude interval is zero".into());
    }
    Ok(DtedHeader {
        level,
        origin: [lon, lat],
        interval_tenths: [lon_tenths, lat_tenths],
        columns,
        rows,
    })
}

/// The product level from the DSI designator `DTED0`, `DTED1` or `DTED2`.
fn level(field: &[u8]) -> Result<u8, String> {
    match field {
        b"DTED0" => Ok(0),
        b"DTED1" => Ok(1),
        b"DTED2" => Ok(2),
        _ => Err(format!(
            "DSI product level {:?} is not DTED0, DTED1 or DTED2",
            String::from_utf8_lossy(field)
        )),
    }
}

/// A decimal field of ASCII digits.
fn number(field: &[u8], what: &str) -> Result<u32, String> {
    let text = std::str::from_utf8(field).map_err(|_| format!("{what} is not ASCII"))?;
    text.trim().parse().map_err(|_| format!("{what} {text:?} is not a number"))
}

/// A `DDDMMSSH` angle in degrees; `positive`/`negative` are the hemisphere letters.
fn angle(field: &[u8], positive: u8, negative: u8, max_degrees: u32) -> Result<f64, String> {
    let text = String::from_utf8_lossy(field).into_owned();
    let bad = || format!("origin {text:?} is not DDDMMSSH");
    let sign = match field[7] {
        h if h == positive => 1.0,
        h if h == negative => -1.0,
        _ => return Err(bad()),
    };
    let degrees = number(&field[0..3], "origin degrees").map_err(|_| bad())?;
    let minutes = number(&field[3..5], "origin minutes").map_err(|_| bad())?;
    let seconds = number(&field[5..7], "origin seconds").map_err(|_| bad())?;
    if degrees > max_degrees || minutes >= 60 || seconds >= 60 {
        return Err(bad());
    }
    Ok(sign * (f64::from(degrees) + f64::from(minutes) / 60.0 + f64::from(seconds) / 3600.0))
}

/// Decodes a DTED signed-magnitude 16-bit value (high bit = sign).
pub fn signed_magnitude(raw: u16) -> i32 {
    let magnitude = i32::from(raw & 0x7FFF);
    if raw & 0x8000 != 0 {
        -magnitude
    } else {
        magnitude
    }
}

/// Checks the sentinel, counts and checksum of the data record of `column`
/// and returns its heights, south to north.
fn check_record(record: &[u8], column: u32) -> Result<impl Iterator<Item = i32> + '_, Problem> {
    let bad = |what: String| Problem::DtedRecord { column, what };
    if record[0] != SENTINEL {
        return Err(bad(format!("sentinel is {:#04x}, not 0xaa", record[0])));
    }
    let (body, checksum) = record.split_at(record.len() - 4);
    let stored = u32::from_be_bytes([checksum[0], checksum[1], checksum[2], checksum[3]]);
    let computed = body.iter().map(|&b| u32::from(b)).sum::<u32>();
    if stored != computed {
        return Err(Problem::DtedChecksum { column, stored, computed });
    }
    let longitude_count = signed_magnitude(u16::from_be_bytes([body[4], body[5]]));
    let latitude_count = signed_magnitude(u16::from_be_bytes([body[6], body[7]]));
    if longitude_count != column as i32 || latitude_count != 0 {
        return Err(bad(format!(
            "longitude count {longitude_count} and latitude count {latitude_count}, expected {column} and 0"
        )));
    }
    Ok(body[8..]
        .chunks_exact(2)
        .map(|pair| signed_magnitude(u16::from_be_bytes([pair[0], pair[1]]))))
}
