//! An opened pyramid: the file memory-mapped and its header checked, nodes
//! served to the loader as a [`NodeSource`] and checked as they are paged in,
//! and exact heights read from the full-resolution level.
//!
//! Opening reads only the header (its size grows with the node count, 20
//! bytes a node, about 0.1 % of the file), so it costs about the same for a
//! 1 MB and a 10 GB pyramid. Each node's checksum is checked when the node is
//! read ([`NodeSource::read_node`]); [`Pyramid::verify`] checks every node at
//! once, for `ridgeline info` and anyone who wants a damaged file refused
//! before anything is drawn. Absent nodes (no data of their resolution
//! there) have no record: [`NodeSource::has_node`] says so, and exact heights
//! come from the finest present node at each place.

use std::fs::File;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};

use memmap2::Mmap;
use rayon::prelude::*;

use super::bytes::f32s_from_le;
use super::error::PyramidError;
use super::format::{check_record, decode_header, NodeSummary, NodeTable, PyramidInfo, FILE_NAME};
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// A node [`Pyramid::exact_height`] has not checked yet.
const UNCHECKED: u8 = 0;
/// A node whose record passed its check.
const INTACT: u8 = 1;
/// A node whose record failed its check.
const DAMAGED: u8 = 2;

/// A node whose table entry [`Pyramid::is_present`] has not read yet.
const UNREAD: u8 = 0;
/// A node whose table entry says absent.
const ABSENT_NODE: u8 = 1;
/// A node whose table entry says present (or fails its check: reading the
/// node then reports the damage).
const STORED_NODE: u8 = 2;

/// A memory-mapped pyramid file whose header has been checked; nodes are
/// checked as they are read.
pub struct Pyramid {
    path: PathBuf,
    /// Kept open to notice the file shrinking under the map.
    file: File,
    map: Mmap,
    info: PyramidInfo,
    /// The node table, read one entry at a time from the map.
    table: NodeTable,
    /// Per node, whether [`Pyramid::exact_height`] found its record intact
    /// ([`UNCHECKED`], [`INTACT`], [`DAMAGED`]): it reads a few posts per
    /// call, too few to pay for a whole record's checksum each time.
    checked: Vec<AtomicU8>,
    /// Per node, what its table entry said the first time
    /// [`Pyramid::is_present`] read it ([`UNREAD`], [`ABSENT_NODE`],
    /// [`STORED_NODE`]): the clipmap and the LOD ask every frame, and the
    /// entry's checksum need not be recomputed for each question.
    presence: Vec<AtomicU8>,
}

impl Pyramid {
    /// Opens `path`, a pyramid file or a cache directory holding
    /// [`FILE_NAME`], and checks the header (its checksum covers the node
    /// table). Node records are not touched: each is checked when it is read,
    /// so opening costs the same whatever the file's size. Call
    /// [`Pyramid::verify`] to check every node now.
    pub fn open(path: impl AsRef<Path>) -> Result<Pyramid, PyramidError> {
        let path = Self::file_in(path.as_ref());
        let file = File::open(&path).map_err(PyramidError::io(&path))?;
        let map = map_file(&file).map_err(PyramidError::io(&path))?;
        let header = decode_header(&path, &map)?;
        let count = header.table.count;
        Ok(Pyramid {
            path,
            file,
            map,
            info: header.info,
            table: header.table,
            checked: (0..count).map(|_| AtomicU8::new(UNCHECKED)).collect(),
            presence: (0..count).map(|_| AtomicU8::new(UNREAD)).collect(),
        })
    }

