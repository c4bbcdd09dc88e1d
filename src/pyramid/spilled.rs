//! Elevation files into layers that live in spills ([`crate::spill`]), for
//! imports larger than memory: each file is decoded once (one at a time),
//! swath by swath ([`crate::dem::swath`]), into a spill, and written into
//! its layer's spill at its place on the mosaic's lattice, so neither a
//! file nor a layer is ever whole on the heap. The rules are those of
//! [`crate::dem::import_layers`] (grouping by spacing, the mosaic's first valid
//! height wins, a global grid's closing column), with one difference in
//! void filling: small voids are filled per file (per piece of at most
//! [`FILL_PIECE`] posts a side of a larger file), over its posts and
//! [`FILL_HALO`] posts around them, instead of over the whole mosaic.
//! For a layer of one file of at most [`FILL_PIECE`] a side that is the
//! same thing; otherwise it differs only for a void that reaches farther
//! than the halo across a seam.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::progress::Progress;
use crate::dem::mosaic::{plan, Footprint};
use crate::dem::{
    check_same_crs, same_spacing, swath, voids, GridView, ImportError, Problem, RawGrid,
};
use crate::geo::GeoRef;
use crate::spill::{ScratchDir, Spill};

/// Posts around a file that its void filling sees in a mosaic (and half
/// of it the gap between files it fills).
pub const FILL_HALO: u32 = 256;

/// One layer in a spill.
pub struct SpilledLayer {
    /// The layer's first file, named in errors.
    pub path: PathBuf,
    /// Posts per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `width * height` heights, row 0 southern; NaN: no data.
    pub heights: Spill<f32>,
    /// Where post (0, 0) is.
    pub georef: GeoRef,
    /// Void posts filled.
    pub voids_filled: u64,
}

impl SpilledLayer {
    /// The layer as a [`GridView`].
    pub fn view(&self) -> GridView<'_> {
        GridView {
            width: self.width,
            height: self.height,
            heights: self.heights.as_slice(),
            georef: self.georef,
            voids_filled: self.voids_filled,
        }
    }
}

/// Raises every layer's heights below sea level to it
/// ([`crate::dem::sea`]), a band of rows at a time, dropping the pages
/// behind each; returns the posts raised.
pub fn raise_to_sea_surface(layers: &mut [SpilledLayer]) -> u64 {
    let mut raised = 0;
    for layer in layers {
        let releaser = layer.heights.releaser();
        let band = layer.width as usize * PASTE_ROWS;
        for rows in layer.heights.as_mut_slice().chunks_mut(band) {
            raised += crate::dem::sea::raise_to_sea_surface(rows);
            releaser.release();
        }
    }
    raised
}

/// A decoded file waiting for its layer: its footprint and its heights.
struct Decoded {
    footprint: Footprint,
    heights: Spill<f32>,
}

/// Reads `paths` into layers in spills of `scratch`, in the order their
/// first file was given (see [`crate::dem::import_layers`]).
pub fn spill_layers(
    paths: &[PathBuf],
    scratch: &ScratchDir,
    progress: &dyn Progress,
) -> Result<Vec<SpilledLayer>, ImportError> {
    if paths.is_empty() {
        return Err(ImportError::new(Path::new(""), Problem::NoInput));
    }
    let mut groups: Vec<Vec<Decoded>> = Vec::new();
    progress.phase("reading files", paths.len() as u64);
    for path in paths {
        let opened = crate::dem::open::open(path)?;
        let footprint = opened.footprint().clone();
        if let Some(first) = groups.first().and_then(|g| g.first()) {
            let first = &first.footprint;
            check_same_crs(&first.path, &first.georef, path, &footprint.georef)?;
        }
        let [width, height] = footprint.size.map(|s| s as usize);
        let mut heights = scratch
            .spill("file", width * height, 0.0f32)
            .map_err(|e| ImportError::new(path, e.into()))?;
        // Windows of the file go straight to the spill, its pages dropped
        // behind each one: no file is ever whole in memory.
        let releaser = heights.releaser();
        opened.read_into(heights.as_mut_slice(), swath::SWATH_BYTES, &mut || releaser.release())?;
        heights.release();
        let decoded = Decoded { footprint, heights };
        let same_spacing =
            |g: &Vec<Decoded>| same_spacing(&g[0].footprint.georef, &decoded.footprint.georef);
        match groups.iter_mut().position(|g| same_spacing(g)) {
            Some(k) => groups[k].push(decoded),
            None => groups.push(vec![decoded]),
        }
        progress.advance(1);
    }
    groups.into_iter().map(|group| spill_layer(group, scratch, progress)).collect()
}

