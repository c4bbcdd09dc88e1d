//! An opened pyramid: the file memory-mapped, its header and every node
//! checked, nodes served to the loader as a [`NodeSource`], and exact heights
//! read from the full-resolution level.

use std::fs::File;
use std::path::{Path, PathBuf};

use memmap2::Mmap;
use rayon::prelude::*;

use super::bytes::f32s_from_le;
use super::error::PyramidError;
use super::format::{check_record, decode_header, NodeSummary, PyramidInfo, FILE_NAME};
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// A verified, memory-mapped pyramid file.
pub struct Pyramid {
    path: PathBuf,
    map: Mmap,
    info: PyramidInfo,
    /// Node summaries in file order ([`NodeLayout::node_index`]).
    nodes: Vec<NodeSummary>,
    header_len: u64,
    record_len: u64,
}

impl Pyramid {
    /// Opens `path`, a pyramid file or a cache directory holding
    /// [`FILE_NAME`], and verifies the header and every node's checksum, so a
    /// damaged file is refused here, before anything is drawn.
    pub fn open(path: impl AsRef<Path>) -> Result<Pyramid, PyramidError> {
        let path = Self::file_in(path.as_ref());
        let file = File::open(&path).map_err(PyramidError::io(&path))?;
        let map = map_file(&file).map_err(PyramidError::io(&path))?;
        let header = decode_header(&path, &map)?;
        let pyramid = Pyramid {
            path,
            map,
            info: header.info,
            nodes: header.nodes,
            header_len: header.header_len,
            record_len: header.record_len,
        };
        pyramid.verify_nodes()?;
        Ok(pyramid)
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

    pub fn path(&self) -> &Path {
        &self.path
    }

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

    /// The full-resolution height at `(x_m, y_m)` in the local frame, read
    /// from level 0 and interpolated on the south-west to north-east
    /// triangles of its cell. Positions outside the data take the height at
    /// the nearest edge (the pyramid's clamping rule); `None` for a
    /// non-finite position.
    pub fn exact_height(&self, x_m: f64, y_m: f64) -> Option<f32> {
        if !(x_m.is_finite() && y_m.is_finite()) {
            return None;
        }
        let layout = &self.info.layout;
        let (i, fu) = cell_of(x_m / layout.spacing_m[0], layout.posts[0]);
        let (j, fv) = cell_of(y_m / layout.spacing_m[1], layout.posts[1]);
        let (i1, j1) = ((i + 1).min(layout.posts[0] - 1), (j + 1).min(layout.posts[1] - 1));
        let h = |i, j| self.sample(i, j) as f64;
        let surface = crate::node::cell_surface(h(i, j), h(i1, j), h(i, j1), h(i1, j1), fu, fv);
        Some(surface as f32)
    }

    /// Level-0 sample `(i, j)`, read from the level-0 node that holds it.
    fn sample(&self, i: u32, j: u32) -> f32 {
        let layout = &self.info.layout;
        let [nodes_x, nodes_y] = layout.nodes_at(0);
        let (x, y) =
            ((i / layout.node_size).min(nodes_x - 1), (j / layout.node_size).min(nodes_y - 1));
        let (p, q) =
            (i - x * layout.node_size + layout.border, j - y * layout.node_size + layout.border);
        let index = layout.node_index(NodeId::new(0, x, y)).expect("the node of a sample exists");
        let post = q as u64 * layout.stored_side() as u64 + p as u64;
        let at = (self.header_len + index * self.record_len + 4 * post) as usize;
        // In bounds: the header check tied every record to the file's length.
        f32::from_le_bytes(self.map[at..at + 4].try_into().expect("4 bytes"))
    }

    /// The bytes of record `index`.
    fn record(&self, index: u64) -> &[u8] {
        let start = (self.header_len + index * self.record_len) as usize;
        &self.map[start..start + self.record_len as usize]
    }

    /// Checks every node's checksum, in parallel; the first damaged node
    /// found is reported.
    fn verify_nodes(&self) -> Result<(), PyramidError> {
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
    // unchanged inode. A foreign program writing into the file could still
    // change bytes under us; every node read re-checks its checksum, so such a
    // change surfaces as NodeError::Corrupt rather than as drawn garbage.
    unsafe { Mmap::map(file) }
}

impl NodeSource for Pyramid {
    fn layout(&self) -> &NodeLayout {
        &self.info.layout
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        let index = self.info.layout.node_index(id).ok_or(NodeError::OutOfRange { id })?;
        let summary = self.nodes[index as usize];
        let heights = check_record(self.record(index), &summary)
            .map_err(|problem| NodeError::Corrupt { path: self.path.clone(), id, problem })?;
        f32s_from_le(heights, &mut out.heights);
        out.min = summary.min;
        out.max = summary.max;
        out.delta = summary.delta;
        Ok(())
    }
}
