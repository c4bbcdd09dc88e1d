//! Camera paths as CSV text: the `--path FILE` format and its writer.
//!
//! ```text
//! # comment lines and blank lines are ignored
//! t,x,y,alt,heading,pitch,roll
//! 0,1200,800,2500,45,-3,0
//! 10,2400,2000,2300,50,-3,5
//! ```
//!
//! The header names the columns in any order (any case, spaces around names
//! and cells allowed): `t` seconds, `x`/`y` metres east/north of the dataset's
//! south-west sample, `alt` metres above mean sea level, `heading` degrees
//! clockwise from true north, `pitch` degrees nose up, `roll` degrees right
//! wing down. A geographic dataset also accepts `lat`/`lon` degrees in place of
//! `x`/`y`, mapped by [`super::geographic`]. Every problem is reported with the
//! file, the row (and its line in the file) and the column.
//!
//! **Longitudes** may be given as the data store them (0 to 360 for a
//! grid stored so) or in [-180, 180]: each is read in the turn that holds
//! the grid, and over a grid that wraps (its columns span 360 degrees) in
//! the turn nearest the previous row's, so a path crossing the grid's seam
//! (Greenwich for a 0-360 grid, the antimeridian for a -180-180 one) is
//! followed across it, not back over the whole earth. What was done is
//! said: [`FlightPath::longitude_note`].

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};

use super::columns::{Column, ValueProblem};
use super::path::{FlightPath, Waypoint};
use super::pose::Pose;
use crate::earth::GridPlacement;
use crate::geo::{Crs, GeoRef};

/// Larger files are refused before reading: a path of 1 Hz rows this size
/// would already run for days.
pub const MAX_FILE_BYTES: u64 = 16 << 20;

/// The header [`FlightPath::to_csv`] writes.
pub const XY_HEADER: &str = "t,x,y,alt,heading,pitch,roll";

/// A camera path file that cannot be used: the file and the problem.
#[derive(Debug, thiserror::Error)]
#[error("camera path {}: {problem}", path.display())]
pub struct PathError {
    /// The camera path file as given.
    pub path: PathBuf,
    /// What is wrong with it.
    pub problem: PathProblem,
}

/// What is wrong with a camera path file.
#[derive(Debug, thiserror::Error)]
pub enum PathProblem {
    /// The file could not be read.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// The file is larger than [`MAX_FILE_BYTES`].
    #[error("{bytes} bytes is too large for a camera path (at most {MAX_FILE_BYTES})")]
    TooLarge {
        /// Size of the file, bytes.
        bytes: u64,
    },
    /// The file holds only blank lines and `#` comments.
    #[error(
        "no header: expected `t,x,y,alt,heading,pitch,roll` or `t,lat,lon,alt,heading,pitch,roll`"
    )]
    NoHeader,
    /// A header name is none of the [`Column`] names.
    #[error("header (line {line}), column {position} `{name}`: unknown column; the columns are t, x, y (or lat, lon), alt, heading, pitch, roll")]
    UnknownColumn {
        /// Line of the header in the file, from 1.
        line: usize,
        /// Position of the name in the header, from 1.
        position: usize,
        /// The name as written.
        name: String,
    },
    /// The header names a column twice.
    #[error("header (line {line}), column `{}`: named twice", column.name())]
    DuplicateColumn {
        /// Line of the header in the file, from 1.
        line: usize,
        /// The column named twice.
        column: Column,
    },
    /// The header lacks a column every path needs.
    #[error("header (line {line}), column `{}`: missing", column.name())]
    MissingColumn {
        /// Line of the header in the file, from 1.
        line: usize,
        /// The first column missing.
        column: Column,
    },
    /// The header gives the position as both `x,y` and `lat,lon`.
    #[error(
        "header (line {line}), columns `x,y` and `lat,lon`: give the position one way, not both"
    )]
    MixedPosition {
        /// Line of the header in the file, from 1.
        line: usize,
    },
    /// The header gives `lat,lon` but the dataset is not in geographic coordinates.
    #[error("header (line {line}), columns `lat,lon`: the dataset is not in longitude/latitude ({}), so positions must be `x,y` metres east and north of its south-west corner", describe_crs(crs))]
    LatLonNeedsGeographic {
        /// Line of the header in the file, from 1.
        line: usize,
        /// The dataset's coordinate system.
        crs: Crs,
    },
    /// A row has more or fewer cells than the header has columns.
    #[error("row {row} (line {line}), column {column}: the row has {found} cells, the header {expected}")]
    CellCount {
        /// Row, from 1 for the first row after the header.
        row: usize,
        /// Line of the row in the file, from 1.
        line: usize,
        /// Cells in the row.
        found: usize,
        /// Columns in the header.
        expected: usize,
        /// The first column without a cell, or the first cell beyond the header, as text.
        column: String,
    },
    /// A cell cannot be used as its column's value.
    #[error("row {row} (line {line}), column `{}`: {problem}", column.name())]
    Value {
        /// Row, from 1 for the first row after the header.
        row: usize,
        /// Line of the row in the file, from 1.
        line: usize,
        /// The cell's column.
        column: Column,
        /// What is wrong with the value.
        problem: ValueProblem,
    },
    /// A row's time is not later than the previous row's.
    #[error("row {row} (line {line}), column `t`: {t} s does not come after the previous row's {previous} s; times must strictly increase")]
    TimeNotIncreasing {
        /// Row, from 1 for the first row after the header.
        row: usize,
        /// Line of the row in the file, from 1.
        line: usize,
        /// This row's time, seconds.
        t: f64,
        /// The previous row's time, seconds.
        previous: f64,
    },
    /// The header is followed by no rows.
    #[error("no rows after the header (line {line}): a camera path needs at least one")]
    NoRows {
        /// Line of the header in the file, from 1.
        line: usize,
    },
}

