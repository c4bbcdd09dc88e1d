//! netCDF-3 classic (CDF-1) and 64-bit offset (CDF-2) grids, read through the
//! pure-Rust `netcdf3` crate (no C library to cross-compile for the boards).
//!
//! The file must hold exactly one two-dimensional numeric variable whose two
//! dimensions each have a one-dimensional coordinate variable of the same
//! name (the netCDF convention): the first dimension is latitude, the second
//! longitude (fastest varying), in degrees. Its `_FillValue` or
//! `missing_value` attribute, or netCDF's default fill for its type when it
//! declares neither, marks voids; any other NaN or infinity is an error.
//!
//! Georeference: stored coordinate variables drift (ETOPO5's longitudes are
//! written in `f32` and wander off `i / 12` by up to 0.01 degree), so the
//! spacing is snapped to the nearest whole number of posts per degree when
//! it is within 1 % of one, and the origin to that lattice; every stored
//! coordinate must then lie within a quarter spacing of its computed
//! position, otherwise the grid is refused as irregular. Latitudes may run
//! either way (ETOPO5's run south first); rows are turned so that row 0 is
//! the southern row. Longitudes are kept as stored (ETOPO5's run 0 to
//! 359.92 east); a grid crossing its own first meridian is not joined.
//!
//! Sizes are checked against the file's length before the variable is read,
//! so an absurd header cannot allocate.

use std::path::Path;

use netcdf3::{DataSet, DataType, DataVector, FileReader, ReadError, Variable};

use super::error::{ImportError, Problem};
use super::mosaic::Footprint;
use super::raw::{check_dimensions, classify, file_len, non_finite, NoData};
use super::swath::{rows_per_swath, OpenedFile};
use crate::geo::{Crs, GeoRef};

/// The start of every netCDF-3 file: `CDF` and the version byte (1 classic,
/// 2 64-bit offsets).
pub const MAGIC: [&[u8]; 2] = [b"CDF\x01", b"CDF\x02"];
/// Largest relative distance of the spacing from a whole number of posts per
/// degree for it to be snapped.
const SNAP_TOLERANCE: f64 = 1e-2;
/// Largest distance, in spacings, of a stored coordinate from its post.
const COORDINATE_TOLERANCE: f64 = 0.25;

/// An opened netCDF-3 grid: its header and coordinates read and checked,
/// the heights not yet.
pub struct NetCdfFile {
    footprint: Footprint,
    /// Where the height variable's values start.
    begin: u64,
    data_type: DataType,
    /// Latitudes run south first (else rows are turned).
    south_first: bool,
    nodata: NoData,
}

/// Opens a netCDF-3 file: reads its header and its coordinate variables.
pub fn open(path: &Path) -> Result<NetCdfFile, ImportError> {
    let fail = |problem| ImportError::new(path, problem);
    let start = super::raw::read_prefix(path, 4)?;
    if !MAGIC.iter().any(|m| start == *m) {
        return Err(fail(Problem::BadMagic {
            format: "netCDF-3",
            expected: "CDF\\x01 or CDF\\x02",
            found: String::from_utf8_lossy(&start).into_owned(),
        }));
    }
    let actual = file_len(path)?;
    let mut reader = FileReader::open(path).map_err(|e| fail(netcdf_problem(e, actual)))?;
    let (name, lat_dim, lon_dim, rows, columns, nodata, data_type, needed) = {
        let data_set = reader.data_set();
        let variable = elevation_variable(data_set).map_err(fail)?;
        let dims = variable.get_dims();
        let (lat_dim, lon_dim) = (dims[0].name(), dims[1].name());
        let coordinates = [coordinate(data_set, &lat_dim), coordinate(data_set, &lon_dim)];
        let [lat_var, lon_var] = coordinates.map(|c| c.map_err(fail));
        // Every value the variables claim must fit in the file before any is read.
        let needed = [variable, lat_var?, lon_var?]
            .iter()
            .map(|v| v.len() as u64 * v.data_type().size_of() as u64)
            .sum::<u64>();
        let name = variable.name().to_string();
        let (rows, columns) = (dims[0].size() as u64, dims[1].size() as u64);
        let data_type = variable.data_type();
        (name, lat_dim, lon_dim, rows, columns, fill_value(variable), data_type, needed)
    };
    let (width, height) = check_dimensions(path, columns, rows)?;
    if needed > actual {
        let what = format!("{columns} x {rows} values of {name}");
        return Err(fail(Problem::Truncated { what, needed, actual }));
    }
    let lats = read_f64(&mut reader, &lat_dim, actual).map_err(fail)?;
    let lons = read_f64(&mut reader, &lon_dim, actual).map_err(fail)?;
    let (lon0, lon_step) = lattice(&lons, "longitude").map_err(fail)?;
    let (lat0, lat_step) = lattice(&lats, "latitude").map_err(fail)?;
    let south_first = lat_step > 0.0;
    let origin = [lon0, if south_first { lat0 } else { lat0 + lat_step * (rows - 1) as f64 }];
    if lon_step <= 0.0 {
        return Err(fail(Problem::Unsupported("longitudes run westwards".into())));
    }
    let georef = GeoRef { crs: Crs::Geographic, origin, spacing: [lon_step, lat_step.abs()] };
    if let Some(problem) = georef.problem([width, height]) {
        return Err(fail(Problem::Header(problem)));
    }
    let begin = super::netcdf_header::data_offset(path, &name).map_err(fail)?;
    let bytes = rows * columns * data_type.size_of() as u64;
    if begin.saturating_add(bytes) > actual {
        let what = format!("{columns} x {rows} values of {name} from byte {begin}");
        return Err(fail(Problem::Truncated { what, needed: begin + bytes, actual }));
    }
    let footprint = Footprint { path: path.to_path_buf(), georef, size: [width, height] };
    Ok(NetCdfFile { footprint, begin, data_type, south_first, nodata })
}

