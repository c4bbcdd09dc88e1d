//! The bytes of `cache/NAME/pyramid.rlp`, format version 3. Every number is
//! little-endian; every byte of the file is covered by a CRC-32 (IEEE) or
//! must be zero. Older versions are refused with a "rebuild it" error.
//!
//! ```text
//! header   magic "RIDGEPYR"  version u32  header_len u64  file_len u64
//!          node_size u32  border u32  levels u32  samples u32 x2
//!          spacing_m f64 x2                      (local frame, east, north)
//!          crs u32 (0 geographic, 1 projected, 2 local)  epsg u32 (0 unknown)
//!          origin f64 x2  spacing f64 x2         (the GeoRef, crs units)
//!          height_min f32  height_max f32
//!          posts_interpolated u64  posts_from_layer u64  posts_no_data u64
//!          layers u32  finest_first u32 x2  finest_posts u32 x2
//!          node_count u64  present_count u64  record_len u32
//!          levels x { nodes_x u32  nodes_y u32  present u64  delta_max f32  min f32  max f32 }
//!          header_crc u32                        (of every header byte before it)
//!          nodes  x { offset u64  min f32  max f32  delta f32
//!                     crc u32 }                  (of the node's index u64, then the entry)
//!                                                (offset ABSENT and zeros: no node)
//!          zero padding to a multiple of 16      (= header_len)
//! records  nodes x { heights f32 x stored_side^2 (row 0 south, border included)
//!                    min f32  max f32  delta f32
//!                    crc u32 }                   (of the node's index u64, then the record)
//! ```
//!
//! Opening checks the fixed part and the level table (their checksum) and
//! nothing that grows with the number of nodes: each node's table entry and
//! record are checked when the node is first read, so a 10 GB pyramid opens
//! as fast as a 1 MB one. Both checksums start with the node's index, so an
//! entry or record moved to another node's place fails. [`Pyramid::verify`]
//! (`ridgeline info`) checks every entry and record, and that the entries
//! agree with each other and with the level table.
//!
//! [`Pyramid::verify`]: super::Pyramid::verify
//!
//! Nodes are listed finest level first, row by row (south first) within a
//! level ([`NodeLayout::node_index`]). The table lists every node of the
//! layout; a node no data of its resolution reach is *absent* (offset
//! [`ABSENT`], summary zero) and has no record: a layered pyramid stores
//! level 0 only where the finest layer is (see [`super`]). Records of present
//! nodes are contiguous in table order, so the `k`-th present node's `offset`
//! is `header_len + k * record_len`: a read checks that an entry's offset is
//! some record's place, [`Pyramid::verify`] that it is the right one. The node table
//! repeats each record's min, max and delta so bounds and errors of the whole
//! pyramid are known without touching the heights; each record repeats them so
//! it is self-contained (Ulrich section 15).

use super::bytes::{Decoder, Encoder};
use super::error::PyramidError;
use super::limits::check_layout;
use crate::geo::{Crs, GeoRef};
use crate::node::NodeLayout;
use std::path::Path;

/// The first eight bytes of every pyramid file.
pub const MAGIC: [u8; 8] = *b"RIDGEPYR";
/// The format version this build writes and reads.
pub const VERSION: u32 = 3;
/// The node table's offset of an absent node.
pub const ABSENT: u64 = u64::MAX;
/// The pyramid's file inside a cache directory.
pub const FILE_NAME: &str = "pyramid.rlp";
const HEADER_ALIGN: u64 = 16;
/// Bytes of the header before the level table.
const FIXED_LEN: u64 = 176;
const LEVEL_ENTRY_LEN: u64 = 28;
const NODE_ENTRY_LEN: u64 = 24;

