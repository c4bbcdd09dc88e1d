//! The bytes of `cache/NAME/pyramid.rlp`, format version 1. Every number is
//! little-endian; every byte of the file is covered by a CRC-32 (IEEE) or
//! must be zero.
//!
//! ```text
//! header   magic "RIDGEPYR"  version u32  header_len u64  file_len u64
//!          node_size u32  border u32  levels u32  samples u32 x2
//!          spacing_m f64 x2                      (local frame, east, north)
//!          crs u32 (0 geographic, 1 projected, 2 local)  epsg u32 (0 unknown)
//!          origin f64 x2  spacing f64 x2         (the GeoRef, crs units)
//!          height_min f32  height_max f32  voids_filled u64
//!          node_count u64  record_len u32
//!          levels x { nodes_x u32  nodes_y u32  delta_max f32  min f32  max f32 }
//!          nodes  x { offset u64  min f32  max f32  delta f32 }
//!          header_crc u32                        (of every header byte before it)
//!          zero padding to a multiple of 16      (= header_len)
//! records  nodes x { heights f32 x stored_side^2 (row 0 south, border included)
//!                    min f32  max f32  delta f32  crc u32 (of the record before it) }
//! ```
//!
//! Nodes are listed finest level first, row by row (south first) within a
//! level ([`NodeLayout::node_index`]); records are contiguous, so `offset` is
//! `header_len + index * record_len`, which the reader checks. The node table
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
pub const VERSION: u32 = 1;
/// The pyramid's file inside a cache directory.
pub const FILE_NAME: &str = "pyramid.rlp";
const HEADER_ALIGN: u64 = 16;
/// Bytes of the header before the level table.
const FIXED_LEN: u64 = 132;
const LEVEL_ENTRY_LEN: u64 = 20;
const NODE_ENTRY_LEN: u64 = 20;

/// Heights over the whole grid and how many voids the importer filled.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GridStats {
    /// Lowest height of the grid, metres.
    pub height_min: f32,
    /// Highest height of the grid, metres.
    pub height_max: f32,
    /// Posts the importer filled because the source had voids there.
    pub voids_filled: u64,
}

/// One level at a glance.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LevelSummary {
    /// Nodes east and north at this level.
    pub nodes: [u32; 2],
    /// The largest delta of the level's nodes, metres.
    pub delta_max: f32,
    /// Lowest height of the level's nodes, metres.
    pub height_min: f32,
    /// Highest height of the level's nodes, metres.
    pub height_max: f32,
}

/// One node at a glance: see [`crate::node::NodeData`] for the meanings.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct NodeSummary {
    /// Lowest height of the node's centre posts.
    pub min: f32,
    /// Highest height of the node's centre posts.
    pub max: f32,
    /// Ulrich's delta of the node, metres.
    pub delta: f32,
}

/// Everything the header says about a pyramid except the node table.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PyramidInfo {
    /// Levels, node size, border and post spacing.
    pub layout: NodeLayout,
    /// Where the grid lies on the earth.
    pub georef: GeoRef,
    /// Heights and void counts over the whole grid.
    pub stats: GridStats,
    /// One summary per level, finest first.
    pub levels: Vec<LevelSummary>,
}

/// Bytes of one node record.
pub fn record_len(layout: &NodeLayout) -> u64 {
    let side = layout.stored_side() as u64;
    4 * (side * side + 3) + 4
}

