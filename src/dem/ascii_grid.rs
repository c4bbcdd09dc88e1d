//! ESRI ASCII grids (`.asc`): a header of `keyword value` pairs, then the
//! heights as text, the northern row first.
//!
//! Header keywords (case-insensitive): `ncols`, `nrows`, `xllcorner` or
//! `xllcenter`, `yllcorner` or `yllcenter`, `cellsize` (or GDAL's `dx` and
//! `dy`), and optionally `nodata_value` (ESRI's default is -9999). With
//! `*corner` the numbers name the outer corner of the south-west cell, so the
//! south-west post is half a cell further in; with `*center` they name the
//! post itself.
//!
//! The format carries no coordinate system. A `.prj` sidecar whose WKT starts
//! with `GEOGCS`/`GEOGCRS` makes the grid geographic, `PROJCS`/`PROJCRS`
//! projected (code unknown); without a sidecar the grid is local metres,
//! except that a grid whose numbers only make sense in degrees (|x| <= 180,
//! |y| <= 90 over the whole grid and a cell size under 0.01) is refused with
//! [`Problem::DegreesWithoutPrj`], which says how to add the sidecar: read as
//! metres it would be a needle a few centimetres wide and kilometres tall.
//!
//! The file is read as a stream of tokens, so it is never held in memory;
//! the heights go wherever the caller puts them ([`super::swath`]).

use std::io::{BufRead, BufReader};
use std::path::Path;

use super::error::{ImportError, Problem};
use super::mosaic::Footprint;
use super::raw::{check_dimensions, classify, file_len, non_finite, NoData};
use super::swath::OpenedFile;
use crate::geo::{Crs, GeoRef};

/// Cell size below which a grid without `.prj` whose corners fit in
/// longitude and latitude ranges is taken to be in degrees and refused.
const DEGREE_LIKE_CELL: f64 = 0.01;
/// ESRI's nodata when the header declares none.
const DEFAULT_NODATA: f64 = -9999.0;
/// Longest token accepted: numbers are short, so a longer run of
/// non-blank bytes means the file is not a grid (and must not fill memory).
const MAX_TOKEN_LEN: usize = 256;
/// Largest `.prj` sidecar read; WKT is a few hundred bytes.
const MAX_PRJ_LEN: u64 = 64 * 1024;

/// An opened ESRI ASCII grid: its header read, the first value in hand.
pub struct AsciiFile {
    footprint: Footprint,
    tokens: Tokens<BufReader<std::fs::File>>,
    /// The first value (the header parser stopped at it).
    token: Vec<u8>,
    nodata: NoData,
}

/// Opens an ESRI ASCII grid: reads its header and its `.prj` sidecar.
pub fn open(path: &Path) -> Result<AsciiFile, ImportError> {
    let fail = |problem| ImportError::new(path, problem);
    let file = std::fs::File::open(path).map_err(|e| fail(e.into()))?;
    let mut tokens = Tokens { reader: BufReader::new(file), consumed: 0 };
    let mut token = Vec::new();
    let header = Header::parse(&mut tokens, &mut token).map_err(fail)?;
    let (width, height) = check_dimensions(path, header.ncols, header.nrows)?;
    // Each value needs a character and a separator: refuse a declaration the
    // rest of the file cannot hold before allocating the grid.
    let samples = u64::from(width) * u64::from(height);
    let values_start = tokens.consumed.saturating_sub(token.len() as u64 + 1);
    let (needed, actual) = (values_start + 2 * samples - 1, file_len(path)?);
    if actual < needed {
        return Err(fail(Problem::Truncated {
            what: format!("{width} x {height} values"),
            needed,
            actual,
        }));
    }
    let crs = sidecar_crs(path)?;
    if crs == Crs::Local && header.looks_like_degrees() {
        let [x, y] = header.lower_left;
        let cell_size = header.spacing[0].max(header.spacing[1]);
        return Err(fail(Problem::DegreesWithoutPrj { x, y, cell_size }));
    }
    let georef = GeoRef { crs, origin: header.origin(), spacing: header.spacing };
    let footprint = Footprint { path: path.to_path_buf(), georef, size: [width, height] };
    Ok(AsciiFile { footprint, tokens, token, nodata: header.nodata })
}