/// Heights over all the data and what became of the sources' voids. The
/// three counts are in posts of the source files (each layer on its own
/// lattice) and do not overlap.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GridStats {
    /// Lowest height of any present node, metres.
    pub height_min: f32,
    /// Highest height of any present node, metres.
    pub height_max: f32,
    /// Void posts in small voids, interpolated from their neighbours
    /// ([`crate::dem::voids`]).
    pub voids_filled: u64,
    /// Void posts of a layer in large voids that a coarser layer covers:
    /// the pyramid holds the coarser layer's data there.
    pub posts_from_layer: u64,
    /// Void posts of a layer in large voids no other layer covers: no data
    /// there, nothing is drawn.
    pub posts_no_data: u64,
}

/// A window of level-0 posts: its south-west post and its size in posts.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PostWindow {
    /// Level-0 post (east, north) of the window's south-west corner.
    pub first: [u32; 2],
    /// Posts east and north.
    pub posts: [u32; 2],
}

/// One level at a glance.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LevelSummary {
    /// Nodes of the layout at this level, east and north (present or not).
    pub nodes: [u32; 2],
    /// Nodes of the level that are stored (present).
    pub present: u64,
    /// The largest delta of the level's present nodes, metres.
    pub delta_max: f32,
    /// Lowest height of the level's present nodes, metres.
    pub height_min: f32,
    /// Highest height of the level's present nodes, metres.
    pub height_max: f32,
}

/// One node at a glance: see [`crate::node::NodeData`] for the meanings.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct NodeSummary {
    /// Lowest centre post, metres.
    pub min: f32,
    /// Highest centre post, metres.
    pub max: f32,
    /// Largest vertical distance to the best data under the node, metres.
    pub delta: f32,
}

/// Everything the header says about a pyramid except the node table.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PyramidInfo {
    /// The node layout over the union of all layers.
    pub layout: NodeLayout,
    /// Where level-0 post (0, 0) is and the level-0 post spacing.
    pub georef: GeoRef,
    /// Heights and void counts.
    pub stats: GridStats,
    /// How many layers (sets of files of one resolution) were imported.
    pub layers: u32,
    /// The level-0 posts of the finest layer (where a flight over the best
    /// data goes).
    pub finest: PostWindow,
    /// Per level, finest first.
    pub levels: Vec<LevelSummary>,
}

/// Bytes of one node record.
pub fn record_len(layout: &NodeLayout) -> u64 {
    let side = layout.stored_side() as u64;
    4 * (side * side + 3) + 4
}

/// Bytes of the header, padding included, for this many levels and nodes.
pub(crate) fn header_len(levels: u64, nodes: u64) -> Option<u64> {
    let unpadded = FIXED_LEN
        .checked_add(levels.checked_mul(LEVEL_ENTRY_LEN)?)?
        .checked_add(4)?
        .checked_add(nodes.checked_mul(NODE_ENTRY_LEN)?)?;
    Some(unpadded.div_ceil(HEADER_ALIGN) * HEADER_ALIGN)
}

fn crs_code(crs: Crs) -> (u32, u32) {
    match crs {
        Crs::Geographic => (0, 0),
        Crs::Projected { epsg } => (1, epsg.unwrap_or(0)),
        Crs::Local => (2, 0),
    }
}

fn crs_from_code((code, epsg): (u32, u32)) -> Result<Crs, String> {
    match code {
        0 => Ok(Crs::Geographic),
        1 => Ok(Crs::Projected { epsg: (epsg != 0).then_some(epsg) }),
        2 => Ok(Crs::Local),
        _ => Err(format!("unknown coordinate system code {code}")),
    }
}

