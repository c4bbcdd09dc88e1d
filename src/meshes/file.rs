//! The map file, `meshes.rlm` beside the pyramid: every stored node's
//! error map, one file for every tau and viewport. Little-endian,
//! versioned, checksummed per record, memory-mapped, written atomically
//! and streaming (records are written as nodes finish; memory does not
//! grow with the pyramid), in one process or in shards merged afterwards.
//!
//! ```text
//! header  magic "RIDGEMAP", version u32, levels u32, nodes u64,
//!         pyramid u32 (see below), depth u32, tile_cells u32,
//!         finest_view_px f64, per level: floor_m f32,
//!         reference_delta_max f32, error_max f32 (the coarsest mesh's
//!         error); then crc32 of all of the above
//! table   per node of the pyramid's layout, in its node order (24 bytes):
//!         offset u64 (u64::MAX: absent from the pyramid, u64::MAX - 1:
//!         not built by this shard), len u32, count u32, shape u32 (the
//!         record's kind, plus 4 times its cells), crc32
//!         of (node index, record)
//! records block by block (`super::block::record_order`), each as
//!         `super::record` lays it out (format 2: compact keys, heights
//!         quantised or read from the pyramid at page-in)
//! ```
//!
//! `pyramid` is the CRC-32 of the first 64 KiB of the pyramid file (its
//! header and node table, or all of it): a map file built for another
//! pyramid, or for an earlier import of this one, is refused at open and
//! rebuilt by the caller.

use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use memmap2::Mmap;
use rayon::prelude::*;

use super::block::{build_blocks, record_order};
use super::pagein::fill_from_pyramid;
use super::record;
use super::{MeshOptions, MeshesError};
use crate::mesh::code::{code_error, ALWAYS};
use crate::node::{ErrorMap, NodeError, NodeId, NodeLayout, NodeSource};
use crate::pyramid::{replace_file, Progress};

#[cfg(target_endian = "big")]
compile_error!("the map file is read by casting little-endian bytes");

/// The map file's name in a pyramid's cache directory.
pub const MAP_FILE_NAME: &str = "meshes.rlm";

const MAGIC: [u8; 8] = *b"RIDGEMAP";
const VERSION: u32 = 2;
const FIXED_LEN: usize = 48;
/// Bytes of one level's summary in the header.
const LEVEL_LEN: usize = 12;
const ENTRY_LEN: usize = 24;
const ABSENT: u64 = u64::MAX;
const NOT_BUILT: u64 = u64::MAX - 1;
/// Bytes of the pyramid file its identity covers.
const PYRAMID_ID_BYTES: u64 = 64 * 1024;
/// Bytes a decoded map takes beside its arrays: `above`'s 4 x 256 counts.
const ABOVE_BYTES: u64 = 4 * 256 * 4;

/// What the header says.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StoreInfo {
    /// The options the maps were built with.
    pub options: MeshOptions,
    /// Per level, the smallest error its sparse maps serve (0 where every
    /// node of the level is dense), metres.
    pub floor_per_level: Vec<f32>,
    /// Per level, the largest reference delta of its maps, metres.
    pub reference_delta_per_level: Vec<f32>,
    /// Per level, the error of its coarsest meshes (the largest split
    /// error its maps keep), metres: past it a larger error draws nothing
    /// coarser.
    pub max_error_per_level: Vec<f32>,
    /// Identity of the pyramid file the maps belong to.
    pub pyramid: u32,
}

impl StoreInfo {
    /// What each level's maps can do, for the tiles' errors.
    pub fn map_errors(&self) -> crate::tiles::errors::MapErrors {
        let f64s = |v: &[f32]| v.iter().map(|&x| x as f64).collect();
        crate::tiles::errors::MapErrors {
            floor: f64s(&self.floor_per_level),
            reference: f64s(&self.reference_delta_per_level),
            max: f64s(&self.max_error_per_level),
        }
    }