/// One group of files of one spacing into one layer.
fn spill_layer(
    group: Vec<Decoded>,
    scratch: &ScratchDir,
    progress: &dyn Progress,
) -> Result<SpilledLayer, ImportError> {
    let footprints: Vec<Footprint> = group.iter().map(|d| d.footprint.clone()).collect();
    let path = footprints[0].path.clone();
    let io = |e: std::io::Error| ImportError::new(&path, e.into());
    let plan = plan(&footprints, u64::MAX)?;
    progress.phase("mosaic", footprints.len() as u64);
    let (width, height) = (plan.width, plan.height);
    let heights = if group.len() == 1 {
        group.into_iter().next().expect("one file").heights
    } else {
        let posts = width as usize * height as usize;
        let mut heights = scratch.spill("layer", posts, f32::NAN).map_err(io)?;
        for (decoded, offset) in group.iter().zip(&plan.offsets) {
            paste(&mut heights, width, &decoded.footprint, decoded.heights.as_slice(), *offset);
            heights.release();
            decoded.heights.release();
            progress.advance(1);
        }
        heights
    };
    let mut layer =
        SpilledLayer { path, width, height, heights, georef: plan.georef, voids_filled: 0 };
    let rects: Vec<[u32; 4]> = footprints
        .iter()
        .zip(&plan.offsets)
        .flat_map(|(f, o)| pieces([o[0], o[1], o[0] + f.size[0], o[1] + f.size[1]]))
        .collect();
    fill_voids(&mut layer, &rects, progress)?;
    close_global(layer, scratch)
}

/// Largest side, in posts, of the piece of a file whose voids are filled
/// at once: a larger file (a world grid) is filled piece by piece, each
/// with [`FILL_HALO`] around it, like the files of a mosaic, so the fill's
/// scratch (about 14 bytes a post of the piece and its halo, some 90 MB)
/// does not grow with the file.
pub const FILL_PIECE: u32 = 2048;

/// `rect` (`[x0, y0, x1, y1)` in posts) cut into pieces of at most
/// [`FILL_PIECE`] a side.
fn pieces(rect: [u32; 4]) -> Vec<[u32; 4]> {
    let starts = |from: u32, to: u32| (from..to).step_by(FILL_PIECE as usize);
    let mut out = Vec::new();
    for y in starts(rect[1], rect[3]) {
        for x in starts(rect[0], rect[2]) {
            out.push([x, y, (x + FILL_PIECE).min(rect[2]), (y + FILL_PIECE).min(rect[3])]);
        }
    }
    out
}

/// Copies a file's heights into the layer at `offset`, keeping heights
/// already there (the first file given wins), [`PASTE_ROWS`] rows at a
/// time, dropping the layer's pages behind each band: a file's rows lie a
/// whole layer row apart, so pasting one file touched a page run per row
/// (230 MB of a 4 x 4 tile mosaic for one tile).
fn paste(layer: &mut Spill<f32>, width: u32, file: &Footprint, heights: &[f32], offset: [u32; 2]) {
    let (w, fw) = (width as usize, file.size[0] as usize);
    let releaser = layer.releaser();
    let start = offset[1] as usize * w;
    let layer_rows = layer.as_mut_slice()[start..].chunks_mut(w * PASTE_ROWS);
    for (band, source) in layer_rows.zip(heights.chunks(fw * PASTE_ROWS)) {
        band.par_chunks_mut(w).zip(source.par_chunks(fw)).for_each(|(row, source)| {
            let row = &mut row[offset[0] as usize..offset[0] as usize + fw];
            for (to, &from) in row.iter_mut().zip(source) {
                if to.is_nan() {
                    *to = from;
                }
            }
        });
        releaser.release();
    }
}

/// Rows of a file pasted between two releases of the layer's pages.
const PASTE_ROWS: usize = 256;