    /// Checks every node's checksum, in parallel (CRC-32 runs at several
    /// GB/s), and reports the first damaged node found, by id and file.
    pub fn verify(&self) -> Result<(), PyramidError> {
        self.check_length().map_err(|problem| PyramidError::corrupt(&self.path, problem))?;
        let nodes = self
            .table
            .all_entries(&self.map, &self.info.layout, &self.info.levels)
            .map_err(|problem| PyramidError::corrupt(&self.path, problem))?;
        let damaged = (0..nodes.len() as u64).into_par_iter().find_map_any(|index| {
            let (offset, summary) = nodes[index as usize]?;
            let record = self.record(offset);
            check_record(index, record, &summary).err().map(|problem| (index, problem))
        });
        match damaged {
            None => Ok(()),
            Some((index, problem)) => {
                let id = node_at(&self.info.layout, index);
                Err(PyramidError::corrupt(&self.path, format!("node {id:?}: {problem}")))
            }
        }
    }

    /// The pyramid file named by `path`: `path` itself, or `path/FILE_NAME`
    /// when `path` is a directory.
    pub fn file_in(path: &Path) -> PathBuf {
        if path.is_dir() {
            path.join(FILE_NAME)
        } else {
            path.to_path_buf()
        }
    }

    /// The pyramid file (not its directory).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// What the header says.
    pub fn info(&self) -> &PyramidInfo {
        &self.info
    }

    /// Bytes of the file.
    pub fn file_len(&self) -> u64 {
        self.map.len() as u64
    }

    /// Min, max and delta of node `id` without reading its heights; `None`
    /// for a node outside the pyramid or absent.
    pub fn node_summary(&self, id: NodeId) -> Option<NodeSummary> {
        self.entry(id).ok().flatten().map(|(_, summary)| summary)
    }

    /// Whether node `id` is stored (inside the pyramid and not absent). A
    /// node whose table entry fails its check counts as stored: reading it
    /// reports the damage, and its ancestor serves.
    pub fn is_present(&self, id: NodeId) -> bool {
        let Some(index) = self.info.layout.node_index(id) else { return false };
        let state = &self.presence[index as usize];
        let known = match state.load(Ordering::Relaxed) {
            UNREAD => {
                let stored = !matches!(self.table.entry(&self.map, index), Ok(None));
                let known = if stored { STORED_NODE } else { ABSENT_NODE };
                state.store(known, Ordering::Relaxed);
                known
            }
            known => known,
        };
        known == STORED_NODE
    }

    /// Node `id`'s table entry, checked: its record's offset and summary,
    /// `None` when absent.
    fn entry(&self, id: NodeId) -> Result<Option<(u64, NodeSummary)>, String> {
        let index = self.info.layout.node_index(id).ok_or("outside the pyramid")?;
        self.table.entry(&self.map, index)
    }

    /// The bytes of the file holding node `id`'s record (its heights, min,
    /// max, delta and checksum), `None` for a node outside the pyramid or
    /// absent.
    pub fn record_range(&self, id: NodeId) -> Option<Range<u64>> {
        let (start, _) = self.entry(id).ok()??;
        Some(start..start + self.table.record_len)
    }

    /// The finest layer's area in the local frame: its south-west post and
    /// its extent east and north, metres (where the best data are; the
    /// built-in approach flies over it).
    pub fn finest_area_m(&self) -> ([f64; 2], [f64; 2]) {
        let layout = &self.info.layout;
        let window = self.info.finest;
        let at = |a: usize, posts: u32| posts as f64 * layout.spacing_m[a];
        (
            [at(0, window.first[0]), at(1, window.first[1])],
            [at(0, window.posts[0].saturating_sub(1)), at(1, window.posts[1].saturating_sub(1))],
        )
    }

    /// The height of the best data at `(x_m, y_m)` in the local frame: the
    /// finest present node there, interpolated on the south-west to
    /// north-east triangles of its cell. Positions outside the data take the
    /// height at the nearest edge (the pyramid's clamping rule); NaN where
    /// the best data have no data; `None` for a non-finite position, or
    /// where the node holding the cell's posts fails its checksum (each node
    /// is checked the first time a height is read from it, not on every
    /// call).
    pub fn exact_height(&self, x_m: f64, y_m: f64) -> Option<f32> {
        if !(x_m.is_finite() && y_m.is_finite()) {
            return None;
        }
        self.checked_exact_height(x_m, y_m).ok()
    }