    /// The error of level `l`'s finest mesh, metres: its floor and its
    /// reference lattice's delta (what the rings' Ulrich rule needs).
    pub fn finest_error_per_level(&self) -> Vec<f64> {
        self.floor_per_level
            .iter()
            .zip(&self.reference_delta_per_level)
            .map(|(&f, &r)| f as f64 + r as f64)
            .collect()
    }
}

/// The identity of the pyramid file at `path` (see the module notes).
pub fn pyramid_identity(path: &Path) -> std::io::Result<u32> {
    let mut bytes = Vec::new();
    File::open(path)?.take(PYRAMID_ID_BYTES).read_to_end(&mut bytes)?;
    Ok(crc32fast::hash(&bytes))
}

/// One node's table entry.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    offset: u64,
    len: u32,
    count: u32,
    /// The record's kind (bit 0) and twice its cells.
    shape: u32,
    crc: u32,
}

impl Entry {
    const ABSENT: Entry = Entry { offset: ABSENT, len: 0, count: 0, shape: 0, crc: 0 };
    const NOT_BUILT: Entry = Entry { offset: NOT_BUILT, ..Entry::ABSENT };

    fn encode(&self) -> [u8; ENTRY_LEN] {
        let mut out = [0u8; ENTRY_LEN];
        out[0..8].copy_from_slice(&self.offset.to_le_bytes());
        out[8..12].copy_from_slice(&self.len.to_le_bytes());
        out[12..16].copy_from_slice(&self.count.to_le_bytes());
        out[16..20].copy_from_slice(&self.shape.to_le_bytes());
        out[20..24].copy_from_slice(&self.crc.to_le_bytes());
        out
    }

    fn decode(bytes: &[u8]) -> Entry {
        let u32_at = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
        Entry {
            offset: u64::from_le_bytes(bytes[0..8].try_into().expect("8 bytes")),
            len: u32_at(8),
            count: u32_at(12),
            shape: u32_at(16),
            crc: u32_at(20),
        }
    }

    fn is_record(&self) -> bool {
        self.offset < NOT_BUILT
    }

    fn kind(&self) -> u32 {
        self.shape & 3
    }

    /// The heap a decoded map of this record takes, bytes: its arrays,
    /// `above`, and for a sparse map its row index.
    fn heap_bytes(&self) -> u64 {
        if !self.is_record() {
            return 0;
        }
        let cells = (self.shape >> 2) as u64;
        match self.kind() {
            record::DENSE => self.count as u64 + ABOVE_BYTES,
            _ => 11 * self.count as u64 + ABOVE_BYTES + 4 * (cells + 2),
        }
    }
}

fn record_crc(index: u64, record: &[u8]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&index.to_le_bytes());
    hasher.update(record);
    hasher.finalize()
}

/// A node's record and its entry (offset still to be set).
fn encode_record(index: u64, map: &ErrorMap) -> (Vec<u8>, Entry) {
    let (bytes, count) = record::encode(map);
    let entry = Entry {
        offset: 0,
        len: bytes.len() as u32,
        count,
        shape: record::kind_of(map) | map.cells << 2,
        crc: record_crc(index, &bytes),
    };
    (bytes, entry)
}

/// Decodes node `id`'s record into `out` (a fresh map), reading the heights
/// and normals of a map that stores none from the nodes under it in
/// `source` ([`super::pagein`]); buffers are reserved exactly (a buffer is counted at what the
/// node needs, as the memory budget plans).
fn decode_record(
    source: &dyn NodeSource,
    id: NodeId,
    bytes: &[u8],
    entry: &Entry,
    out: &mut ErrorMap,
) -> Result<(), NodeError> {
    let corrupt = |problem: String| NodeError::Corrupt { path: PathBuf::new(), id, problem };
    let head = record::head(bytes);
    if head.kind | head.cells << 2 != entry.shape || head.count != entry.count as usize {
        return Err(corrupt(format!("map record does not fit its entry ({entry:?})")));
    }
    record::decode(bytes, out).map_err(corrupt)?;
    let layout = source.layout();
    let lattice = out.post_level <= id.level
        && (layout.node_size as u64) << (id.level - out.post_level) == out.cells as u64;
    if !lattice {
        return Err(corrupt(format!(
            "map record's lattice of level {} does not fit",
            out.post_level
        )));
    }
    if head.kind == record::FROM_PYRAMID {
        fill_from_pyramid(source, id, out)?;
    }
    if out.heights.iter().any(|h| h.is_infinite()) {
        return Err(corrupt("map record has an infinite height".into()));
    }
    out.count_codes();
    out.index_rows();
    Ok(())
}