impl OpenedFile for AsciiFile {
    fn footprint(&self) -> &Footprint {
        &self.footprint
    }

    /// The text is a stream of tokens; a swath is `swath_bytes` of it.
    fn read_into(
        self: Box<Self>,
        out: &mut [f32],
        swath_bytes: usize,
        swath_done: &mut dyn FnMut(),
    ) -> Result<(), ImportError> {
        let AsciiFile { footprint, mut tokens, mut token, nodata } = *self;
        let path = &footprint.path;
        let [width, height] = footprint.size;
        let samples = u64::from(width) * u64::from(height);
        let (mut count, mut swath_end) = (0u64, tokens.consumed.saturating_add(swath_bytes as u64));
        while !token.is_empty() {
            if count < samples {
                let value = parse(path, width, count, &token, nodata)?;
                let (row, column) = (count / u64::from(width), count % u64::from(width));
                let j = u64::from(height) - 1 - row;
                out[(j * u64::from(width) + column) as usize] = value;
            }
            count += 1;
            token.clear();
            tokens.next_into(&mut token).map_err(|e| ImportError::new(path, e.into()))?;
            if tokens.consumed >= swath_end {
                swath_done();
                swath_end = tokens.consumed.saturating_add(swath_bytes as u64);
            }
        }
        if count != samples {
            return Err(ImportError::new(
                path,
                Problem::ValueCount { expected: samples, found: count },
            ));
        }
        swath_done();
        Ok(())
    }
}

/// Parses value number `k` (row-major from the north-west) of a grid
/// `width` posts wide.
fn parse(
    path: &Path,
    width: u32,
    k: u64,
    token: &[u8],
    nodata: NoData,
) -> Result<f32, ImportError> {
    let (row, column) = (k / u64::from(width), k % u64::from(width));
    let text = String::from_utf8_lossy(token);
    let value: f64 = text.parse().map_err(|_| {
        ImportError::new(path, Problem::NotANumber { row, column, token: text.to_string() })
    })?;
    classify(value, Some(nodata)).ok_or_else(|| non_finite(path, row, column, value))
}

/// The header's numbers.
#[derive(Debug)]
struct Header {
    ncols: u64,
    nrows: u64,
    /// `xll*`, `yll*` as written.
    lower_left: [f64; 2],
    /// Whether `lower_left` is the cell corner (`*corner`) or the post (`*center`).
    corner: bool,
    spacing: [f64; 2],
    nodata: NoData,
}

impl Header {
    /// Reads `keyword value` pairs until the first token that is not a
    /// keyword, which is left in `token` (it is the first height).
    fn parse<R: BufRead>(tokens: &mut Tokens<R>, token: &mut Vec<u8>) -> Result<Header, Problem> {
        let mut fields: Vec<(String, f64)> = Vec::new();
        loop {
            token.clear();
            if !tokens.next_into(token)? {
                break;
            }
            let key = String::from_utf8_lossy(token).to_ascii_lowercase();
            if !KEYWORDS.contains(&key.as_str()) {
                if fields.is_empty() {
                    return Err(Problem::BadMagic {
                        format: "ESRI ASCII grid",
                        expected: "ncols",
                        found: key,
                    });
                }
                break;
            }
            token.clear();
            tokens.next_into(token)?;
            let text = String::from_utf8_lossy(token);
            let value = text
                .parse()
                .map_err(|_| Problem::Header(format!("{key} {text:?} is not a number")))?;
            fields.push((key, value));
        }
        Header::from_fields(&fields)
    }

