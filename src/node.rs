//! The node pyramid's vocabulary, shared by the pyramid on disk, the procedural
//! source and the chunked clipmap: which node is which, how big nodes are, and
//! what a loaded node holds (Kühnert 4.5.3 and 4.5.6, Ulrich section 10).
//!
//! Level 0 is the finest; a node of level `lod` spans `node_size << lod`
//! level-0 sample spacings per side (Kühnert eq. 4.8). Node `(x, y)` of level
//! `lod` covers level-0 samples `[x * span, (x + 1) * span]` east and
//! `[y * span, (y + 1) * span]` north, `span = node_size << lod`, sampled every
//! `1 << lod` samples: `node_size + 1` posts per side, so neighbours share their
//! edge posts. A border of `border` posts on every side repeats the
//! neighbours' posts (extended at the edge of the data) for normals and
//! seamless sampling.

/// Names one node of the pyramid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct NodeId {
    pub lod: u8,
    pub x: u32,
    pub y: u32,
}

impl NodeId {
    pub fn new(lod: u8, x: u32, y: u32) -> Self {
        NodeId { lod, x, y }
    }

    /// The node one level coarser that contains this one.
    pub fn parent(self) -> Option<NodeId> {
        (self.lod < u8::MAX).then(|| NodeId::new(self.lod + 1, self.x / 2, self.y / 2))
    }
}

/// Sizes shared by every node of one pyramid.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct NodeLayout {
    /// Number of levels (`lod_count`); level `levels - 1` is the root level.
    pub levels: u8,
    /// Cells per node side at every level (posts per side: `node_size + 1`).
    pub node_size: u32,
    /// Extra posts stored on each side of a node.
    pub border: u32,
    /// Level-0 samples of the data, east and north.
    pub samples: [u32; 2],
    /// Metres between level-0 samples, east and north, in the local frame.
    pub spacing_m: [f64; 2],
}

impl NodeLayout {
    /// Posts per stored node side, border included.
    pub fn stored_side(&self) -> u32 {
        self.node_size + 1 + 2 * self.border
    }

    /// Nodes per side at `lod`, east and north (covering every sample).
    pub fn nodes_at(&self, lod: u8) -> [u32; 2] {
        let span = (self.node_size as u64) << lod;
        let count = |samples: u32| (samples.saturating_sub(1) as u64).div_ceil(span).max(1) as u32;
        [count(self.samples[0]), count(self.samples[1])]
    }

    /// Level-0 sample spacings spanned by one node of `lod` (Kühnert eq. 4.8).
    pub fn span(&self, lod: u8) -> u64 {
        (self.node_size as u64) << lod
    }

    /// Levels needed so that the root level is a single node covering every
    /// sample: level `l` exists while level `l - 1` still needs more than one
    /// node per side.
    pub fn levels_for(samples: [u32; 2], node_size: u32) -> u8 {
        debug_assert!(node_size > 0, "a node has at least one cell per side");
        let node_size = node_size.max(1) as u64;
        let cells = samples[0].max(samples[1]).saturating_sub(1) as u64;
        let mut levels = 1u8;
        while (node_size << (levels - 1)) < cells {
            levels += 1;
        }
        levels
    }

    /// Nodes in the whole pyramid.
    pub fn node_count(&self) -> u64 {
        (0..self.levels).map(|lod| self.nodes_at_count(lod)).sum()
    }

    /// Nodes at one level.
    pub fn nodes_at_count(&self, lod: u8) -> u64 {
        let [x, y] = self.nodes_at(lod);
        x as u64 * y as u64
    }

    /// Whether `id` names a node of this pyramid.
    pub fn contains(&self, id: NodeId) -> bool {
        if id.lod >= self.levels {
            return false;
        }
        let [x, y] = self.nodes_at(id.lod);
        id.x < x && id.y < y
    }

    /// The position of `id` when nodes are listed level by level (finest
    /// first), row by row (south first) within a level.
    pub fn node_index(&self, id: NodeId) -> Option<u64> {
        if !self.contains(id) {
            return None;
        }
        let before: u64 = (0..id.lod).map(|lod| self.nodes_at_count(lod)).sum();
        let [x_count, _] = self.nodes_at(id.lod);
        Some(before + id.y as u64 * x_count as u64 + id.x as u64)
    }
}

/// A node's stored content.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeData {
    /// `stored_side^2` heights in metres, row 0 southern, border included.
    pub heights: Vec<f32>,
    /// Lowest and highest height of the node's centre posts.
    pub min: f32,
    pub max: f32,
    /// Ulrich's delta: the largest vertical distance, in metres, between the
    /// node's surface (posts joined as triangles, each cell split from its
    /// south-west to its north-east corner) and the level-0 samples it covers.
    pub delta: f32,
}

/// Anything that can produce nodes: the memory-mapped pyramid, the procedural
/// earth. Called from the loader thread.
pub trait NodeSource: Send + Sync {
    fn layout(&self) -> &NodeLayout;
    /// Writes node `id` into `out`, reusing its buffers.
    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError>;
}

/// Why a node could not be produced.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    #[error("node {id:?} is outside the pyramid")]
    OutOfRange { id: NodeId },
    #[error("{path}: node {id:?}: {problem}")]
    Corrupt { path: std::path::PathBuf, id: NodeId, problem: String },
    #[error("{path}: {source}")]
    Io { path: std::path::PathBuf, source: std::io::Error },
}
