//! Building the pyramid file streaming, with bounded memory: each level is
//! cut band by band (rows of nodes) from the layers, which may live in
//! memory-mapped spills, and its records are appended to the file as the
//! bands complete; a node's delta reads the finer levels back from the
//! records already written. Only the node tables (a few bytes per node)
//! grow with the input. The header and node table are written last, into
//! the space reserved for them at the start, and the file is renamed into
//! place ([`replace_file`]). The bytes are those of
//! [`build_layers`](super::build_layers) and [`write_atomic`](super::write_atomic).

use std::borrow::Cow;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::Mutex;

use rayon::prelude::*;

use super::build::weighted;
use super::build::{
    candidates, check_layer, check_options, cut_node, finest_window, grid_stats, place_layers,
    summarise_level, BuildOptions,
};
use super::delta::{node_delta, FinerNodes};
use super::error::{PyramidError, StreamError};
use super::format::{
    encode_header, encode_record, record_len, GridStats, LevelSummary, NodeSummary, PyramidInfo,
};
use super::layers::{blend_weights_into, Composite};
use super::progress::Progress;
use super::write::replace_file;
use crate::dem::GridView;
use crate::geo::GeoRef;
use crate::node::{NodeError, NodeId, NodeLayout};
use crate::spill::{Releaser, ScratchDir, Spill};

/// How to build and how much memory the bands may take.
#[derive(Clone, Copy, Debug)]
pub struct StreamOptions {
    /// Node size and border.
    pub build: BuildOptions,
    /// Bytes the bands of nodes in flight may take (a quarter of
    /// `--memory-mb`: the rest is for decoding files and the pages of the
    /// layers a band touches).
    pub band_bytes: u64,
}

/// One level's present nodes: where each is stored and its summary.
pub(crate) struct LevelIndex {
    /// Per node of the level, its slot among the present nodes.
    pub slots: Vec<Option<u32>>,
    /// Summaries of the present nodes in slot order.
    pub summaries: Vec<NodeSummary>,
    /// Per slot, whether any centre post has data.
    pub has_data: Vec<bool>,
    /// Present nodes of all finer levels: the record number of slot 0.
    pub first_record: u64,
}

/// Builds the pyramid of `layers` into the file at `path`, atomically;
/// the blend weights of layers over coarser ones go to spills in
/// `scratch`; `release` is called after every band to drop the layers'
/// touched pages (see [`crate::spill`]).
pub fn build_streaming(
    layers: &[GridView],
    scratch: &ScratchDir,
    options: &StreamOptions,
    path: &Path,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> Result<PyramidInfo, StreamError> {
    with_prepared(layers, scratch, options, release, progress, |prepared, release| {
        write_pyramid(prepared, &LevelPlan::WHOLE, path, release, progress)
    })
}

/// The layers placed on the level-0 lattice, ready to be cut: where every
/// form of the streaming build (whole, a shard's part, the merge) starts.
pub(crate) struct Prepared<'a> {
    /// The layers as given.
    pub layers: &'a [GridView<'a>],
    /// The node layout over all of them.
    pub layout: NodeLayout,
    /// Where level-0 post (0, 0) is.
    pub georef: GeoRef,
    /// The layers on the lattice, with their blend weights.
    pub composite: Composite<'a>,
    /// Rows of nodes cut between two writes.
    pub rows_per_band: u32,
    /// Bytes the bands may take.
    pub band_bytes: u64,
}

/// Checks the layers and options, spills the blend weights, places the
/// layers and runs `body` on them; `body`'s `release` also drops the
/// weights' pages.
pub(crate) fn with_prepared<R>(
    layers: &[GridView],
    scratch: &ScratchDir,
    options: &StreamOptions,
    release: &dyn Fn(),
    progress: &dyn Progress,
    body: impl FnOnce(&Prepared, &dyn Fn()) -> Result<R, StreamError>,
) -> Result<R, StreamError> {
    check_options(&options.build)?;
    for (k, layer) in layers.iter().enumerate() {
        check_layer(k, *layer, &mut || release())?;
    }
    let weights = spill_weights(layers, scratch, release, progress)
        .map_err(|source| PyramidError::Io { path: scratch.path().to_path_buf(), source })?;
    let release = &|| {
        release();
        weights.iter().flatten().for_each(Spill::release);
    };
    let weight_slices: Vec<Option<&[f32]>> =
        weights.iter().map(|w| w.as_ref().map(Spill::as_slice)).collect();
    let (layout, georef, composite) = place_layers(layers, &weight_slices, &options.build)?;
    let record = record_len(&layout);
    let widest = (0..layout.levels).map(|l| layout.nodes_at(l)[0] as u64).max().unwrap_or(1);
    // A band holds its nodes' posts twice (cut and encoded) and reads a
    // node's worth of layer rows per node.
    let row_bytes = 3 * widest * record;
    if row_bytes > options.band_bytes {
        return Err(StreamError::Memory(format!(
            "one row of {widest} nodes needs {} MB; raise --memory-mb to at least {}",
            row_bytes.div_ceil(1 << 20),
            (4 * row_bytes).div_ceil(1 << 20)
        )));
    }
    let rows_per_band = (band_target(options.band_bytes) / row_bytes).max(1) as u32;
    let prepared = Prepared {
        layers,
        layout,
        georef,
        composite,
        rows_per_band,
        band_bytes: options.band_bytes,
    };
    body(&prepared, release)
}