impl OpenedFile for NetCdfFile {
    fn footprint(&self) -> &Footprint {
        &self.footprint
    }

    /// Swaths of whole rows, read at their place in the file.
    fn read_into(
        self: Box<Self>,
        out: &mut [f32],
        swath_bytes: usize,
        swath_done: &mut dyn FnMut(),
    ) -> Result<(), ImportError> {
        let path = &self.footprint.path;
        let fail = |problem| ImportError::new(path, problem);
        let [width, height] = self.footprint.size.map(|s| s as usize);
        let size = self.data_type.size_of();
        let file = std::fs::File::open(path).map_err(|e| fail(e.into()))?;
        let rows = rows_per_swath(swath_bytes, (width * size) as u64, height);
        let mut bytes = vec![0u8; rows * width * size];
        for first in (0..height).step_by(rows) {
            let swath = &mut bytes[..rows.min(height - first) * width * size];
            let at = self.begin + (first * width * size) as u64;
            read_exact_at(&file, swath, at).map_err(|e| fail(e.into()))?;
            for (k, row) in swath.chunks_exact(width * size).enumerate() {
                let file_row = first + k;
                let j = if self.south_first { file_row } else { height - 1 - file_row };
                let to = &mut out[j * width..(j + 1) * width];
                for (column, (to, value)) in to.iter_mut().zip(row.chunks_exact(size)).enumerate() {
                    let value = big_endian(&self.data_type, value);
                    *to = classify(value, Some(self.nodata))
                        .ok_or_else(|| non_finite(path, file_row as u64, column as u64, value))?;
                }
            }
            swath_done();
        }
        Ok(())
    }
}

/// One big-endian value of `data_type` as `f64`.
fn big_endian(data_type: &DataType, bytes: &[u8]) -> f64 {
    match data_type {
        DataType::I8 => f64::from(bytes[0] as i8),
        DataType::U8 => f64::from(bytes[0]),
        DataType::I16 => f64::from(i16::from_be_bytes([bytes[0], bytes[1]])),
        DataType::I32 => f64::from(i32::from_be_bytes(bytes.try_into().expect("4 bytes"))),
        DataType::F32 => f64::from(f32::from_be_bytes(bytes.try_into().expect("4 bytes"))),
        DataType::F64 => f64::from_be_bytes(bytes.try_into().expect("8 bytes")),
    }
}

/// Fills `buf` from `file` at `offset`.
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut file = file;
    file.seek(SeekFrom::Start(offset))?;
    file.read_exact(buf)
}

/// The one two-dimensional numeric variable whose dimensions both have
/// coordinate variables.
fn elevation_variable(data_set: &DataSet) -> Result<&Variable, Problem> {
    let candidates: Vec<&Variable> = data_set
        .get_vars()
        .into_iter()
        .filter(|v| v.num_dims() == 2 && v.data_type() != DataType::U8 && !v.is_record_var())
        .filter(|v| v.dim_names().iter().all(|d| data_set.has_var(d)))
        .collect();
    match candidates.as_slice() {
        [one] => Ok(one),
        [] => Err(Problem::Header(
            "no two-dimensional variable with latitude and longitude coordinate variables".into(),
        )),
        many => Err(Problem::Header(format!(
            "several two-dimensional variables ({}), cannot tell which holds the heights",
            many.iter().map(|v| v.name()).collect::<Vec<_>>().join(", ")
        ))),
    }
}