/// Builds the maps of `nodes` (stored nodes of `source`, ascending in the
/// layout's node order) and writes them to `out` atomically, streaming: a
/// few nodes per core are held at a time. Nodes of the layout not in
/// `nodes` are marked absent (not stored) or not built (a shard's part).
/// `pyramid` is the pyramid file's identity.
pub fn build_store(
    source: &dyn NodeSource,
    pyramid: u32,
    nodes: &[NodeId],
    options: MeshOptions,
    out: &Path,
    progress: &dyn Progress,
) -> Result<StoreInfo, MeshesError> {
    options.validate(source.layout())?;
    let layout = *source.layout();
    let io = |path: &Path, source| MeshesError::Io { path: path.to_path_buf(), source };
    let mut info = StoreInfo {
        options,
        floor_per_level: vec![0.0; layout.levels as usize],
        reference_delta_per_level: vec![0.0; layout.levels as usize],
        max_error_per_level: vec![0.0; layout.levels as usize],
        pyramid,
    };
    progress.phase("meshes", nodes.len() as u64);
    replace_file(
        out,
        |temporary| {
            let file = File::create(temporary).map_err(|e| io(temporary, e))?;
            let mut writer = StoreWriter::new(file, &layout);
            writer.start(&info).map_err(|e| io(temporary, e))?;
            let mut table = initial_table(source, &layout);
            let mut emit = |id: NodeId, map: ErrorMap| {
                let index = layout.node_index(id).expect("a node of the layout");
                note_level(&mut info, id.level, &map);
                let entry = writer.append(index, &map).map_err(|e| io(temporary, e))?;
                table[index as usize] = entry;
                progress.advance(1);
                Ok(())
            };
            build_blocks(source, nodes, &options, &mut emit)?;
            writer.finish(&info, &table).map_err(|e| io(temporary, e))
        },
        io,
    )?;
    Ok(info)
}

/// The table before any record: absent where the pyramid stores no node,
/// not built elsewhere.
fn initial_table(source: &dyn NodeSource, layout: &NodeLayout) -> Vec<Entry> {
    let stored = |id: NodeId| source.has_node(id);
    all_nodes(layout)
        .into_iter()
        .map(|id| if stored(id) { Entry::NOT_BUILT } else { Entry::ABSENT })
        .collect()
}

/// Every node of the layout, in its node order.
fn all_nodes(layout: &NodeLayout) -> Vec<NodeId> {
    let mut ids = Vec::with_capacity(layout.node_count() as usize);
    for level in 0..layout.levels {
        let [nx, ny] = layout.nodes_at(level);
        ids.extend((0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(level, x, y))));
    }
    ids
}

fn note_level(info: &mut StoreInfo, level: u8, map: &ErrorMap) {
    let l = level as usize;
    info.floor_per_level[l] = info.floor_per_level[l].max(map.floor_m);
    info.reference_delta_per_level[l] = info.reference_delta_per_level[l].max(map.reference_delta);
    let coarsest = map.codes.iter().filter(|&&c| c < ALWAYS).max().map_or(0.0, |&c| code_error(c));
    info.max_error_per_level[l] = info.max_error_per_level[l].max(coarsest as f32);
}

/// Writes a map file: the header and table reserved first, records
/// appended, then the table and the header filled in.
struct StoreWriter {
    out: BufWriter<File>,
    offset: u64,
    header_len: usize,
    table_len: usize,
}

impl StoreWriter {
    fn new(file: File, layout: &NodeLayout) -> StoreWriter {
        let header_len = FIXED_LEN + LEVEL_LEN * layout.levels as usize + 4;
        let table_len = ENTRY_LEN * layout.node_count() as usize;
        let offset = (header_len + table_len) as u64;
        StoreWriter { out: BufWriter::new(file), offset, header_len, table_len }
    }