/// Which nodes a streaming build writes, level by level.
pub(crate) struct LevelPlan<'a> {
    /// Levels below this are copied from shards' parts (`parts`).
    pub copied: u8,
    /// Where the copied levels' nodes come from.
    pub parts: Option<&'a dyn PartNodes>,
    /// Levels from this on are left empty (a shard's part stops at its
    /// split level).
    pub top: u8,
    /// Of the candidates, the nodes to cut (a shard's subtrees).
    pub keep: Option<&'a (dyn Fn(NodeId) -> bool + Sync)>,
    /// Whether the header's statistics cover the whole input (a part's
    /// count nothing but the heights of its own nodes).
    pub whole: bool,
}

impl LevelPlan<'_> {
    /// Every level cut from the layers.
    pub const WHOLE: LevelPlan<'static> =
        LevelPlan { copied: 0, parts: None, top: u8::MAX, keep: None, whole: true };
}

/// The nodes of finer levels that shards built, for a merge to copy.
pub(crate) trait PartNodes: Sync {
    /// Node `id`'s posts and summary from the part that built it, `None`
    /// when it is absent.
    fn node(&self, id: NodeId) -> Result<Option<(Vec<f32>, NodeSummary)>, NodeError>;
    /// Drops the parts' pages read so far (memory must not grow with the
    /// input).
    fn release_pages(&self);
}

/// Writes the pyramid `plan` names into `path`, atomically: records
/// first, then the header and node table.
pub(crate) fn write_pyramid(
    prepared: &Prepared,
    plan: &LevelPlan,
    path: &Path,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> Result<PyramidInfo, StreamError> {
    let layout = prepared.layout;
    let composite = &prepared.composite;
    let mut info = None;
    replace_file(
        path,
        |temporary| {
            let (levels, file) = write_levels(prepared, plan, temporary, release, progress)?;
            let summaries: Vec<_> = (0..layout.levels)
                .map(|l| {
                    let level = &levels[l as usize];
                    summarise_level(layout.nodes_at(l), &level.summaries, &level.has_data)
                })
                .collect();
            let stats = match plan.whole {
                true => grid_stats(&summaries, composite, &mut || release())?,
                false => part_stats(&summaries),
            };
            let built_info = PyramidInfo {
                layout,
                georef: prepared.georef,
                stats,
                layers: prepared.layers.len() as u32,
                finest: finest_window(composite),
                levels: summaries,
            };
            write_header(file, &built_info, &levels, temporary)?;
            info = Some(built_info);
            Ok(())
        },
        |path, source| StreamError::Write(PyramidError::Io { path: path.to_path_buf(), source }),
    )?;
    Ok(info.expect("written"))
}

/// A part's statistics: the heights of its own nodes (0 to 0 where it has
/// none), no void counts (the merge counts them over the whole input).
fn part_stats(levels: &[LevelSummary]) -> GridStats {
    let with_data = levels.iter().filter(|l| l.present > 0 && l.height_min <= l.height_max);
    let (low, high) = with_data.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), l| {
        (lo.min(l.height_min), hi.max(l.height_max))
    });
    let (height_min, height_max) = if low <= high { (low, high) } else { (0.0, 0.0) };
    GridStats { height_min, height_max, voids_filled: 0, posts_from_layer: 0, posts_no_data: 0 }
}

