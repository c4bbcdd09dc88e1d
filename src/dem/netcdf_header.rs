//! Where a netCDF-3 variable's values start in the file: the `begin`
//! field of its entry in the header, which the `netcdf3` crate reads but
//! does not expose. The header has already been parsed and checked by
//! the crate when this walks it, so it only has to follow the layout
//! (netCDF classic format specification, "The Format in Detail"):
//! `magic numrecs dim_list gatt_list var_list`, big-endian 32-bit counts,
//! names and values padded to 4 bytes, `begin` 32 bits in CDF-1 and 64
//! in CDF-2.

use std::io::{BufReader, Read};
use std::path::Path;

use super::error::Problem;

const NC_DIMENSION: u32 = 0x0A;
const NC_VARIABLE: u32 = 0x0B;
const NC_ATTRIBUTE: u32 = 0x0C;
/// Longest name or attribute walked over: far beyond any real header.
const MAX_FIELD_BYTES: u64 = 1 << 24;

/// The byte offset of the values of the variable `name` in the file at `path`.
pub fn data_offset(path: &Path, name: &str) -> Result<u64, Problem> {
    let file = std::fs::File::open(path)?;
    let mut header = Header { input: BufReader::new(file) };
    let mut magic = [0u8; 4];
    header.input.read_exact(&mut magic)?;
    let wide_offsets = magic[3] == 2;
    header.word()?; // numrecs
    for _ in 0..header.list(NC_DIMENSION)? {
        header.name()?;
        header.word()?;
    }
    header.attributes()?;
    for _ in 0..header.list(NC_VARIABLE)? {
        let this = header.name()?;
        let dims = header.word()?;
        header.skip(4 * u64::from(dims))?;
        header.attributes()?;
        header.word()?; // nc_type
        header.word()?; // vsize
        let begin = if wide_offsets {
            (u64::from(header.word()?) << 32) | u64::from(header.word()?)
        } else {
            u64::from(header.word()?)
        };
        if this == name {
            return Ok(begin);
        }
    }
    Err(Problem::NetCdf(format!("no variable {name} in the header")))
}

struct Header<R> {
    input: R,
}

impl<R: Read> Header<R> {
    fn word(&mut self) -> Result<u32, Problem> {
        let mut bytes = [0u8; 4];
        self.input.read_exact(&mut bytes)?;
        Ok(u32::from_be_bytes(bytes))
    }

    fn skip(&mut self, bytes: u64) -> Result<(), Problem> {
        if bytes > MAX_FIELD_BYTES {
            return Err(Problem::NetCdf(format!("a header field of {bytes} bytes")));
        }
        let copied = std::io::copy(&mut (&mut self.input).take(bytes), &mut std::io::sink())?;
        if copied != bytes {
            return Err(Problem::NetCdf("the header is cut short".into()));
        }
        Ok(())
    }

    /// A list's element count: `tag count`, or `0 0` for an absent list.
    fn list(&mut self, tag: u32) -> Result<u32, Problem> {
        let (found, count) = (self.word()?, self.word()?);
        match (found, count) {
            (0, 0) => Ok(0),
            (found, count) if found == tag => Ok(count),
            _ => Err(Problem::NetCdf(format!("header list tag {found:#x}, expected {tag:#x}"))),
        }
    }

    fn name(&mut self) -> Result<String, Problem> {
        let len = u64::from(self.word()?);
        if len > MAX_FIELD_BYTES {
            return Err(Problem::NetCdf(format!("a name of {len} bytes")));
        }
        let mut bytes = vec![0u8; len as usize];
        self.input.read_exact(&mut bytes)?;
        self.skip(padding(len))?;
        Ok(String::from_utf8_lossy(&bytes).into_owned())
    }

    fn attributes(&mut self) -> Result<(), Problem> {
        for _ in 0..self.list(NC_ATTRIBUTE)? {
            self.name()?;
            let size = type_size(self.word()?)?;
            let bytes = u64::from(self.word()?) * size;
            self.skip(bytes + padding(bytes))?;
        }
        Ok(())
    }
}

/// Bytes that pad `len` to a multiple of 4.
fn padding(len: u64) -> u64 {
    (4 - len % 4) % 4
}

/// Bytes of one value of netCDF type `code` (byte, char, short, int, float, double).
fn type_size(code: u32) -> Result<u64, Problem> {
    match code {
        1 | 2 => Ok(1),
        3 => Ok(2),
        4 | 5 => Ok(4),
        6 => Ok(8),
        other => Err(Problem::NetCdf(format!("attribute type {other}"))),
    }
}