/// Fills the layer's small voids window by window (each file's rectangle
/// and [`FILL_HALO`] around it), counting them; refuses a layer without
/// data. Fills are applied once all windows are measured, so no window
/// sees another's fills, and a post two windows fill takes the first's.
fn fill_voids(
    layer: &mut SpilledLayer,
    rects: &[[u32; 4]],
    progress: &dyn Progress,
) -> Result<(), ImportError> {
    let (w, h) = (layer.width, layer.height);
    let (voids, any_data) = count_voids(layer);
    if !any_data {
        return Err(ImportError::new(&layer.path, Problem::AllVoids));
    }
    if voids == 0 {
        return Ok(());
    }
    progress.phase("void filling", rects.len() as u64);
    let one_file = rects.len() == 1;
    let mut fills: Vec<(usize, f32)> = Vec::new();
    for rect in rects {
        // A layer of one piece is filled whole, as before mosaicking.
        let grow =
            |v: u32, by: u32, max: u32| if one_file { v } else { v.saturating_add(by).min(max) };
        let shrink = |v: u32, by: u32| if one_file { v } else { v.saturating_sub(by) };
        let core = [shrink(rect[0], FILL_HALO / 2), shrink(rect[1], FILL_HALO / 2)];
        let core_end = [grow(rect[2], FILL_HALO / 2, w), grow(rect[3], FILL_HALO / 2, h)];
        let window = [shrink(rect[0], FILL_HALO), shrink(rect[1], FILL_HALO)];
        let window_end = [grow(rect[2], FILL_HALO, w), grow(rect[3], FILL_HALO, h)];
        let raw = window_grid(layer, window, window_end);
        let (ww, wh) = (raw.width as usize, raw.height as usize);
        let before: Vec<bool> = raw.heights.iter().map(|v| v.is_nan()).collect();
        layer.heights.release();
        let Ok(filled) = voids::fill_small(raw) else {
            progress.advance(1);
            continue; // a window of voids only: nothing to fill from
        };
        for q in 0..wh {
            for p in 0..ww {
                let (x, y) = (window[0] as usize + p, window[1] as usize + q);
                let inside = (core[0] as usize..core_end[0] as usize).contains(&x)
                    && (core[1] as usize..core_end[1] as usize).contains(&y);
                let value = filled.heights[q * ww + p];
                if inside && before[q * ww + p] && !value.is_nan() {
                    fills.push((y * w as usize + x, value));
                }
            }
        }
        progress.advance(1);
    }
    fills.sort_by_key(|&(index, _)| index);
    fills.dedup_by_key(|&mut (index, _)| index);
    let heights = layer.heights.as_mut_slice();
    for &(index, value) in &fills {
        heights[index] = value;
    }
    layer.heights.release();
    layer.voids_filled = fills.len() as u64;
    Ok(())
}

/// The layer's posts of no data, and whether it has any data, read band
/// by band (each band's pages released after it).
fn count_voids(layer: &SpilledLayer) -> (u64, bool) {
    let (mut voids, mut any_data) = (0u64, false);
    for band in layer.heights.as_slice().chunks(BAND_POSTS) {
        voids += band.par_iter().filter(|v| v.is_nan()).count() as u64;
        any_data = any_data || band.par_iter().any(|v| !v.is_nan());
        layer.heights.release();
    }
    (voids, any_data)
}

/// Posts between two releases while a layer is scanned.
const BAND_POSTS: usize = 8 << 20;

/// A copy of the layer's posts `[start, end)` as a grid with its voids.
fn window_grid(layer: &SpilledLayer, start: [u32; 2], end: [u32; 2]) -> RawGrid {
    let (ww, w) = ((end[0] - start[0]) as usize, layer.width as usize);
    let mut heights = Vec::with_capacity(ww * (end[1] - start[1]) as usize);
    let all = layer.heights.as_slice();
    for y in start[1] as usize..end[1] as usize {
        heights.extend_from_slice(&all[y * w + start[0] as usize..][..ww]);
    }
    RawGrid {
        path: layer.path.clone(),
        width: ww as u32,
        height: end[1] - start[1],
        heights,
        georef: layer.georef,
    }
}

/// The closing column of a global grid (see [`crate::dem::close_global`]),
/// written into a new spill one post wider.
fn close_global(layer: SpilledLayer, scratch: &ScratchDir) -> Result<SpilledLayer, ImportError> {
    if !layer.georef.lacks_closing_column(layer.width) {
        return Ok(layer);
    }
    let (w, h) = (layer.width as usize, layer.height as usize);
    let io = |e: std::io::Error| ImportError::new(&layer.path, e.into());
    let mut wider = scratch.spill("closed", (w + 1) * h, 0.0f32).map_err(io)?;
    let rows_per_band = (BAND_POSTS / w).max(1);
    for first in (0..h).step_by(rows_per_band) {
        let rows = rows_per_band.min(h - first);
        let from = &layer.heights.as_slice()[first * w..(first + rows) * w];
        let to = &mut wider.as_mut_slice()[first * (w + 1)..(first + rows) * (w + 1)];
        to.par_chunks_mut(w + 1).zip(from.par_chunks(w)).for_each(|(to, from)| {
            to[..w].copy_from_slice(from);
            to[w] = from[0];
        });
        layer.heights.release();
        wider.release();
    }
    wider.release();
    Ok(SpilledLayer { width: layer.width + 1, heights: wider, ..layer })
}
