//! Where a GeoTIFF's pixels are: the raster-to-model mapping from
//! ModelPixelScale + ModelTiepoint or ModelTransformation, the coordinate
//! system from the GeoKey directory, and the PixelIsArea/PixelIsPoint
//! conversion to the crate's posts.
//!
//! Raster space puts pixel `(column, row)` at the square
//! `[column, column + 1] x [row, row + 1]`. With PixelIsArea (the GeoTIFF
//! default) a pixel's value belongs to the centre of that square, raster
//! point `(column + 0.5, row + 0.5)`; with PixelIsPoint it belongs to raster
//! point `(column, row)`. Either way the post is mapped through the model
//! transformation, so a PixelIsArea tile whose tie point is the corner
//! (40 E, 40 N) has its north-west post half a cell east and south of it.

use std::io::{Read, Seek};

use tiff::decoder::Decoder;
use tiff::tags::Tag;

use super::error::Problem;
use crate::geo::{Crs, GeoRef};

// GeoKey ids and values (GeoTIFF 1.0, section 6.3).
const GT_MODEL_TYPE: u16 = 1024;
const GT_RASTER_TYPE: u16 = 1025;
const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;
const PROJ_LINEAR_UNITS: u16 = 3076;
const VERTICAL_UNITS: u16 = 4099;
const MODEL_PROJECTED: u16 = 1;
const MODEL_GEOGRAPHIC: u16 = 2;
const RASTER_PIXEL_IS_POINT: u16 = 2;
const USER_DEFINED: u16 = 32767;
const LINEAR_METRE: u16 = 9001;
/// WGS 84, and NAD83 (within 2 m of WGS 84, far below any DEM's spacing).
const WGS84_LIKE: [u16; 2] = [4326, 4269];

/// How file rows map onto grid rows (row 0 south).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Rows of the file run north to south (the usual north-up raster).
    pub north_up: bool,
    /// Rows in the file.
    pub height: u32,
}

impl Placement {
    /// The grid row of file row `row`.
    pub fn grid_row(self, row: u32) -> u32 {
        debug_assert!(row < self.height);
        if self.north_up {
            self.height - 1 - row
        } else {
            row
        }
    }
}

/// Model coordinates of raster point `(column, row)`: `x0 + column * dx`,
/// `y0 + row * dy` (an axis-aligned affine map).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Affine {
    x0: f64,
    dx: f64,
    y0: f64,
    dy: f64,
}

/// The georeference of a raster `height` rows high and how its rows are stored.
pub fn georef<R: Read + Seek>(
    decoder: &mut Decoder<R>,
    height: u32,
) -> Result<(GeoRef, Placement), Problem> {
    let keys = GeoKeys::read(decoder)?;
    let affine = affine(decoder)?;
    let crs = keys.crs()?;
    // Raster offset of a pixel's post from its corner.
    let half = if keys.get(GT_RASTER_TYPE) == Some(RASTER_PIXEL_IS_POINT) { 0.0 } else { 0.5 };
    let north_up = affine.dy < 0.0;
    // The south-west post is the first column of the last stored row when
    // north-up, of the first stored row otherwise.
    let south_row = if north_up { f64::from(height - 1) } else { 0.0 };
    let origin = [affine.x0 + half * affine.dx, affine.y0 + (south_row + half) * affine.dy];
    let georef = GeoRef { crs, origin, spacing: [affine.dx, affine.dy.abs()] };
    Ok((georef, Placement { north_up, height }))
}

/// The raster-to-model map from ModelTransformation, or else from
/// ModelPixelScale and the single ModelTiepoint.
fn affine<R: Read + Seek>(decoder: &mut Decoder<R>) -> Result<Affine, Problem> {
    let affine = if let Some(matrix) = decoder.find_tag(Tag::ModelTransformationTag)? {
        from_matrix(&matrix.into_f64_vec()?)?
    } else {
        let scale =
            decoder.find_tag(Tag::ModelPixelScaleTag)?.map(|v| v.into_f64_vec()).transpose()?;
        let tie = decoder.find_tag(Tag::ModelTiepointTag)?.map(|v| v.into_f64_vec()).transpose()?;
        match (scale, tie) {
            (Some(scale), Some(tie)) => from_scale_and_tiepoint(&scale, &tie)?,
            _ => return Err(Problem::Header(
                "no georeference: need ModelPixelScale with ModelTiepoint, or ModelTransformation"
                    .into(),
            )),
        }
    };
    let Affine { x0, dx, y0, dy } = affine;
    if ![x0, dx, y0, dy].iter().all(|v| v.is_finite()) || dx <= 0.0 || dy == 0.0 {
        return Err(Problem::Header(format!(
            "unusable raster-to-model map: x = {x0} + {dx} * column, y = {y0} + {dy} * row \
             (need finite values, columns running east)"
        )));
    }
    Ok(affine)
}