    fn from_fields(fields: &[(String, f64)]) -> Result<Header, Problem> {
        let get = |key: &str| fields.iter().find(|(k, _)| k == key).map(|&(_, v)| v);
        let need = |key: &str| get(key).ok_or_else(|| Problem::Header(format!("no {key}")));
        let count = |key: &str| -> Result<u64, Problem> {
            let v = need(key)?;
            if v.fract() != 0.0 || v < 0.0 || v > u32::MAX as f64 {
                return Err(Problem::Header(format!("{key} {v} is not a count")));
            }
            Ok(v as u64)
        };
        let either = |corner: &str, center: &str| match (get(corner), get(center)) {
            (Some(v), None) => Ok((v, true)),
            (None, Some(v)) => Ok((v, false)),
            _ => Err(Problem::Header(format!("need exactly one of {corner} and {center}"))),
        };
        let (x, x_corner) = either("xllcorner", "xllcenter")?;
        let (y, y_corner) = either("yllcorner", "yllcenter")?;
        if x_corner != y_corner {
            return Err(Problem::Header("mixes *corner and *center".into()));
        }
        let spacing = match (get("cellsize"), get("dx"), get("dy")) {
            (Some(s), None, None) => [s, s],
            (None, Some(dx), Some(dy)) => [dx, dy],
            _ => return Err(Problem::Header("need cellsize, or dx and dy".into())),
        };
        if !spacing.iter().all(|s| s.is_finite() && *s > 0.0) || !x.is_finite() || !y.is_finite() {
            return Err(Problem::Header(format!(
                "spacing {spacing:?} or corner ({x}, {y}) is not usable"
            )));
        }
        let nodata = NoData(get("nodata_value").unwrap_or(DEFAULT_NODATA));
        Ok(Header {
            ncols: count("ncols")?,
            nrows: count("nrows")?,
            lower_left: [x, y],
            corner: x_corner,
            spacing,
            nodata,
        })
    }

    /// Whether the numbers only make sense in degrees: the whole grid lies
    /// within |x| <= 180, |y| <= 90 and cells are under 0.01 (1 cm in metres,
    /// about 1 km in degrees).
    fn looks_like_degrees(&self) -> bool {
        let [x, y] = self.lower_left;
        let east = x + self.spacing[0] * self.ncols as f64;
        let north = y + self.spacing[1] * self.nrows as f64;
        let small = self.spacing.iter().all(|&s| s < DEGREE_LIKE_CELL);
        small
            && [x, east].iter().all(|v| v.abs() <= 180.0)
            && [y, north].iter().all(|v| v.abs() <= 90.0)
    }

    /// The south-west post.
    fn origin(&self) -> [f64; 2] {
        let half = if self.corner { 0.5 } else { 0.0 };
        [self.lower_left[0] + half * self.spacing[0], self.lower_left[1] + half * self.spacing[1]]
    }
}

const KEYWORDS: [&str; 10] = [
    "ncols",
    "nrows",
    "xllcorner",
    "xllcenter",
    "yllcorner",
    "yllcenter",
    "cellsize",
    "dx",
    "dy",
    "nodata_value",
];

/// The coordinate system named by a `.prj` sidecar, if there is one.
fn sidecar_crs(path: &Path) -> Result<Crs, ImportError> {
    let prj = path.with_extension("prj");
    if !prj.exists() {
        return Ok(Crs::Local);
    }
    let text =
        String::from_utf8_lossy(&super::raw::read_bounded(&prj, MAX_PRJ_LEN)?).to_ascii_uppercase();
    let text = text.trim_start();
    if text.starts_with("GEOGCS") || text.starts_with("GEOGCRS") {
        Ok(Crs::Geographic)
    } else if text.starts_with("PROJCS") || text.starts_with("PROJCRS") {
        Ok(Crs::Projected { epsg: None })
    } else {
        Err(ImportError::new(
            &prj,
            Problem::Unsupported("the .prj sidecar is not WKT GEOGCS or PROJCS".into()),
        ))
    }
}

/// Whitespace-separated tokens of a text stream.
struct Tokens<R> {
    reader: R,
    /// Bytes consumed so far.
    consumed: u64,
}

impl<R: BufRead> Tokens<R> {
    /// Appends the next token to `token`; false at the end of the stream.
    fn next_into(&mut self, token: &mut Vec<u8>) -> std::io::Result<bool> {
        loop {
            let available = self.reader.fill_buf()?;
            if available.is_empty() {
                return Ok(!token.is_empty());
            }
            let mut used = 0;
            let mut done = false;
            for &byte in available {
                used += 1;
                if byte.is_ascii_whitespace() {
                    if !token.is_empty() {
                        done = true;
                        break;
                    }
                } else if token.len() < MAX_TOKEN_LEN {
                    token.push(byte);
                } else {
                    let message = format!("a token longer than {MAX_TOKEN_LEN} bytes");
                    return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, message));
                }
            }
            self.reader.consume(used);
            self.consumed += used as u64;
            if done {
                return Ok(true);
            }
        }
    }
}