/// The chart point of `lat`, `lon` (degrees): in the grid's turn, or over
/// a grid that wraps in the turn nearest `previous_x` (the previous row's
/// chart `x`); counted in `longitudes` when moved by a turn.
fn chart_point(
    placement: &GridPlacement,
    lat: f64,
    lon: f64,
    previous_x: Option<f64>,
    longitudes: &mut Longitudes,
) -> DVec2 {
    let [mut x, y] = placement.chart_of_geodetic(lat.to_radians(), lon.to_radians());
    let [sx, _] = placement.chart_spacing_m();
    let mut turns = 0.0;
    if let (Some(period), Some(previous)) = (placement.period_posts(), previous_x) {
        let period_m = period * sx;
        turns = ((previous - x) / period_m).round();
        x += turns * period_m;
    }
    if turns != 0.0 {
        longitudes.across_seam += 1;
    }
    // The longitude the chart point stands for, against the one written.
    let used = longitudes.west + x / sx * placement_step(placement);
    if ((used - lon) / 360.0).round() != 0.0 {
        longitudes.moved += 1;
    }
    DVec2::new(x, y)
}

/// Degrees of longitude between a geographic grid's columns.
fn placement_step(placement: &GridPlacement) -> f64 {
    let (_, lon0) = placement.geodetic_of_post(0.0, 0.0);
    let (_, lon1) = placement.geodetic_of_post(1.0, 0.0);
    (lon1 - lon0).to_degrees()
}

fn describe_crs(crs: &Crs) -> String {
    match crs {
        Crs::Geographic => "longitude/latitude".into(),
        Crs::Projected { epsg: Some(code) } => format!("projected, EPSG:{code}"),
        Crs::Projected { epsg: None } => "projected".into(),
        Crs::Local => "a local grid in metres".into(),
    }
}

/// The columns of a file, in file order, and how positions are given.
struct Header {
    line: usize,
    columns: Vec<Column>,
    /// Positions come as `lat,lon`, mapped onto the chart by this.
    geographic: Option<GridPlacement>,
}

/// What became of the rows' longitudes.
#[derive(Default)]
struct Longitudes {
    /// Rows read in another turn than written (normalised to the grid's).
    moved: usize,
    /// Rows followed across the seam of a grid that wraps.
    across_seam: usize,
    /// The grid's turn, degrees: its west edge, and whether it wraps.
    west: f64,
    wraps: bool,
}

impl Longitudes {
    fn note(&self, rows: usize) -> Option<String> {
        let turn = if self.wraps {
            format!("the grid's columns span 360 degrees from {} E, so longitudes wrap", self.west)
        } else {
            format!("the grid starts at {} E", self.west)
        };
        match (self.moved, self.across_seam) {
            (0, 0) => None,
            (moved, 0) => Some(format!(
                "longitudes: {moved} of {rows} rows normalised by 360 degrees into the grid's turn ({turn})"
            )),
            (moved, seam) => Some(format!(
                "longitudes: {moved} of {rows} rows normalised by 360 degrees, and the path followed across the grid's seam {seam} times ({turn})"
            )),
        }
    }
}

impl FlightPath {
    /// Reads and parses the camera path file at `path` for a dataset with
    /// `georef` and `extent_samples` samples (east, north).
    pub fn read(
        path: &Path,
        georef: &GeoRef,
        extent_samples: [u32; 2],
    ) -> Result<FlightPath, PathError> {
        let fail = |problem| PathError { path: path.to_path_buf(), problem };
        let bytes = std::fs::metadata(path).map_err(|e| fail(e.into()))?.len();
        if bytes > MAX_FILE_BYTES {
            return Err(fail(PathProblem::TooLarge { bytes }));
        }
        let text = std::fs::read_to_string(path).map_err(|e| fail(e.into()))?;
        Self::parse_csv(path, &text, georef, extent_samples)
    }

    /// Parses camera path CSV `text` (from the file `path`, named in errors).
    pub fn parse_csv(
        path: &Path,
        text: &str,
        georef: &GeoRef,
        extent_samples: [u32; 2],
    ) -> Result<FlightPath, PathError> {
        parse_lines(text, georef, extent_samples)
            .map_err(|problem| PathError { path: path.to_path_buf(), problem })
    }