fn from_matrix(m: &[f64]) -> Result<Affine, Problem> {
    if m.len() != 16 {
        return Err(Problem::Header(format!("ModelTransformation has {} values, not 16", m.len())));
    }
    if m[1] != 0.0 || m[4] != 0.0 {
        return Err(Problem::Unsupported("rotated or sheared ModelTransformation".into()));
    }
    Ok(Affine { x0: m[3], dx: m[0], y0: m[7], dy: m[5] })
}

fn from_scale_and_tiepoint(scale: &[f64], tie: &[f64]) -> Result<Affine, Problem> {
    if scale.len() < 2 {
        return Err(Problem::Header(format!("ModelPixelScale has {} values", scale.len())));
    }
    if tie.len() != 6 {
        return Err(Problem::Unsupported(format!(
            "{} ModelTiepoint values (only one tie point, 6 values, is supported)",
            tie.len()
        )));
    }
    // Tie point: raster (i, j) is model (x, y); the scale is positive with
    // y decreasing down the raster (a negative scale flips that).
    let (i, j, x, y) = (tie[0], tie[1], tie[3], tie[4]);
    let (sx, sy) = (scale[0], scale[1]);
    Ok(Affine { x0: x - i * sx, dx: sx, y0: y + j * sy, dy: -sy })
}

/// The short (inline) entries of the GeoKey directory.
struct GeoKeys(Vec<(u16, u16)>);

impl GeoKeys {
    fn read<R: Read + Seek>(decoder: &mut Decoder<R>) -> Result<GeoKeys, Problem> {
        let Some(directory) = decoder.find_tag(Tag::GeoKeyDirectoryTag)? else {
            return Err(Problem::Header(
                "no GeoKeyDirectory: the coordinate system is unknown".into(),
            ));
        };
        let directory = directory.into_u16_vec()?;
        let count = directory.get(3).copied().unwrap_or(0) as usize;
        let entries = directory.get(4..4 + 4 * count).ok_or_else(|| {
            Problem::Header(format!(
                "GeoKeyDirectory declares {count} keys but holds {} values",
                directory.len()
            ))
        })?;
        // Entry: key id, location (0 = value inline), count, value.
        let inline = entries.chunks_exact(4).filter(|e| e[1] == 0).map(|e| (e[0], e[3])).collect();
        Ok(GeoKeys(inline))
    }

    fn get(&self, key: u16) -> Option<u16> {
        self.0.iter().find(|(k, _)| *k == key).map(|&(_, v)| v)
    }

    fn crs(&self) -> Result<Crs, Problem> {
        if let Some(units) = self.get(VERTICAL_UNITS).filter(|&u| u != LINEAR_METRE) {
            return Err(Problem::Unsupported(format!(
                "vertical units {units} (heights must be metres, 9001)"
            )));
        }
        match self.get(GT_MODEL_TYPE) {
            Some(MODEL_GEOGRAPHIC) => match self.get(GEOGRAPHIC_TYPE) {
                None | Some(USER_DEFINED) => Ok(Crs::Geographic),
                Some(code) if WGS84_LIKE.contains(&code) => Ok(Crs::Geographic),
                Some(code) => {
                    Err(Problem::Unsupported(format!("geographic CRS EPSG:{code} (need WGS 84)")))
                }
            },
            Some(MODEL_PROJECTED) => {
                if let Some(units) = self.get(PROJ_LINEAR_UNITS).filter(|&u| u != LINEAR_METRE) {
                    return Err(Problem::Unsupported(format!(
                        "projected linear units {units} (need metres, 9001)"
                    )));
                }
                let epsg =
                    self.get(PROJECTED_CS_TYPE).filter(|&c| c != USER_DEFINED).map(u32::from);
                Ok(Crs::Projected { epsg })
            }
            Some(other) => Err(Problem::Unsupported(format!(
                "GTModelType {other} (need 1 projected or 2 geographic)"
            ))),
            None => Err(Problem::Header("GeoKeyDirectory has no GTModelType".into())),
        }
    }
}