/// The header of a pyramid with `nodes` in node order (`None`: absent).
pub(crate) fn encode_header(info: &PyramidInfo, nodes: &[Option<NodeSummary>]) -> Vec<u8> {
    let layout = &info.layout;
    debug_assert_eq!(nodes.len() as u64, layout.node_count());
    debug_assert_eq!(info.levels.len(), layout.levels as usize);
    let header_len =
        header_len(info.levels.len() as u64, nodes.len() as u64).expect("in-memory sizes fit u64");
    let record_len = record_len(layout);
    let present = nodes.iter().flatten().count() as u64;
    let mut e = Encoder::default();
    e.bytes.extend_from_slice(&MAGIC);
    e.u32(VERSION);
    e.u64(header_len);
    e.u64(header_len + present * record_len);
    for v in
        [layout.node_size, layout.border, layout.levels as u32, layout.posts[0], layout.posts[1]]
    {
        e.u32(v);
    }
    layout.spacing_m.iter().for_each(|&v| e.f64(v));
    let (crs, epsg) = crs_code(info.georef.crs);
    e.u32(crs);
    e.u32(epsg);
    info.georef.origin.iter().chain(&info.georef.spacing).for_each(|&v| e.f64(v));
    e.f32(info.stats.height_min);
    e.f32(info.stats.height_max);
    e.u64(info.stats.voids_filled);
    e.u64(info.stats.posts_from_layer);
    e.u64(info.stats.posts_no_data);
    e.u32(info.layers);
    info.finest.first.iter().chain(&info.finest.posts).for_each(|&v| e.u32(v));
    e.u64(nodes.len() as u64);
    e.u64(present);
    e.u32(record_len as u32);
    debug_assert_eq!(e.bytes.len() as u64, FIXED_LEN);
    for level in &info.levels {
        e.u32(level.nodes[0]);
        e.u32(level.nodes[1]);
        e.u64(level.present);
        [level.delta_max, level.height_min, level.height_max].iter().for_each(|&v| e.f32(v));
    }
    let crc = crc32fast::hash(&e.bytes);
    e.u32(crc);
    encode_nodes(&mut e, nodes, header_len, record_len);
    e.bytes.resize(header_len as usize, 0);
    e.bytes
}

/// The node table: each node's record offset (records follow the
/// `header_len` bytes of header, `record_len` each, present nodes only)
/// and summary, with a checksum that also covers its index.
fn encode_nodes(e: &mut Encoder, nodes: &[Option<NodeSummary>], header_len: u64, record_len: u64) {
    let mut next = header_len;
    for (index, node) in nodes.iter().enumerate() {
        let start = e.bytes.len();
        match node {
            Some(node) => {
                e.u64(next);
                next += record_len;
                [node.min, node.max, node.delta].iter().for_each(|&v| e.f32(v));
            }
            None => {
                e.u64(ABSENT);
                [0.0f32; 3].iter().for_each(|&v| e.f32(v));
            }
        }
        let crc = indexed_crc(index as u64, &e.bytes[start..]);
        e.u32(crc);
    }
}

/// Checks that the `fixed` part of a header read from `path` (`file_len`
/// bytes) agrees with the file's length and its own layout.
fn check_sizes(path: &Path, fixed: &Fixed, file_len: usize) -> Result<(), PyramidError> {
    let corrupt = |problem: String| PyramidError::corrupt(path, problem);
    if fixed.file_len != file_len as u64 {
        let problem = format!("header says {} bytes, the file has {}", fixed.file_len, file_len);
        return Err(if fixed.file_len > file_len as u64 {
            PyramidError::Truncated { path: path.to_path_buf(), problem }
        } else {
            corrupt(problem)
        });
    }
    let layout = fixed.layout;
    check_layout(&layout).map_err(corrupt)?;
    let node_count = layout.node_count();
    let expected_header = header_len(layout.levels as u64, node_count);
    let expected_file = expected_header.and_then(|h| {
        let present = fixed.present_count.min(node_count);
        present.checked_mul(record_len(&layout))?.checked_add(h)
    });
    if fixed.node_count != node_count
        || fixed.present_count > node_count
        || fixed.record_len as u64 != record_len(&layout)
        || expected_header != Some(fixed.header_len)
        || expected_file != Some(fixed.file_len)
    {
        return Err(corrupt(format!("sizes disagree with the layout {layout:?}")));
    }
    Ok(())
}

/// A header read back and checked.
pub(crate) struct DecodedHeader {
    pub info: PyramidInfo,
    /// Where the node table starts and its sizes.
    pub table: NodeTable,
}

