//! An opened pyramid: the file memory-mapped and its header checked, nodes
//! served to the loader as a [`NodeSource`] and checked as they are paged in,
//! and exact heights read from the full-resolution level.
//!
//! Opening reads only the header (its size grows with the node count, 20
//! bytes a node, about 0.1 % of the file), so it costs about the same for a
//! 1 MB and a 10 GB pyramid. Each node's checksum is checked when the node is
//! read ([`NodeSource::read_node`]); [`Pyramid::verify`] checks every node at
//! once, for `ridgeline info` and anyone who wants a damaged file refused
//! before anything is drawn.

use std::fs::File;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};

use memmap2::Mmap;
use rayon::prelude::*;

use super::bytes::f32s_from_le;
use super::error::PyramidError;
use super::format::{check_record, decode_header, NodeSummary, PyramidInfo, FILE_NAME};
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// A level-0 node [`Pyramid::exact_height`] has not checked yet.
const UNCHECKED: u8 = 0;
/// A level-0 node whose record passed its check.
const INTACT: u8 = 1;
/// A level-0 node whose record failed its check.
const DAMAGED: u8 = 2;

/// A memory-mapped pyramid file whose header has been checked; nodes are
/// checked as they are read.
pub struct Pyramid {
    path: PathBuf,
    /// Kept open to notice the file shrinking under the map.
    file: File,
    map: Mmap,
    info: PyramidInfo,
    /// Node summaries in file order ([`NodeLayout::node_index`]).
    nodes: Vec<NodeSummary>,
    header_len: u64,
    record_len: u64,
    /// Per level-0 node, whether [`Pyramid::exact_height`] found its record
    /// intact ([`UNCHECKED`], [`INTACT`], [`DAMAGED`]): it reads a few posts
    /// per call, too few to pay for a whole record's checksum each time.
    level0_checked: Vec<AtomicU8>,
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
        let level0 = header.info.layout.nodes_at_count(0) as usize;
        Ok(Pyramid {
            path,
            file,
            map,
            info: header.info,
            nodes: header.nodes,
            header_len: header.header_len,
            record_len: header.record_len,
            level0_checked: (0..level0).map(|_| AtomicU8::new(UNCHECKED)).collect(),
        })
    }

    /// Checks every node's checksum, in parallel (CRC-32 runs at several
    /// GB/s), and reports the first damaged node found, by id and file.
    pub fn verify(&self) -> Result<(), PyramidError> {
        self.check_length().map_err(|problem| PyramidError::corrupt(&self.path, problem))?;
        let damaged = (0..self.nodes.len() as u64).into_par_iter().find_map_any(|index| {
            check_record(self.record(index), &self.nodes[index as usize])
                .err()
                .map(|problem| (index, problem))
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

    /// Min, max and delta of node `id` without reading its heights.
    pub fn node_summary(&self, id: NodeId) -> Option<NodeSummary> {
        self.info.layout.node_index(id).map(|index| self.nodes[index as usize])
    }

    /// The bytes of the file holding node `id`'s record (its heights, min,
    /// max, delta and checksum), `None` for a node outside the pyramid.
    pub fn record_range(&self, id: NodeId) -> Option<Range<u64>> {
        let index = self.info.layout.node_index(id)?;
        let start = self.header_len + index * self.record_len;
        Some(start..start + self.record_len)
    }

    /// The full-resolution height at `(x_m, y_m)` in the local frame, read
    /// from level 0 and interpolated on the south-west to north-east
    /// triangles of its cell. Positions outside the data take the height at
    /// the nearest edge (the pyramid's clamping rule); `None` for a
    /// non-finite position, or where a level-0 node holding the cell's posts
    /// fails its checksum (each level-0 node is checked the first time a
    /// height is read from it, not on every call).
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
        let (i, fu) = cell_of(x_m / layout.spacing_m[0], layout.posts[0]);
        let (j, fv) = cell_of(y_m / layout.spacing_m[1], layout.posts[1]);
        let (i1, j1) = ((i + 1).min(layout.posts[0] - 1), (j + 1).min(layout.posts[1] - 1));
        let h = |i, j| self.sample(i, j).map(|h| h as f64);
        let surface = crate::node::cell_surface(h(i, j)?, h(i1, j)?, h(i, j1)?, h(i1, j1)?, fu, fv);
        Ok(surface as f32)
    }

    /// Level-0 sample `(i, j)`, read from the level-0 node that holds it
    /// once that node's record has been found intact.
    fn sample(&self, i: u32, j: u32) -> Result<f32, NodeError> {
        let layout = &self.info.layout;
        let [nodes_x, nodes_y] = layout.nodes_at(0);
        let (x, y) =
            ((i / layout.node_size).min(nodes_x - 1), (j / layout.node_size).min(nodes_y - 1));
        let (p, q) =
            (i - x * layout.node_size + layout.border, j - y * layout.node_size + layout.border);
        let id = NodeId::new(0, x, y);
        let index = layout.node_index(id).expect("the node of a sample exists");
        self.check_level0(id, index)?;
        let post = q as u64 * layout.stored_side() as u64 + p as u64;
        let at = (self.header_len + index * self.record_len + 4 * post) as usize;
        // In bounds: the header check tied every record to the file's length.
        Ok(f32::from_le_bytes(self.map[at..at + 4].try_into().expect("4 bytes")))
    }

    /// Checks level-0 node `id` (at `index`) the first time it is asked for,
    /// and remembers the answer.
    fn check_level0(&self, id: NodeId, index: u64) -> Result<(), NodeError> {
        let state = &self.level0_checked[index as usize];
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
    fn checked_record(&self, id: NodeId, index: u64) -> Result<&[u8], NodeError> {
        self.check_length().map_err(|problem| NodeError::Io {
            path: self.path.clone(),
            source: std::io::Error::new(std::io::ErrorKind::UnexpectedEof, problem),
        })?;
        check_record(self.record(index), &self.nodes[index as usize])
            .map_err(|problem| self.corrupt(id, problem))
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

    /// The bytes of record `index`.
    fn record(&self, index: u64) -> &[u8] {
        let start = (self.header_len + index * self.record_len) as usize;
        &self.map[start..start + self.record_len as usize]
    }
}

/// The sample column (or row) whose cell holds `position` samples from the
/// origin, and the fraction across it; positions outside `0..=samples - 1`
/// clamp to the edge.
fn cell_of(position: f64, samples: u32) -> (u32, f64) {
    let last = (samples - 1) as f64;
    let position = position.clamp(0.0, last);
    let cell = (position.floor() as u32).min(samples.saturating_sub(2));
    (cell, position - cell as f64)
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

    /// Reads node `id` after checking its record's checksum: the check at
    /// page-in that [`Pyramid::open`] leaves to each node. A damaged record
    /// is [`NodeError::Corrupt`], naming the file and the node; `out` is
    /// then left as it was.
    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        let index = self.info.layout.node_index(id).ok_or(NodeError::OutOfRange { id })?;
        let summary = self.nodes[index as usize];
        let heights = self.checked_record(id, index)?;
        f32s_from_le(heights, &mut out.heights);
        out.min = summary.min;
        out.max = summary.max;
        out.delta = summary.delta;
        Ok(())
    }
}