    /// [`Pyramid::exact_height`] for a finite position, with the reason when
    /// a node is damaged.
    fn checked_exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        let layout = &self.info.layout;
        let [ex, ey] = layout.extent_m();
        let (x_m, y_m) = (x_m.clamp(0.0, ex), y_m.clamp(0.0, ey));
        for lod in 0..layout.levels {
            let Some(point) = layout.locate(lod, x_m, y_m) else { break };
            let Some(index) = layout.node_index(point.id) else { break };
            let entry =
                self.table.entry(&self.map, index).map_err(|p| self.corrupt(point.id, p))?;
            let Some((offset, _)) = entry else { continue };
            self.check_node(point.id, index)?;
            let last_cell = layout.node_size.saturating_sub(1);
            let cell = |p: f64| (p.max(0.0).floor() as u32).min(last_cell);
            let (i, j) = (cell(point.posts[0]), cell(point.posts[1]));
            let (fu, fv) = (point.posts[0] - i as f64, point.posts[1] - j as f64);
            let h = |i: u32, j: u32| self.post(offset, i, j) as f64;
            let surface = crate::node::cell_surface(
                h(i, j),
                h(i + 1, j),
                h(i, j + 1),
                h(i + 1, j + 1),
                fu,
                fv,
            );
            return Ok(surface as f32);
        }
        Err(NodeError::OutsideData { x_m, y_m })
    }

    /// Centre post `(i, j)` of the record at `offset`.
    fn post(&self, offset: u64, i: u32, j: u32) -> f32 {
        let layout = &self.info.layout;
        let (p, q) = (i + layout.border, j + layout.border);
        let post = q as u64 * layout.stored_side() as u64 + p as u64;
        let at = (offset + 4 * post) as usize;
        // In bounds: the header check tied every record to the file's length.
        f32::from_le_bytes(self.map[at..at + 4].try_into().expect("4 bytes"))
    }

    /// Checks node `id` (at `index`) the first time it is asked for, and
    /// remembers the answer.
    fn check_node(&self, id: NodeId, index: u64) -> Result<(), NodeError> {
        let state = &self.checked[index as usize];
        match state.load(Ordering::Acquire) {
            INTACT => Ok(()),
            DAMAGED => Err(self.corrupt(id, "failed its checksum earlier".into())),
            _ => {
                let checked = self.checked_record(id, index).map(|_| ());
                // A shrunk file is not remembered: it may be an I/O problem that passes.
                match &checked {
                    Ok(()) => state.store(INTACT, Ordering::Release),
                    Err(NodeError::Corrupt { .. }) => state.store(DAMAGED, Ordering::Release),
                    Err(_) => {}
                }
                checked
            }
        }
    }

    /// The heights bytes of node `id` (at `index`) once its record has
    /// passed its checksum and repeats the node table's summary.
    fn checked_record(&self, id: NodeId, index: u64) -> Result<(&[u8], NodeSummary), NodeError> {
        let entry = self.table.entry(&self.map, index).map_err(|p| self.corrupt(id, p))?;
        let (offset, summary) = entry.ok_or(NodeError::Absent { id })?;
        self.check_length().map_err(|problem| NodeError::Io {
            path: self.path.clone(),
            source: std::io::Error::new(std::io::ErrorKind::UnexpectedEof, problem),
        })?;
        let heights = check_record(index, self.record(offset), &summary)
            .map_err(|problem| self.corrupt(id, problem))?;
        Ok((heights, summary))
    }

    fn corrupt(&self, id: NodeId, problem: String) -> NodeError {
        NodeError::Corrupt { path: self.path.clone(), id, problem }
    }

    /// Whether the file still holds every mapped byte. Reading a mapped page
    /// beyond the end of a file that another program truncated would kill
    /// the process (SIGBUS), so every read of records asks first (one
    /// `fstat`); the window between the question and the read remains.
    fn check_length(&self) -> Result<(), String> {
        match self.file.metadata() {
            Ok(meta) if meta.len() >= self.map.len() as u64 => Ok(()),
            Ok(meta) => Err(format!(
                "the file shrank to {} bytes under its {} byte memory map",
                meta.len(),
                self.map.len()
            )),
            Err(error) => Err(format!("cannot read the file's length: {error}")),
        }
    }

    /// The bytes of the record at `offset`.
    fn record(&self, offset: u64) -> &[u8] {
        let start = offset as usize;
        &self.map[start..start + self.table.record_len as usize]
    }
}