/// Bytes of the header, padding included, for this many levels and nodes.
fn header_len(levels: u64, nodes: u64) -> Option<u64> {
    let unpadded = FIXED_LEN
        .checked_add(levels.checked_mul(LEVEL_ENTRY_LEN)?)?
        .checked_add(nodes.checked_mul(NODE_ENTRY_LEN)?)?
        .checked_add(4)?;
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

/// The header of a pyramid with `nodes` in node order.
pub(crate) fn encode_header(info: &PyramidInfo, nodes: &[NodeSummary]) -> Vec<u8> {
    let layout = &info.layout;
    debug_assert_eq!(nodes.len() as u64, layout.node_count());
    debug_assert_eq!(info.levels.len(), layout.levels as usize);
    let header_len =
        header_len(info.levels.len() as u64, nodes.len() as u64).expect("in-memory sizes fit u64");
    let record_len = record_len(layout);
    let mut e = Encoder::default();
    e.bytes.extend_from_slice(&MAGIC);
    e.u32(VERSION);
    e.u64(header_len);
    e.u64(header_len + nodes.len() as u64 * record_len);
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
    e.u64(nodes.len() as u64);
    e.u32(record_len as u32);
    debug_assert_eq!(e.bytes.len() as u64, FIXED_LEN);
    for level in &info.levels {
        e.u32(level.nodes[0]);
        e.u32(level.nodes[1]);
        [level.delta_max, level.height_min, level.height_max].iter().for_each(|&v| e.f32(v));
    }
    for (index, node) in nodes.iter().enumerate() {
        e.u64(header_len + index as u64 * record_len);
        [node.min, node.max, node.delta].iter().for_each(|&v| e.f32(v));
    }
    let crc = crc32fast::hash(&e.bytes);
    e.u32(crc);
    e.bytes.resize(header_len as usize, 0);
    e.bytes
}

/// A header read back and checked.
pub(crate) struct DecodedHeader {
    pub info: PyramidInfo,
    pub nodes: Vec<NodeSummary>,
    pub header_len: u64,
    pub record_len: u64,
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
    if fixed.file_len != bytes.len() as u64 {
        let problem = format!("header says {} bytes, the file has {}", fixed.file_len, bytes.len());
        return Err(if fixed.file_len > bytes.len() as u64 {
            truncated(problem)
        } else {
            corrupt(problem)
        });
    }
    let layout = fixed.layout;
    check_layout(&layout).map_err(corrupt)?;
    let node_count = layout.node_count();
    let expected_header = header_len(layout.levels as u64, node_count);
    let expected_file =
        expected_header.and_then(|h| node_count.checked_mul(record_len(&layout))?.checked_add(h));
    if fixed.node_count != node_count
        || fixed.record_len as u64 != record_len(&layout)
        || expected_header != Some(fixed.header_len)
        || expected_file != Some(fixed.file_len)
    {
        return Err(corrupt(format!("sizes disagree with the layout {layout:?}")));
    }
    // From here every table lies inside the file: the lengths are bounded by it.
    // crc_at + 4 <= header_len <= file_len == bytes.len(), checked just above.
    let crc_at = crc_pos(layout.levels as u64, node_count) as usize;
    let stored_crc = u32::from_le_bytes(bytes[crc_at..crc_at + 4].try_into().expect("4 bytes"));
    if crc32fast::hash(&bytes[..crc_at]) != stored_crc {
        return Err(corrupt("header checksum mismatch".into()));
    }
    if bytes[crc_at + 4..fixed.header_len as usize].iter().any(|&b| b != 0) {
        return Err(corrupt("header padding is not zero".into()));
    }
    let levels = read_levels(&mut d, &layout).map_err(corrupt)?;
    let nodes =
        read_nodes(&mut d, node_count, fixed.header_len, record_len(&layout)).map_err(corrupt)?;
    let georef = GeoRef { crs: crs_from_code(fixed.crs).map_err(corrupt)?, ..fixed.georef };
    let info = PyramidInfo { layout, georef, stats: fixed.stats, levels };
    check_stats(&info).map_err(corrupt)?;
    Ok(DecodedHeader { info, nodes, header_len: fixed.header_len, record_len: record_len(&layout) })
}

/// Byte position of the header checksum.
fn crc_pos(levels: u64, nodes: u64) -> u64 {
    FIXED_LEN + levels * LEVEL_ENTRY_LEN + nodes * NODE_ENTRY_LEN
}

struct Fixed {
    header_len: u64,
    file_len: u64,
    layout: NodeLayout,
    crs: (u32, u32),
    georef: GeoRef,
    stats: GridStats,
    node_count: u64,
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
    let stats = GridStats { height_min: d.f32()?, height_max: d.f32()?, voids_filled: d.u64()? };
    let node_count = d.u64()?;
    let record_len = d.u32()?;
    let levels = u8::try_from(levels).unwrap_or(u8::MAX);
    let layout = NodeLayout { levels, node_size, border, posts: [samples_x, samples_y], spacing_m };
    Some(Fixed { header_len, file_len, layout, crs, georef, stats, node_count, record_len })
}

fn read_levels(d: &mut Decoder, layout: &NodeLayout) -> Result<Vec<LevelSummary>, String> {
    (0..layout.levels)
        .map(|lod| {
            let short = || "level table cut short".to_string();
            let nodes = [d.u32().ok_or_else(short)?, d.u32().ok_or_else(short)?];
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
            Ok(LevelSummary { nodes, delta_max, height_min, height_max })
        })
        .collect()
}

fn read_nodes(
    d: &mut Decoder,
    count: u64,
    header_len: u64,
    record_len: u64,
) -> Result<Vec<NodeSummary>, String> {
    (0..count)
        .map(|index| {
            let short = || "node table cut short".to_string();
            let offset = d.u64().ok_or_else(short)?;
            let summary = NodeSummary {
                min: d.f32().ok_or_else(short)?,
                max: d.f32().ok_or_else(short)?,
                delta: d.f32().ok_or_else(short)?,
            };
            if offset != header_len + index * record_len {
                return Err(format!(
                    "node {index} at offset {offset}, expected {}",
                    header_len + index * record_len
                ));
            }
            check_summary(&summary).map_err(|p| format!("node {index}: {p}"))?;
            Ok(summary)
        })
        .collect()
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
pub(crate) fn encode_record(heights: &[f32], summary: &NodeSummary, out: &mut [u8]) {
    let (body, crc) = out.split_at_mut(out.len() - 4);
    debug_assert_eq!(body.len(), heights.len() * 4 + 12);
    let values = heights.iter().chain([&summary.min, &summary.max, &summary.delta]);
    for (chunk, value) in body.chunks_exact_mut(4).zip(values) {
        chunk.copy_from_slice(&value.to_le_bytes());
    }
    crc.copy_from_slice(&crc32fast::hash(body).to_le_bytes());
}

/// The heights bytes of a record after checking its checksum and that it
/// repeats the node table's `expected` summary.
pub(crate) fn check_record<'a>(
    record: &'a [u8],
    expected: &NodeSummary,
) -> Result<&'a [u8], String> {
    let (body, crc) = record.split_at(record.len() - 4);
    if crc32fast::hash(body) != u32::from_le_bytes(crc.try_into().expect("4 bytes")) {
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