/// The blend weights of every layer [`weighted`] names, each in a spill
/// (its chamfer distances in another, dropped once done).
fn spill_weights(
    layers: &[GridView],
    scratch: &ScratchDir,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> std::io::Result<Vec<Option<Spill<f32>>>> {
    let mut all = Vec::with_capacity(layers.len());
    for (layer, weighted) in layers.iter().zip(weighted(layers)) {
        if !weighted {
            all.push(None);
            continue;
        }
        progress.phase("blend weights", 1);
        let posts = layer.heights.len();
        let mut distance = scratch.spill("distance", posts, 0.0f64)?;
        let mut weights = scratch.spill("weights", posts, 0.0f32)?;
        let spacing_m = layer.georef.spacing_m([layer.width, layer.height]);
        let releasers = [distance.releaser(), weights.releaser()];
        let (d, w) = (distance.as_mut_slice(), weights.as_mut_slice());
        // The passes run over the spills in place, dropping the pages
        // behind them (they map back on the next access).
        blend_weights_into(*layer, spacing_m, d, w, &mut || {
            release();
            releasers.iter().for_each(Releaser::release);
        });
        distance.release();
        weights.release();
        progress.advance(1);
        all.push(Some(weights));
    }
    Ok(all)
}

/// Writes the levels `plan` names after the space for the header, finest
/// first; returns the levels' indices and the file.
fn write_levels(
    prepared: &Prepared,
    plan: &LevelPlan,
    path: &Path,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> Result<(Vec<LevelIndex>, File), StreamError> {
    let layout = &prepared.layout;
    let io = |source| StreamError::Write(PyramidError::Io { path: path.to_path_buf(), source });
    let info_len = header_len_of(layout);
    let file = File::create(path).map_err(io)?;
    let reader = File::open(path).map_err(io)?;
    let mut out = BufWriter::with_capacity(1 << 20, file);
    out.seek(SeekFrom::Start(info_len)).map_err(io)?;
    let mut levels: Vec<LevelIndex> = Vec::with_capacity(layout.levels as usize);
    let mut records = 0u64;
    for lod in 0..layout.levels {
        let [nodes_x, nodes_y] = layout.nodes_at(lod);
        let mut level = LevelIndex {
            slots: vec![None; nodes_x as usize * nodes_y as usize],
            summaries: Vec::new(),
            has_data: Vec::new(),
            first_record: records,
        };
        if lod < plan.top {
            // The finer levels are read back through their own handle.
            out.flush().map_err(io)?;
            let finer = WrittenNodes {
                file: &reader,
                layout,
                levels: &levels,
                info_len,
                failed: Mutex::new(None),
            };
            let copy = plan.parts.filter(|_| lod < plan.copied);
            let below = levels.last().map(|l| l.slots.as_slice());
            let emit = &mut |bytes: &[u8]| out.write_all(bytes).map_err(io);
            match copy {
                Some(parts) => copy_level(prepared, parts, lod, &mut level, emit, progress)?,
                None => {
                    let cut = Cut { prepared, plan, finer: &finer, release, progress };
                    cut.level(below, lod, &mut level, emit)?;
                    if let Some(error) = finer.failed.lock().expect("not poisoned").take() {
                        return Err(io(error));
                    }
                }
            }
        }
        records += level.summaries.len() as u64;
        levels.push(level);
    }
    let file = out.into_inner().map_err(|e| io(e.into_error()))?;
    Ok((levels, file))
}

/// What cutting a level from the layers needs.
struct Cut<'a> {
    prepared: &'a Prepared<'a>,
    plan: &'a LevelPlan<'a>,
    finer: &'a WrittenNodes<'a>,
    release: &'a dyn Fn(),
    progress: &'a dyn Progress,
}

/// Where a level's records go, band by band.
type Emit<'a> = &'a mut dyn FnMut(&[u8]) -> Result<(), StreamError>;

impl Cut<'_> {
    /// Cuts level `lod`'s candidates that the plan keeps, band by band,
    /// into `emit`; a failed read of the finer levels is left in
    /// `finer.failed` and stops the cut.
    fn level(
        &self,
        below: Option<&[Option<u32>]>,
        lod: u8,
        level: &mut LevelIndex,
        emit: Emit,
    ) -> Result<(), StreamError> {
        let layout = &self.prepared.layout;
        let mut candidates = candidates(layout, &self.prepared.composite, lod, below);
        if let Some(keep) = self.plan.keep {
            candidates.retain(|(id, _)| keep(*id));
        }
        self.progress.phase(&format!("level {lod}"), candidates.len() as u64);
        let rows = self.prepared.rows_per_band;
        for band in candidates.chunk_by(|a, b| a.0.y / rows == b.0.y / rows) {
            let bytes = self.band(band, level);
            if self.finer.failed.lock().expect("not poisoned").is_some() {
                return Ok(());
            }
            emit(&bytes)?;
        }
        Ok(())
    }

    /// Cuts one band of candidates (whole rows of nodes), measures their
    /// deltas against the finer levels, records them in `level` and
    /// returns their records' bytes in node order.
    fn band(&self, band: &[(NodeId, bool)], level: &mut LevelIndex) -> Vec<u8> {
        let Prepared { layout, composite, band_bytes, .. } = self.prepared;
        let side = layout.stored_side() as usize;
        let per_step = nodes_per_step(layout, band[0].0.level, *band_bytes);
        let mut present: Vec<CutNode> = Vec::new();
        for step in band.chunks(per_step) {
            let cut: Vec<Option<CutNode>> = step
                .par_iter()
                .map(|&(id, parent)| {
                    let mut posts = vec![0.0f32; side * side];
                    let (mut summary, has_data) = cut_node(layout, composite, id, &mut posts);
                    if (has_data || parent) && id.level > 0 {
                        summary.delta = node_delta(self.finer, layout, id, &posts);
                    }
                    self.progress.advance(1);
                    (has_data || parent).then_some((id, posts, summary, has_data))
                })
                .collect();
            present.extend(cut.into_iter().flatten());
            (self.release)();
        }
        append_present(layout, present, level)
    }
}