/// Reads and checks the header of `bytes`, the whole file at `path`.
///
/// Sizes are checked against the file's length before anything is
/// allocated, and the checksum before any value is trusted.
pub(crate) fn decode_header(path: &Path, bytes: &[u8]) -> Result<DecodedHeader, PyramidError> {
    let corrupt = |problem: String| PyramidError::corrupt(path, problem);
    let truncated = |problem: String| PyramidError::Truncated { path: path.to_path_buf(), problem };
    let mut d = Decoder::new(bytes);
    let short = || truncated(format!("{} bytes, shorter than the header", bytes.len()));
    if d.take::<8>().ok_or_else(short)? != MAGIC {
        return Err(PyramidError::NotAPyramid { path: path.to_path_buf() });
    }
    let version = d.u32().ok_or_else(short)?;
    if version != VERSION {
        return Err(PyramidError::Version {
            path: path.to_path_buf(),
            found: version,
            supported: VERSION,
        });
    }
    let fixed = read_fixed(&mut d).ok_or_else(short)?;
    check_sizes(path, &fixed, bytes.len())?;
    let layout = fixed.layout;
    let node_count = layout.node_count();
    // From here every table lies inside the file: the lengths are bounded by it.
    // crc_at + 4 <= header_len <= file_len == bytes.len(), checked just above.
    let crc_at = crc_pos(layout.levels as u64) as usize;
    let stored_crc = u32::from_le_bytes(bytes[crc_at..crc_at + 4].try_into().expect("4 bytes"));
    if crc32fast::hash(&bytes[..crc_at]) != stored_crc {
        return Err(corrupt("header checksum mismatch".into()));
    }
    let table = NodeTable {
        start: crc_at as u64 + 4,
        count: node_count,
        present: fixed.present_count,
        header_len: fixed.header_len,
        record_len: record_len(&layout),
    };
    // The padding after the table: at most 15 bytes, whatever the size.
    if bytes[table.end() as usize..fixed.header_len as usize].iter().any(|&b| b != 0) {
        return Err(corrupt("header padding is not zero".into()));
    }
    let levels = read_levels(&mut d, &layout).map_err(corrupt)?;
    if levels.iter().map(|l| l.present).sum::<u64>() != fixed.present_count {
        return Err(corrupt("the levels' present nodes do not add up to the header's".into()));
    }
    let georef = GeoRef { crs: crs_from_code(fixed.crs).map_err(corrupt)?, ..fixed.georef };
    let info = PyramidInfo {
        layout,
        georef,
        stats: fixed.stats,
        layers: fixed.layers,
        finest: fixed.finest,
        levels,
    };
    check_stats(&info).map_err(corrupt)?;
    Ok(DecodedHeader { info, table })
}

/// Byte position of the header checksum (the node table follows it).
fn crc_pos(levels: u64) -> u64 {
    FIXED_LEN + levels * LEVEL_ENTRY_LEN
}

/// CRC-32 of a node's index (little-endian u64) followed by `bytes`: ties a
/// table entry or a record to its node, so bytes moved to another node's
/// place fail their check.
pub(crate) fn indexed_crc(index: u64, bytes: &[u8]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&index.to_le_bytes());
    hasher.update(bytes);
    hasher.finalize()
}

struct Fixed {
    header_len: u64,
    file_len: u64,
    layout: NodeLayout,
    crs: (u32, u32),
    georef: GeoRef,
    stats: GridStats,
    layers: u32,
    finest: PostWindow,
    node_count: u64,
    present_count: u64,
    record_len: u32,
}

