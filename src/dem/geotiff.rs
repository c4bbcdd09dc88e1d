//! GeoTIFF elevation rasters, decoded with the `tiff` crate: one sample per
//! pixel of type int16 (the SRTM/DTED norm), uint16, int32, float32 or
//! float64; strips or tiles; uncompressed, DEFLATE or LZW, with or without
//! the horizontal or floating-point predictor.
//!
//! Georeference (see [`super::geotiff_georef`]) comes from ModelPixelScale plus one
//! ModelTiepoint, or from an axis-aligned ModelTransformation; the
//! coordinate system and PixelIsArea/PixelIsPoint from the GeoKey directory.
//! The GDAL nodata tag (42113, ASCII) marks voids, compared in the samples'
//! own type; any other NaN or infinity is an error.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

use super::error::{ImportError, Problem};
use super::geotiff_georef::{georef, Placement};
use super::mosaic::Footprint;
use super::raw::{
    check_dimensions, classify, file_len, non_finite, read_prefix, NoData, MAX_SAMPLES,
};
use super::swath::OpenedFile;

/// No DEFLATE or LZW stream expands by more than this factor (DEFLATE's
/// limit is 1032, LZW's about 2700); compressed chunks declaring more data
/// than this allows are corrupt, and refused before decoding.
const MAX_COMPRESSION_RATIO: u64 = 4096;

/// TIFF compression code for "none".
const UNCOMPRESSED: u16 = 1;

/// An opened GeoTIFF: its tags read and its chunks checked against the
/// file's length, no chunk decoded.
pub struct GeoTiffFile {
    footprint: Footprint,
    decoder: Decoder<BufReader<File>>,
    placement: Placement,
    nodata: Option<NoData>,
    chunks: u32,
}

/// Opens a GeoTIFF elevation raster.
pub fn open(path: &Path) -> Result<GeoTiffFile, ImportError> {
    let fail = |problem| ImportError::new(path, problem);
    check_magic(path)?;
    let file = File::open(path).map_err(|e| fail(e.into()))?;
    let mut decoder =
        Decoder::new(BufReader::new(file)).map_err(|e| fail(e.into()))?.with_limits(limits());
    let (width, height) = decoder.dimensions().map_err(|e| fail(e.into()))?;
    let (width, height) = check_dimensions(path, width.into(), height.into())?;
    let bytes_per_sample = sample_bytes(&mut decoder).map_err(fail)?;
    check_chunks(path, &mut decoder, u64::from(width) * u64::from(height) * bytes_per_sample)?;
    let (georef, placement) = georef(&mut decoder, height).map_err(fail)?;
    let nodata = gdal_nodata(&mut decoder).map_err(fail)?;
    let chunks = chunk_count(&mut decoder).map_err(fail)?;
    let footprint = Footprint { path: path.to_path_buf(), georef, size: [width, height] };
    Ok(GeoTiffFile { footprint, decoder, placement, nodata, chunks })
}

impl OpenedFile for GeoTiffFile {
    fn footprint(&self) -> &Footprint {
        &self.footprint
    }

    /// Swaths of whole strips or tiles, as many as `swath_bytes` of
    /// decoded samples hold (at least one).
    fn read_into(
        mut self: Box<Self>,
        out: &mut [f32],
        swath_bytes: usize,
        swath_done: &mut dyn FnMut(),
    ) -> Result<(), ImportError> {
        let path = &self.footprint.path;
        let [width, height] = self.footprint.size;
        let mut target = Target { path, width, height, heights: out };
        let mut decoded_since = 0usize;
        for chunk in 0..self.chunks {
            let decoded = self.decoder.read_chunk(chunk).map_err(|e| tiff_error(path, e))?;
            let area = chunk_area(&self.decoder, chunk, width);
            decoded_since += area.width as usize * area.height as usize * 8;
            store_chunk(&mut target, self.placement, area, decoded, self.nodata)?;
            if decoded_since >= swath_bytes {
                swath_done();
                decoded_since = 0;
            }
        }
        swath_done();
        Ok(())
    }
}

fn tiff_error(path: &Path, error: tiff::TiffError) -> ImportError {
    ImportError::new(path, error.into())
}

/// Where decoded chunks go: the grid's heights, row 0 southern.
struct Target<'a> {
    path: &'a Path,
    width: u32,
    height: u32,
    heights: &'a mut [f32],
}

/// Refuses anything that does not start like a TIFF or BigTIFF file.
fn check_magic(path: &Path) -> Result<(), ImportError> {
    let start = read_prefix(path, 4)?;
    if !super::format::TIFF_MAGIC.contains(&start.as_slice()) {
        let found = String::from_utf8_lossy(&start).into_owned();
        let problem = Problem::BadMagic { format: "TIFF", expected: "II*\\0 or MM\\0*", found };
        return Err(ImportError::new(path, problem));
    }
    Ok(())
}

/// Decoder limits large enough for any grid [`check_dimensions`] accepts.
fn limits() -> Limits {
    let mut limits = Limits::default();
    limits.decoding_buffer_size = (MAX_SAMPLES * 8) as usize;
    limits.intermediate_buffer_size = (MAX_SAMPLES * 8) as usize;
    limits
}