    fn start(&mut self, info: &StoreInfo) -> std::io::Result<()> {
        // Placeholders: a file killed before `finish` has a bad header
        // checksum, and is never renamed into place anyway.
        let zeros = vec![0u8; self.header_len + self.table_len];
        debug_assert!(!info.floor_per_level.is_empty());
        self.out.write_all(&zeros)
    }

    fn append(&mut self, index: u64, map: &ErrorMap) -> std::io::Result<Entry> {
        let (bytes, entry) = encode_record(index, map);
        self.append_bytes(&bytes, entry)
    }

    fn append_bytes(&mut self, bytes: &[u8], entry: Entry) -> std::io::Result<Entry> {
        self.out.write_all(bytes)?;
        let placed = Entry { offset: self.offset, ..entry };
        self.offset += bytes.len() as u64;
        Ok(placed)
    }

    fn finish(mut self, info: &StoreInfo, table: &[Entry]) -> std::io::Result<()> {
        self.out.seek(SeekFrom::Start(0))?;
        self.out.write_all(&encode_header(info, table.len() as u64))?;
        for entry in table {
            self.out.write_all(&entry.encode())?;
        }
        let file = self.out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()
    }
}

fn encode_header(info: &StoreInfo, nodes: u64) -> Vec<u8> {
    let levels = info.floor_per_level.len();
    let mut header = Vec::with_capacity(FIXED_LEN + LEVEL_LEN * levels + 4);
    header.extend_from_slice(&MAGIC);
    header.extend_from_slice(&VERSION.to_le_bytes());
    header.extend_from_slice(&(levels as u32).to_le_bytes());
    header.extend_from_slice(&nodes.to_le_bytes());
    header.extend_from_slice(&info.pyramid.to_le_bytes());
    header.extend_from_slice(&(info.options.depth as u32).to_le_bytes());
    header.extend_from_slice(&info.options.tile_cells.to_le_bytes());
    header.extend_from_slice(&info.options.finest_view_px.to_le_bytes());
    header.resize(FIXED_LEN, 0);
    for l in 0..levels {
        header.extend_from_slice(&info.floor_per_level[l].to_le_bytes());
        header.extend_from_slice(&info.reference_delta_per_level[l].to_le_bytes());
        header.extend_from_slice(&info.max_error_per_level[l].to_le_bytes());
    }
    header.extend_from_slice(&crc32fast::hash(&header).to_le_bytes());
    header
}

fn decode_header(bytes: &[u8], layout: &NodeLayout) -> Result<(StoreInfo, usize), String> {
    if bytes.len() < FIXED_LEN || bytes[0..8] != MAGIC {
        return Err("not a Ridgeline map file".into());
    }
    let u32_at = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
    let version = u32_at(8);
    if version != VERSION {
        return Err(format!(
            "map file version {version}, this build reads {VERSION}: rebuild it (opening the \
             pyramid with `fly` or `accuracy` rebuilds it beside it)"
        ));
    }
    let levels = u32_at(12) as usize;
    let nodes = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    if levels != layout.levels as usize || nodes != layout.node_count() {
        return Err(format!("{levels} levels and {nodes} nodes, the pyramid has other"));
    }
    let crc_at = FIXED_LEN + LEVEL_LEN * levels;
    if bytes.len() < crc_at + 4 {
        return Err("truncated header".into());
    }
    if crc32fast::hash(&bytes[..crc_at]) != u32_at(crc_at) {
        return Err("header checksum mismatch".into());
    }
    let options = MeshOptions {
        depth: u32_at(28).min(255) as u8,
        tile_cells: u32_at(32),
        finest_view_px: f64::from_le_bytes(bytes[36..44].try_into().expect("8 bytes")),
    };
    options.validate(layout).map_err(|e| e.to_string())?;
    let level_value =
        |l: usize, k: usize| f32::from_bits(u32_at(FIXED_LEN + LEVEL_LEN * l + 4 * k));
    let floor_per_level: Vec<f32> = (0..levels).map(|l| level_value(l, 0)).collect();
    let reference_delta_per_level: Vec<f32> = (0..levels).map(|l| level_value(l, 1)).collect();
    let max_error_per_level: Vec<f32> = (0..levels).map(|l| level_value(l, 2)).collect();
    let mut distances =
        floor_per_level.iter().chain(&reference_delta_per_level).chain(&max_error_per_level);
    if distances.any(|d| !(d.is_finite() && *d >= 0.0)) {
        return Err("level floors or reference deltas are not distances".into());
    }
    let info = StoreInfo {
        options,
        floor_per_level,
        reference_delta_per_level,
        max_error_per_level,
        pyramid: u32_at(24),
    };
    Ok((info, crc_at + 4))
}