fn read_fixed(d: &mut Decoder) -> Option<Fixed> {
    let header_len = d.u64()?;
    let file_len = d.u64()?;
    let [node_size, border, levels, samples_x, samples_y] =
        [d.u32()?, d.u32()?, d.u32()?, d.u32()?, d.u32()?];
    let spacing_m = [d.f64()?, d.f64()?];
    let crs = (d.u32()?, d.u32()?);
    // The crs is decoded once the checksum has been checked.
    let georef =
        GeoRef { crs: Crs::Local, origin: [d.f64()?, d.f64()?], spacing: [d.f64()?, d.f64()?] };
    let stats = GridStats {
        height_min: d.f32()?,
        height_max: d.f32()?,
        voids_filled: d.u64()?,
        posts_from_layer: d.u64()?,
        posts_no_data: d.u64()?,
    };
    let layers = d.u32()?;
    let finest = PostWindow { first: [d.u32()?, d.u32()?], posts: [d.u32()?, d.u32()?] };
    let node_count = d.u64()?;
    let present_count = d.u64()?;
    let record_len = d.u32()?;
    let levels = u8::try_from(levels).unwrap_or(u8::MAX);
    let layout = NodeLayout { levels, node_size, border, posts: [samples_x, samples_y], spacing_m };
    Some(Fixed {
        header_len,
        file_len,
        layout,
        crs,
        georef,
        stats,
        layers,
        finest,
        node_count,
        present_count,
        record_len,
    })
}

fn read_levels(d: &mut Decoder, layout: &NodeLayout) -> Result<Vec<LevelSummary>, String> {
    (0..layout.levels)
        .map(|lod| {
            let short = || "level table cut short".to_string();
            let nodes = [d.u32().ok_or_else(short)?, d.u32().ok_or_else(short)?];
            let present = d.u64().ok_or_else(short)?;
            let [delta_max, height_min, height_max] = [
                d.f32().ok_or_else(short)?,
                d.f32().ok_or_else(short)?,
                d.f32().ok_or_else(short)?,
            ];
            if nodes != layout.nodes_at(lod) {
                return Err(format!(
                    "level {lod} has {nodes:?} nodes, the layout {:?}",
                    layout.nodes_at(lod)
                ));
            }
            Ok(LevelSummary { nodes, present, delta_max, height_min, height_max })
        })
        .collect()
}

/// Where the node table lies and the sizes its entries are checked against.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NodeTable {
    /// Byte position of entry 0.
    pub start: u64,
    /// Entries: every node of the layout.
    pub count: u64,
    /// Present nodes (records).
    pub present: u64,
    /// Where the records start.
    pub header_len: u64,
    /// Bytes of one record.
    pub record_len: u64,
}

impl NodeTable {
    /// Byte position just past the last entry.
    fn end(&self) -> u64 {
        self.start + self.count * NODE_ENTRY_LEN
    }

    /// Entry `index` of `bytes` (the whole file), checked: its checksum,
    /// and an offset that is a record's place inside the file (or
    /// [`ABSENT`] with a zero summary). Reads 24 bytes: opening decodes no
    /// entry, so it costs the same whatever the number of nodes.
    pub fn entry(&self, bytes: &[u8], index: u64) -> Result<Option<(u64, NodeSummary)>, String> {
        if index >= self.count {
            return Err(format!("node {index} is past the table's {} entries", self.count));
        }
        let at = (self.start + index * NODE_ENTRY_LEN) as usize;
        let entry = &bytes[at..at + NODE_ENTRY_LEN as usize];
        let (body, crc) = entry.split_at(entry.len() - 4);
        if indexed_crc(index, body) != u32::from_le_bytes(crc.try_into().expect("4 bytes")) {
            return Err(format!("node table entry {index}: checksum mismatch"));
        }
        let mut d = Decoder::new(body);
        let short = || format!("node table entry {index} cut short");
        let offset = d.u64().ok_or_else(short)?;
        let summary = NodeSummary {
            min: d.f32().ok_or_else(short)?,
            max: d.f32().ok_or_else(short)?,
            delta: d.f32().ok_or_else(short)?,
        };
        if offset == ABSENT {
            if summary != NodeSummary::default() {
                return Err(format!("absent node {index} has a summary {summary:?}"));
            }
            return Ok(None);
        }
        let slot =
            offset.checked_sub(self.header_len).map(|o| (o / self.record_len, o % self.record_len));
        if !matches!(slot, Some((k, 0)) if k < self.present) {
            return Err(format!("node {index} at offset {offset}, not a record's place"));
        }
        check_summary(&summary).map_err(|p| format!("node {index}: {p}"))?;
        Ok(Some((offset, summary)))
    }