    /// The path as CSV with the `t,x,y,...` header. Numbers are written in
    /// Rust's shortest round-trip form, so parsing the text gives this path back.
    pub fn to_csv(&self) -> String {
        let mut text = format!("{XY_HEADER}\n");
        for Waypoint { t, pose } in self.waypoints() {
            let DVec3 { x, y, z } = pose.position;
            let (heading, pitch, roll) = (pose.heading_deg, pose.pitch_deg, pose.roll_deg);
            text.push_str(&format!("{t},{x},{y},{z},{heading},{pitch},{roll}\n"));
        }
        text
    }
}

fn parse_lines(
    text: &str,
    georef: &GeoRef,
    extent_samples: [u32; 2],
) -> Result<FlightPath, PathProblem> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(index, line)| (index + 1, line))
        .filter(|(_, line)| is_content(line));
    let (header_line, header_text) = lines.next().ok_or(PathProblem::NoHeader)?;
    let header = parse_header(header_line, header_text, georef, extent_samples)?;
    let mut waypoints: Vec<Waypoint> = Vec::new();
    let mut longitudes = Longitudes {
        west: georef.origin[0],
        wraps: header.geographic.is_some_and(|p| p.period_posts().is_some()),
        ..Longitudes::default()
    };
    for (row_index, (line, row_text)) in lines.enumerate() {
        let row = row_index + 1;
        let previous_x = waypoints.last().map(|w| w.pose.position.x);
        let waypoint = parse_row(&header, row, line, row_text, previous_x, &mut longitudes)?;
        if let Some(previous) = waypoints.last() {
            if waypoint.t <= previous.t {
                return Err(PathProblem::TimeNotIncreasing {
                    row,
                    line,
                    t: waypoint.t,
                    previous: previous.t,
                });
            }
        }
        waypoints.push(waypoint);
    }
    if waypoints.is_empty() {
        return Err(PathProblem::NoRows { line: header.line });
    }
    let rows = waypoints.len();
    Ok(FlightPath::from_checked(waypoints).with_longitude_note(longitudes.note(rows)))
}

/// Blank lines and `#` comments carry nothing.
fn is_content(line: &str) -> bool {
    let line = line.trim();
    !line.is_empty() && !line.starts_with('#')
}

fn parse_header(
    line: usize,
    text: &str,
    georef: &GeoRef,
    extent_samples: [u32; 2],
) -> Result<Header, PathProblem> {
    let mut columns = Vec::new();
    for (index, name) in text.split(',').map(str::trim).enumerate() {
        let column = Column::from_name(name).ok_or_else(|| PathProblem::UnknownColumn {
            line,
            position: index + 1,
            name: name.to_string(),
        })?;
        if columns.contains(&column) {
            return Err(PathProblem::DuplicateColumn { line, column });
        }
        columns.push(column);
    }
    let has = |column| columns.contains(&column);
    let geographic = has(Column::Lat) || has(Column::Lon);
    if geographic && (has(Column::X) || has(Column::Y)) {
        return Err(PathProblem::MixedPosition { line });
    }
    let position = if geographic { [Column::Lat, Column::Lon] } else { [Column::X, Column::Y] };
    let required = [
        Column::Time,
        position[0],
        position[1],
        Column::Altitude,
        Column::Heading,
        Column::Pitch,
        Column::Roll,
    ];
    if let Some(&column) = required.iter().find(|&&column| !has(column)) {
        return Err(PathProblem::MissingColumn { line, column });
    }
    let geographic = match (geographic, georef.crs) {
        (false, _) => None,
        (true, Crs::Geographic) => {
            Some(GridPlacement::new(georef, extent_samples, georef.spacing_m(extent_samples)))
        }
        (true, crs) => return Err(PathProblem::LatLonNeedsGeographic { line, crs }),
    };
    Ok(Header { line, columns, geographic })
}

fn parse_row(
    header: &Header,
    row: usize,
    line: usize,
    text: &str,
    previous_x: Option<f64>,
    longitudes: &mut Longitudes,
) -> Result<Waypoint, PathProblem> {
    let cells: Vec<&str> = text.split(',').collect();
    let expected = header.columns.len();
    if cells.len() != expected {
        let column = match header.columns.get(cells.len()) {
            Some(missing) => format!("`{}` (missing)", missing.name()),
            None => format!("{} (beyond the header)", expected + 1),
        };
        return Err(PathProblem::CellCount { row, line, found: cells.len(), expected, column });
    }
    let mut values = [0.0; Column::ALL.len()];
    for (&column, cell) in header.columns.iter().zip(cells) {
        values[column as usize] = column.parse(cell).map_err(|problem| PathProblem::Value {
            row,
            line,
            column,
            problem,
        })?;
    }
    let value = |column: Column| values[column as usize];
    let horizontal = match &header.geographic {
        Some(placement) => {
            chart_point(placement, value(Column::Lat), value(Column::Lon), previous_x, longitudes)
        }
        None => DVec2::new(value(Column::X), value(Column::Y)),
    };
    let pose = Pose {
        position: horizontal.extend(value(Column::Altitude)),
        heading_deg: value(Column::Heading),
        pitch_deg: value(Column::Pitch),
        roll_deg: value(Column::Roll),
    };
    Ok(Waypoint { t: value(Column::Time), pose })
}