/// An open map file.
pub struct MapFile {
    path: PathBuf,
    map: Mmap,
    info: StoreInfo,
    table: usize,
    nodes: u64,
}

impl MapFile {
    /// Opens and checks the header of the map file at `path`, which must
    /// belong to the pyramid of `layout` and identity `pyramid`.
    pub fn open(path: &Path, layout: &NodeLayout, pyramid: u32) -> Result<MapFile, MeshesError> {
        let file = MapFile::open_part(path, layout)?;
        if file.info.pyramid != pyramid {
            let problem = "built for another pyramid (or an earlier import)".into();
            return Err(MeshesError::Corrupt { path: path.to_path_buf(), problem });
        }
        Ok(file)
    }

    /// Opens a map file or a shard's part of one, whatever its pyramid
    /// (its header's identity is the caller's to check).
    pub fn open_part(path: &Path, layout: &NodeLayout) -> Result<MapFile, MeshesError> {
        let io = |source| MeshesError::Io { path: path.to_path_buf(), source };
        let file = File::open(path).map_err(io)?;
        let map = map_file(&file).map_err(io)?;
        let corrupt = |problem: String| MeshesError::Corrupt { path: path.to_path_buf(), problem };
        let (info, table) = decode_header(&map, layout).map_err(corrupt)?;
        let nodes = layout.node_count();
        let end = table as u64 + nodes * ENTRY_LEN as u64;
        if (map.len() as u64) < end {
            return Err(corrupt(format!(
                "truncated: {} bytes, the table ends at {end}",
                map.len()
            )));
        }
        Ok(MapFile { path: path.to_path_buf(), map, info, table, nodes })
    }

    fn entry(&self, index: u64) -> Entry {
        let at = self.table + index as usize * ENTRY_LEN;
        Entry::decode(&self.map[at..at + ENTRY_LEN])
    }

    /// The heap, bytes, the largest map of the file takes once read.
    pub fn largest_map_bytes(&self) -> u64 {
        (0..self.nodes).map(|index| self.entry(index).heap_bytes()).max().unwrap_or(0)
    }

    /// The heap, bytes, node `id`'s map takes once read (0: none).
    pub fn map_bytes(&self, layout: &NodeLayout, id: NodeId) -> u64 {
        match layout.node_index(id) {
            Some(index) if index < self.nodes => self.entry(index).heap_bytes(),
            _ => 0,
        }
    }

    /// Bytes of the file.
    pub fn len(&self) -> u64 {
        self.map.len() as u64
    }

    /// Whether the file is empty (never: a header is there).
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// What the header says.
    pub fn info(&self) -> &StoreInfo {
        &self.info
    }

    /// The path the file was opened from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Checks every record against its entry (bounds and checksum), in
    /// parallel, naming the first damaged node found.
    pub fn verify(&self) -> Result<(), MeshesError> {
        for first in (0..self.nodes).step_by(RECORDS_PER_RELEASE) {
            let end = (first + RECORDS_PER_RELEASE as u64).min(self.nodes);
            let damaged = (first..end).into_par_iter().find_map_any(|index| {
                let entry = self.entry(index);
                let problem = entry.is_record().then(|| self.record(index, &entry).err()).flatten();
                problem.map(|problem| format!("node {index}: {problem}"))
            });
            self.release_pages();
            if let Some(problem) = damaged {
                return Err(MeshesError::Corrupt { path: self.path.clone(), problem });
            }
        }
        Ok(())
    }