/// Copies level `lod`'s nodes from the shards' parts, band by band, into
/// `out`: re-encoded from their posts and summaries (the bytes a single
/// process writes), each part's record checked on the way.
fn copy_level(
    prepared: &Prepared,
    parts: &dyn PartNodes,
    lod: u8,
    level: &mut LevelIndex,
    emit: Emit,
    progress: &dyn Progress,
) -> Result<(), StreamError> {
    let layout = &prepared.layout;
    let [nodes_x, nodes_y] = layout.nodes_at(lod);
    progress.phase(&format!("copy level {lod}"), nodes_x as u64 * nodes_y as u64);
    for first in (0..nodes_y).step_by(prepared.rows_per_band as usize) {
        let rows = first..(first + prepared.rows_per_band).min(nodes_y);
        let ids: Vec<NodeId> =
            rows.flat_map(|y| (0..nodes_x).map(move |x| NodeId::new(lod, x, y))).collect();
        let copied: Vec<Option<CutNode>> = ids
            .par_iter()
            .map(|&id| {
                let node = parts.node(id)?;
                progress.advance(1);
                Ok(node.map(|(posts, summary)| {
                    let has_data = centre_has_data(layout, &posts);
                    (id, posts, summary, has_data)
                }))
            })
            .collect::<Result<_, NodeError>>()
            .map_err(StreamError::Part)?;
        parts.release_pages();
        emit(&append_present(layout, copied.into_iter().flatten().collect(), level))?;
    }
    Ok(())
}

/// A node cut from the layers: its id, posts, summary, and whether any
/// centre post has data.
type CutNode = (NodeId, Vec<f32>, NodeSummary, bool);

/// Encodes the `present` nodes of one band (in node order) and records
/// them in `level`; returns their records' bytes.
fn append_present(layout: &NodeLayout, present: Vec<CutNode>, level: &mut LevelIndex) -> Vec<u8> {
    let record = record_len(layout) as usize;
    let mut bytes = vec![0u8; present.len() * record];
    bytes.par_chunks_mut(record).zip(&present).for_each(|(out, (id, posts, summary, _))| {
        let index = layout.node_index(*id).expect("a node of the layout");
        encode_record(index, posts, summary, out);
    });
    for (id, _, summary, has_data) in present {
        let nodes_x = layout.nodes_at(id.level)[0] as usize;
        let index = id.y as usize * nodes_x + id.x as usize;
        debug_assert!(level.slots[index].is_none(), "each node is recorded once");
        level.slots[index] = Some(level.summaries.len() as u32);
        level.summaries.push(summary);
        level.has_data.push(has_data);
    }
    bytes
}

/// Whether any centre post of a node's stored `posts` has data (what
/// [`cut_node`] reports).
fn centre_has_data(layout: &NodeLayout, posts: &[f32]) -> bool {
    let (side, border) = (layout.stored_side() as usize, layout.border as usize);
    let centre = border..=border + layout.node_size as usize;
    posts
        .chunks_exact(side)
        .enumerate()
        .filter(|(q, _)| centre.contains(q))
        .any(|(_, row)| row[centre.clone()].iter().any(|h| !h.is_nan()))
}