/// The id of the node at position `index` in file order.
fn node_at(layout: &NodeLayout, mut index: u64) -> NodeId {
    for lod in 0..layout.levels {
        let count = layout.nodes_at_count(lod);
        if index < count {
            let x_count = layout.nodes_at(lod)[0] as u64;
            return NodeId::new(lod, (index % x_count) as u32, (index / x_count) as u32);
        }
        index -= count;
    }
    unreachable!("index beyond the node table")
}

/// Drops a read-only file map's resident pages (MADV_DONTNEED): the
/// pyramid's and the map file's.
#[cfg(unix)]
#[allow(unsafe_code)]
pub(crate) fn release_map_pages(map: &Mmap) {
    // SAFETY: the map is a read-only shared mapping of a file: DONTNEED
    // only unmaps its pages, and the next access reads the same bytes back
    // from the page cache or the file, so live slices into it stay valid.
    let _ = unsafe { map.unchecked_advise(memmap2::UncheckedAdvice::DontNeed) };
}

#[cfg(not(unix))]
pub(crate) fn release_map_pages(_map: &Mmap) {}

#[allow(unsafe_code)]
fn map_file(file: &File) -> std::io::Result<Mmap> {
    // SAFETY: the mapping is only read, and the file behind it is never
    // changed in place by Ridgeline: every writer builds a new file beside it
    // and renames it over the old one, which leaves this mapping on the old,
    // unchanged inode. The map is shared (memmap2 maps with MAP_SHARED), so a
    // foreign program writing into the file changes the bytes under us; every
    // node read checks its record's checksum, so such a change surfaces as
    // NodeError::Corrupt rather than as drawn garbage (tests/pyramid_corrupt.rs
    // does this). A foreign program truncating the file would make reads of
    // the lost pages fault (SIGBUS); record reads first check the file's
    // length (Pyramid::check_length), which narrows but cannot close that
    // window. No `&[u8]` into the map outlives the call that made it.
    unsafe { Mmap::map(file) }
}

impl NodeSource for Pyramid {
    fn layout(&self) -> &NodeLayout {
        &self.info.layout
    }

    fn release_pages(&self) {
        release_map_pages(&self.map);
    }

    fn has_node(&self, id: NodeId) -> bool {
        self.is_present(id)
    }

    /// The best data's height at a point inside the data (see
    /// [`Pyramid::exact_height`]); points outside are [`NodeError::OutsideData`].
    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        if self.info.layout.locate(0, x_m, y_m).is_none() {
            return Err(NodeError::OutsideData { x_m, y_m });
        }
        self.checked_exact_height(x_m, y_m)
    }

    /// Reads node `id` after checking its record's checksum: the check at
    /// page-in that [`Pyramid::open`] leaves to each node. A damaged record
    /// is [`NodeError::Corrupt`], naming the file and the node; `out` is
    /// then left as it was.
    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        let index = self.info.layout.node_index(id).ok_or(NodeError::OutOfRange { id })?;
        let (heights, summary) = self.checked_record(id, index)?;
        f32s_from_le(heights, &mut out.heights);
        out.min = summary.min;
        out.max = summary.max;
        out.delta = summary.delta;
        out.grid_delta = summary.delta;
        Ok(())
    }
}