    /// Drops the map's resident pages (MADV_DONTNEED): reading a whole
    /// file (a verify, a merge's copy) would otherwise keep all of it
    /// mapped, and a merge of 64 tiles' parts reads 2 GB of them.
    pub fn release_pages(&self) {
        crate::pyramid::release_map_pages(&self.map);
    }

    /// Whether every stored node has its map (not a shard's part).
    pub fn is_complete(&self) -> bool {
        (0..self.nodes).all(|index| self.entry(index).offset != NOT_BUILT)
    }

    /// Reads node `id`'s map into `out`; a map that stores no heights
    /// takes them from `source` (the pyramid the file belongs to). A
    /// damaged record is [`NodeError::Corrupt`] and leaves `out` as it was.
    /// A node absent from the pyramid is [`NodeError::Absent`].
    pub fn read(
        &self,
        source: &dyn NodeSource,
        id: NodeId,
        out: &mut ErrorMap,
    ) -> Result<(), NodeError> {
        let layout = source.layout();
        let index = layout.node_index(id).ok_or(NodeError::OutOfRange { id })?;
        let corrupt = |problem: String| NodeError::Corrupt { path: self.path.clone(), id, problem };
        let entry = self.entry(index);
        match entry.offset {
            ABSENT => return Err(NodeError::Absent { id }),
            NOT_BUILT => {
                return Err(corrupt("the map file lacks this node (a shard's part)".into()))
            }
            _ => {}
        }
        let record = self.record(index, &entry).map_err(corrupt)?;
        // Decoded apart, so a damaged record leaves `out` as it was; the
        // buffers are exactly the node's size (what the budget plans).
        let mut decoded = ErrorMap::default();
        decode_record(source, id, record, &entry, &mut decoded).map_err(|e| match e {
            NodeError::Corrupt { problem, .. } => corrupt(problem),
            other => other,
        })?;
        *out = decoded;
        Ok(())
    }

    /// Record `index`'s bytes, checked against its entry.
    fn record(&self, index: u64, entry: &Entry) -> Result<&[u8], String> {
        let end =
            entry.offset.checked_add(entry.len as u64).filter(|&e| e <= self.map.len() as u64);
        let Some(end) = end else {
            return Err(format!("map record past the end of the file ({entry:?})"));
        };
        let record = &self.map[entry.offset as usize..end as usize];
        if record.len() < record::RECORD_HEAD || record_crc(index, record) != entry.crc {
            return Err("map record checksum mismatch".into());
        }
        Ok(record)
    }
}

/// Merges shards' parts of one map file (built for the same pyramid, each
/// node by exactly one part) into `out`, atomically: the same bytes a
/// single process writes for the same nodes.
pub fn merge_stores(
    parts: &[PathBuf],
    layout: &NodeLayout,
    out: &Path,
) -> Result<StoreInfo, MeshesError> {
    let files: Vec<MapFile> =
        parts.iter().map(|p| MapFile::open_part(p, layout)).collect::<Result<_, _>>()?;
    let Some(first) = files.first() else {
        return Err(MeshesError::Options("no map file parts to merge".into()));
    };
    let pyramid = first.info.pyramid;
    if let Some(other) = files.iter().find(|f| f.info.pyramid != pyramid) {
        let problem = format!("built for another pyramid than {}", parts[0].display());
        return Err(MeshesError::Corrupt { path: other.path.clone(), problem });
    }
    merge_parts(&files, layout, pyramid, out)
}