/// Nodes of level `lod` cut between two releases of the layers' pages. A
/// coarse node samples rows spread over its whole area, and the kernel
/// maps file pages in folios of up to 2 MB, so the pages it touches grow
/// with its area (4 bytes a level-0 post), not with its posts: as many
/// nodes as `band_bytes` of area allows, at least one per core.
fn nodes_per_step(layout: &NodeLayout, lod: u8, band_bytes: u64) -> usize {
    let area = 4 * layout.span(lod).pow(2);
    ((band_target(band_bytes) / area.max(1)) as usize).max(rayon::current_num_threads()).max(1)
}

/// Bytes a band of nodes, and the layer pages one step of it touches, aim
/// at: [`BAND_TARGET_BYTES`], less if `band_bytes` is smaller.
fn band_target(band_bytes: u64) -> u64 {
    band_bytes.min(BAND_TARGET_BYTES)
}

/// What a band aims at whatever `--memory-mb` allows. Bands bound memory;
/// they do not batch work (one row of nodes keeps every core busy), so a
/// larger band only makes an import hold more of its input at once: with
/// bands of a quarter of 1024 MB, one SRTM1 tile was cut in one band and
/// sixteen touched 256 MB of layer pages per step, twice one tile's peak.
const BAND_TARGET_BYTES: u64 = 32 << 20;

/// Bytes of the header and node table at the start of the file.
fn header_len_of(layout: &NodeLayout) -> u64 {
    super::format::header_len(layout.levels as u64, layout.node_count())
        .expect("a checked layout's header fits u64")
}

/// Writes the header and node table at the start of `file` and flushes it.
fn write_header(
    mut file: File,
    info: &PyramidInfo,
    levels: &[LevelIndex],
    path: &Path,
) -> Result<(), StreamError> {
    let io = |source| StreamError::Write(PyramidError::Io { path: path.to_path_buf(), source });
    let nodes: Vec<Option<NodeSummary>> = levels
        .iter()
        .flat_map(|l| l.slots.iter().map(|s| s.map(|s| l.summaries[s as usize])))
        .collect();
    let header = encode_header(info, &nodes);
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    file.write_all(&header).map_err(io)?;
    file.sync_all().map_err(io)
}

/// The levels already written, read back record by record (positioned
/// reads: nothing of the file stays mapped or resident). A failed read
/// is kept in `failed` (the node counts as absent meanwhile) and fails
/// the band.
struct WrittenNodes<'a> {
    file: &'a File,
    layout: &'a NodeLayout,
    levels: &'a [LevelIndex],
    info_len: u64,
    failed: Mutex<Option<std::io::Error>>,
}

impl WrittenNodes<'_> {
    fn slot(&self, id: NodeId) -> Option<(&LevelIndex, u32)> {
        let level = self.levels.get(id.level as usize)?;
        let [nodes_x, nodes_y] = self.layout.nodes_at(id.level);
        if id.x >= nodes_x || id.y >= nodes_y {
            return None;
        }
        let slot = level.slots[id.y as usize * nodes_x as usize + id.x as usize]?;
        Some((level, slot))
    }
}

impl FinerNodes for WrittenNodes<'_> {
    fn is_present(&self, id: NodeId) -> bool {
        self.slot(id).is_some()
    }

    fn posts(&self, id: NodeId) -> Option<Cow<'_, [f32]>> {
        let (level, slot) = self.slot(id)?;
        let record = record_len(self.layout);
        let at = self.info_len + (level.first_record + slot as u64) * record;
        let side = self.layout.stored_side() as usize;
        let mut posts = vec![0.0f32; side * side];
        match read_at(self.file, bytemuck::cast_slice_mut(&mut posts), at) {
            Ok(()) => Some(Cow::Owned(posts)),
            Err(error) => {
                self.failed.lock().expect("not poisoned").get_or_insert(error);
                None
            }
        }
    }
}

/// Fills `buf` from `file` at `offset`.
fn read_at(file: &File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        let mut done = 0;
        while done < buf.len() {
            let n = std::os::windows::fs::FileExt::seek_read(
                file,
                &mut buf[done..],
                offset + done as u64,
            )?;
            if n == 0 {
                return Err(std::io::ErrorKind::UnexpectedEof.into());
            }
            done += n;
        }
        Ok(())
    }
}