/// Bytes per sample of a single-channel raster; anything else is unsupported.
fn sample_bytes(decoder: &mut Decoder<BufReader<File>>) -> Result<u64, Problem> {
    match decoder.colortype()? {
        ColorType::Gray(bits @ (8 | 16 | 32 | 64)) => Ok(u64::from(bits / 8)),
        other => {
            Err(Problem::Unsupported(format!("{other:?} pixels (need one 8/16/32/64-bit sample)")))
        }
    }
}

fn chunk_count(decoder: &mut Decoder<BufReader<File>>) -> Result<u32, Problem> {
    Ok(match decoder.get_chunk_type() {
        ChunkType::Strip => decoder.strip_count()?,
        ChunkType::Tile => decoder.tile_count()?,
    })
}

/// Checks, before any chunk is decoded, that every chunk lies inside the
/// file and that together they can hold `image_bytes` of samples (exactly
/// when uncompressed, within [`MAX_COMPRESSION_RATIO`] when compressed).
fn check_chunks(
    path: &Path,
    decoder: &mut Decoder<BufReader<File>>,
    image_bytes: u64,
) -> Result<(), ImportError> {
    let fail = |problem| ImportError::new(path, problem);
    let (kind, offsets_tag, counts_tag) = match decoder.get_chunk_type() {
        ChunkType::Strip => ("strip", Tag::StripOffsets, Tag::StripByteCounts),
        ChunkType::Tile => ("tile", Tag::TileOffsets, Tag::TileByteCounts),
    };
    let offsets = decoder.get_tag_u64_vec(offsets_tag).map_err(|e| fail(e.into()))?;
    let counts = decoder.get_tag_u64_vec(counts_tag).map_err(|e| fail(e.into()))?;
    let compression =
        decoder.find_tag_unsigned::<u16>(Tag::Compression).map_err(|e| fail(e.into()))?;
    let actual = file_len(path)?;
    for (index, (&offset, &count)) in offsets.iter().zip(&counts).enumerate() {
        let end = offset.saturating_add(count);
        if end > actual {
            let what = format!("{kind} {index} (bytes {offset}..{end})");
            return Err(fail(Problem::Truncated { what, needed: end, actual }));
        }
    }
    // The decoder has checked that there are as many counts as offsets.
    let stored: u64 = counts.iter().sum();
    let ratio =
        if compression.unwrap_or(UNCOMPRESSED) == UNCOMPRESSED { 1 } else { MAX_COMPRESSION_RATIO };
    if stored.saturating_mul(ratio) < image_bytes {
        return Err(fail(Problem::SizeMismatch {
            expected: image_bytes.div_ceil(ratio),
            actual: stored,
        }));
    }
    Ok(())
}

/// The GDAL nodata value, if the file declares one.
fn gdal_nodata(decoder: &mut Decoder<BufReader<File>>) -> Result<Option<NoData>, Problem> {
    let Some(value) = decoder.find_tag(Tag::GdalNodata)? else {
        return Ok(None);
    };
    let text = value.into_string()?;
    let text = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    let number = text
        .parse()
        .map_err(|_| Problem::Header(format!("GDAL nodata {text:?} is not a number")))?;
    Ok(Some(NoData(number)))
}

/// The pixels a chunk covers in file coordinates (row 0 = first row stored).
#[derive(Clone, Copy, Debug)]
struct ChunkArea {
    first_row: u32,
    first_column: u32,
    width: u32,
    height: u32,
}

fn chunk_area(decoder: &Decoder<BufReader<File>>, chunk: u32, image_width: u32) -> ChunkArea {
    let (chunk_width, chunk_height) = decoder.chunk_dimensions();
    let (width, height) = decoder.chunk_data_dimensions(chunk);
    let across = image_width.div_ceil(chunk_width);
    ChunkArea {
        first_row: (chunk / across) * chunk_height,
        first_column: (chunk % across) * chunk_width,
        width,
        height,
    }
}

/// Converts a decoded chunk to heights and stores it in the grid.
fn store_chunk(
    grid: &mut Target,
    placement: Placement,
    area: ChunkArea,
    decoded: DecodingResult,
    nodata: Option<NoData>,
) -> Result<(), ImportError> {
    // Nodata is compared in the samples' own type: a float32 raster declaring
    // "-3.40282e+38" means the f32 nearest to it.
    let nodata = match decoded {
        DecodingResult::F32(_) => nodata.map(|nd| NoData(f64::from(nd.0 as f32))),
        _ => nodata,
    };
    let values = as_f64(decoded).map_err(|p| ImportError::new(grid.path, p))?;
    let expected = area.width as usize * area.height as usize;
    debug_assert!(values.len() >= expected, "the decoder returns the unpadded chunk");
    for (k, &value) in values.iter().take(expected).enumerate() {
        let row = area.first_row + (k / area.width as usize) as u32;
        let column = area.first_column + (k % area.width as usize) as u32;
        let height = classify(value, nodata)
            .ok_or_else(|| non_finite(grid.path, row.into(), column.into(), value))?;
        debug_assert!(column < grid.width && row < grid.height);
        let index = placement.grid_row(row) as usize * grid.width as usize + column as usize;
        grid.heights[index] = height;
    }
    Ok(())
}

/// Every supported sample type, exactly, as `f64`.
fn as_f64(decoded: DecodingResult) -> Result<Vec<f64>, Problem> {
    Ok(match decoded {
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
        DecodingResult::U64(_) | DecodingResult::I64(_) | DecodingResult::F16(_) => {
            return Err(Problem::Unsupported("64-bit integer or 16-bit float samples".into()))
        }
    })
}