/// Merges opened parts of one map file (built with the same options, each
/// node by exactly one part, their identities checked by the caller) into
/// `out`, atomically, for the pyramid of identity `pyramid`: the same
/// bytes a single process writes for the same nodes.
pub fn merge_parts(
    files: &[MapFile],
    layout: &NodeLayout,
    pyramid: u32,
    out: &Path,
) -> Result<StoreInfo, MeshesError> {
    let Some(first) = files.first() else {
        return Err(MeshesError::Options("no map file parts to merge".into()));
    };
    let mut info = StoreInfo { pyramid, ..first.info.clone() };
    for file in &files[1..] {
        if file.info.options != info.options {
            let problem = format!("built with other options than {}", first.path.display());
            return Err(MeshesError::Corrupt { path: file.path.clone(), problem });
        }
        for l in 0..info.floor_per_level.len() {
            info.floor_per_level[l] = info.floor_per_level[l].max(file.info.floor_per_level[l]);
            info.reference_delta_per_level[l] =
                info.reference_delta_per_level[l].max(file.info.reference_delta_per_level[l]);
            info.max_error_per_level[l] =
                info.max_error_per_level[l].max(file.info.max_error_per_level[l]);
        }
    }
    let io = |path: &Path, source| MeshesError::Io { path: path.to_path_buf(), source };
    replace_file(
        out,
        |temporary| {
            let file = File::create(temporary).map_err(|e| io(temporary, e))?;
            let mut writer = StoreWriter::new(file, layout);
            writer.start(&info).map_err(|e| io(temporary, e))?;
            let mut table = vec![Entry::ABSENT; layout.node_count() as usize];
            let mut ids = all_nodes(layout);
            record_order(layout, info.options.depth, &mut ids);
            for (k, id) in ids.into_iter().enumerate() {
                let index = layout.node_index(id).expect("a node of the layout");
                table[index as usize] = merged_entry(files, index, &mut writer)
                    .map_err(|e| e.into_meshes_error(temporary))?;
                if k % RECORDS_PER_RELEASE == RECORDS_PER_RELEASE - 1 {
                    files.iter().for_each(MapFile::release_pages);
                }
            }
            writer.finish(&info, &table).map_err(|e| io(temporary, e))
        },
        io,
    )?;
    Ok(info)
}

/// Why a merge failed at one node.
enum MergeError {
    Io(std::io::Error),
    Part { path: PathBuf, problem: String },
}

impl MergeError {
    fn into_meshes_error(self, temporary: &Path) -> MeshesError {
        match self {
            MergeError::Io(source) => MeshesError::Io { path: temporary.to_path_buf(), source },
            MergeError::Part { path, problem } => MeshesError::Corrupt { path, problem },
        }
    }
}

/// Node `index`'s entry in the merge: copied from the one part that built
/// it (its record checked on the way), absent if the pyramid lacks it.
fn merged_entry(
    files: &[MapFile],
    index: u64,
    writer: &mut StoreWriter,
) -> Result<Entry, MergeError> {
    let mut found: Option<(&MapFile, Entry)> = None;
    let mut absent = false;
    for file in files {
        let entry = file.entry(index);
        match entry.offset {
            ABSENT => absent = true,
            NOT_BUILT => {}
            _ if found.is_some() => {
                let problem = format!("node {index} is built by two parts");
                return Err(MergeError::Part { path: file.path.clone(), problem });
            }
            _ => found = Some((file, entry)),
        }
    }
    match found {
        Some((file, entry)) => {
            let bytes = file
                .record(index, &entry)
                .map_err(|problem| MergeError::Part { path: file.path.clone(), problem })?;
            writer.append_bytes(bytes, entry).map_err(MergeError::Io)
        }
        None if absent => Ok(Entry::ABSENT),
        None => {
            let path = files[0].path.clone();
            Err(MergeError::Part { path, problem: format!("no part built node {index}") })
        }
    }
}

/// Records read between two releases of a map's pages.
const RECORDS_PER_RELEASE: usize = 512;

#[allow(unsafe_code)]
fn map_file(file: &File) -> std::io::Result<Mmap> {
    // SAFETY: as for the pyramid (see `pyramid::open::map_file`): the file
    // is only ever replaced by rename, never written in place by us; every
    // record read checks its checksum, so a foreign writer surfaces as
    // NodeError::Corrupt; no slice of the map outlives the call that made it.
    unsafe { Mmap::map(file) }
}