    /// Every entry, checked one by one and together: present nodes in node
    /// order at consecutive records, each level's count as `levels` says,
    /// the root level whole ([`crate::pyramid::Pyramid::verify`]).
    pub fn all_entries(
        &self,
        bytes: &[u8],
        layout: &NodeLayout,
        levels: &[LevelSummary],
    ) -> Result<Vec<Option<(u64, NodeSummary)>>, String> {
        let mut next = self.header_len;
        let mut nodes = Vec::with_capacity(self.count as usize);
        for index in 0..self.count {
            let entry = self.entry(bytes, index)?;
            if let Some((offset, _)) = entry {
                if offset != next {
                    return Err(format!("node {index} at offset {offset}, expected {next}"));
                }
                next += self.record_len;
            }
            nodes.push(entry);
        }
        check_presence(layout, levels, &nodes)?;
        Ok(nodes)
    }
}

fn check_presence(
    layout: &NodeLayout,
    levels: &[LevelSummary],
    nodes: &[Option<(u64, NodeSummary)>],
) -> Result<(), String> {
    let mut start = 0usize;
    for (lod, level) in levels.iter().enumerate() {
        let count = layout.nodes_at_count(lod as u8) as usize;
        let present = nodes[start..start + count].iter().flatten().count() as u64;
        if present != level.present {
            return Err(format!(
                "level {lod} lists {} present nodes, the node table {present}",
                level.present
            ));
        }
        start += count;
    }
    let root = levels.last().map_or(0, |l| l.present);
    if root != layout.nodes_at_count(layout.levels - 1) {
        return Err("the root level has absent nodes".into());
    }
    Ok(())
}

fn check_summary(s: &NodeSummary) -> Result<(), String> {
    let ordered = s.min.is_finite() && s.max.is_finite() && s.min <= s.max;
    if !(ordered && s.delta.is_finite() && s.delta >= 0.0) {
        return Err(format!("bad bounds or delta {s:?}"));
    }
    Ok(())
}

fn check_stats(info: &PyramidInfo) -> Result<(), String> {
    let s = &info.stats;
    if !(s.height_min.is_finite() && s.height_max.is_finite() && s.height_min <= s.height_max) {
        return Err(format!("bad height range {}..{}", s.height_min, s.height_max));
    }
    if let Some(problem) = info.georef.problem(info.layout.posts) {
        return Err(problem);
    }
    Ok(())
}

/// Writes the record of one node into `out` (`record_len` bytes).
pub(crate) fn encode_record(index: u64, heights: &[f32], summary: &NodeSummary, out: &mut [u8]) {
    let (body, crc) = out.split_at_mut(out.len() - 4);
    debug_assert_eq!(body.len(), heights.len() * 4 + 12);
    let values = heights.iter().chain([&summary.min, &summary.max, &summary.delta]);
    for (chunk, value) in body.chunks_exact_mut(4).zip(values) {
        chunk.copy_from_slice(&value.to_le_bytes());
    }
    crc.copy_from_slice(&indexed_crc(index, body).to_le_bytes());
}

/// The heights bytes of node `index`'s record after checking its checksum
/// (which covers the index: another node's record fails it) and that it
/// repeats the node table's `expected` summary.
pub(crate) fn check_record<'a>(
    index: u64,
    record: &'a [u8],
    expected: &NodeSummary,
) -> Result<&'a [u8], String> {
    let (body, crc) = record.split_at(record.len() - 4);
    if indexed_crc(index, body) != u32::from_le_bytes(crc.try_into().expect("4 bytes")) {
        return Err("checksum mismatch".into());
    }
    let (heights, tail) = body.split_at(body.len() - 12);
    let value = |n: usize| f32::from_le_bytes(tail[4 * n..4 * n + 4].try_into().expect("4 bytes"));
    let repeated = NodeSummary { min: value(0), max: value(1), delta: value(2) };
    if repeated != *expected {
        return Err(format!("record says {repeated:?}, the node table {expected:?}"));
    }
    Ok(heights)
}