/// The coordinate variable of dimension `name`, which must be one-dimensional
/// along that dimension.
fn coordinate<'a>(data_set: &'a DataSet, name: &str) -> Result<&'a Variable, Problem> {
    match data_set.get_var(name) {
        Some(var) if var.dim_names() == [name.to_string()] => Ok(var),
        _ => Err(Problem::Header(format!("coordinate variable {name} is not 1-D along {name}"))),
    }
}

/// The declared fill (or netCDF's default fill for the variable's type).
fn fill_value(variable: &Variable) -> NoData {
    let declared = ["_FillValue", "missing_value"].iter().find_map(|name| {
        let attr = variable.get_attr(name)?;
        let first = match attr.data_type() {
            DataType::I8 => attr.get_i8()?.first().map(|&v| f64::from(v)),
            DataType::I16 => attr.get_i16()?.first().map(|&v| f64::from(v)),
            DataType::I32 => attr.get_i32()?.first().map(|&v| f64::from(v)),
            DataType::F32 => attr.get_f32()?.first().map(|&v| f64::from(v)),
            DataType::F64 => attr.get_f64()?.first().copied(),
            DataType::U8 => None,
        };
        // An f32 fill is compared with the value as stored, widened to f64.
        first
    });
    NoData(declared.unwrap_or(match variable.data_type() {
        DataType::I8 => f64::from(netcdf3::NC_FILL_I8),
        DataType::I16 => f64::from(netcdf3::NC_FILL_I16),
        DataType::I32 => f64::from(netcdf3::NC_FILL_I32),
        DataType::F32 => f64::from(netcdf3::NC_FILL_F32),
        DataType::F64 | DataType::U8 => netcdf3::NC_FILL_F64,
    }))
}

/// Reads a numeric variable as `f64`.
fn read_f64(reader: &mut FileReader, name: &str, file_len: u64) -> Result<Vec<f64>, Problem> {
    let data = reader.read_var(name).map_err(|e| netcdf_problem(e, file_len))?;
    Ok(match data {
        DataVector::I8(v) => v.into_iter().map(f64::from).collect(),
        DataVector::U8(v) => v.into_iter().map(f64::from).collect(),
        DataVector::I16(v) => v.into_iter().map(f64::from).collect(),
        DataVector::I32(v) => v.into_iter().map(f64::from).collect(),
        DataVector::F32(v) => v.into_iter().map(f64::from).collect(),
        DataVector::F64(v) => v,
    })
}

/// The first post and the (signed) spacing of a coordinate variable, snapped
/// to a whole number of posts per degree where that is within tolerance.
fn lattice(values: &[f64], what: &str) -> Result<(f64, f64), Problem> {
    let irregular = |why: String| Err(Problem::Header(format!("{what} coordinates: {why}")));
    let (Some(&first), Some(&last)) = (values.first(), values.last()) else {
        return irregular("empty".into());
    };
    if values.len() < 2 || !values.iter().all(|v| v.is_finite()) || first == last {
        return irregular(format!("need two or more distinct finite values, {values:?}"));
    }
    // Least-squares line through the stored values: drift at either end
    // moves it far less than it moves the end points.
    let n = values.len() as f64;
    let mean_i = (n - 1.0) / 2.0;
    let mean_v = values.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, &v) in values.iter().enumerate() {
        sxy += (i as f64 - mean_i) * (v - mean_v);
        sxx += (i as f64 - mean_i).powi(2);
    }
    let mut step = sxy / sxx;
    let mut origin = mean_v - step * mean_i;
    if step == 0.0 || !step.is_finite() {
        return irregular("no spacing".into());
    }
    let per_degree = 1.0 / step.abs();
    if (per_degree - per_degree.round()).abs() <= SNAP_TOLERANCE * per_degree {
        let k = per_degree.round();
        step = step.signum() / k;
        origin = (origin * k).round() / k;
    }
    for (i, &v) in values.iter().enumerate() {
        let expected = origin + i as f64 * step;
        if (v - expected).abs() > COORDINATE_TOLERANCE * step.abs() {
            return irregular(format!(
                "value {i} is {v}, {expected} on a regular lattice (irregular grids are not supported)"
            ));
        }
    }
    Ok((origin, step))
}

/// The crate's error as a [`Problem`] (the crate's errors have no `Display`
/// beyond `Debug`); `file_len` is the file's length.
fn netcdf_problem(error: ReadError, file_len: u64) -> Problem {
    match error {
        ReadError::IOErrorKind(std::io::ErrorKind::UnexpectedEof) => Problem::Truncated {
            what: "a variable that runs past the end of the file".into(),
            needed: file_len + 1,
            actual: file_len,
        },
        ReadError::IOErrorKind(kind) => Problem::Io(kind.into()),
        other if other.header_is_incomplete() => {
            Problem::Header("the netCDF header is cut short".into())
        }
        other => Problem::NetCdf(format!("{other:?}")),
    }
}
