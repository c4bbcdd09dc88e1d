//! Node meshes for every tau and viewport (Ulrich's chunks on Polok's
//! buffers; issues 11, 21 and 22): every node a pyramid stores gets the
//! error map of the best data under it, built once beside the pyramid
//! (`meshes.rlm`), read with the node by the loader, and cut into tiles'
//! meshes at the error the tile's ring allows for the viewport and tau
//! (`crate::tiles::extract`), drawn from vertex buffers (no texture reads).
//!
//! Why: a regular grid of level `l` subsamples every `2^l`-th post, and on
//! rugged data its error is large from the first coarse level on (99.5 m
//! at level 1 on the built-in SRTM tile), so the error bound keeps level 0
//! out to 157 km at tau 1 px. A mesh may take any post of the data under
//! the node, and needs 3 to 19 times fewer triangles for the same error.
//! One map serves any error: no file per tau, and the same triangles a
//! 1920-pixel display needs are not drawn on a 320-pixel one.
//!
//! | module | owns |
//! |---|---|
//! | [`mod@reference`] | the best data under a node on a finer level's lattice |
//! | [`mod@build`] | one node's error map |
//! | [`mod@block`] | maps a block at a time: one scan of the block's triangles for every node under it |
//! | [`mod@file`] | the map file: versioned, checksummed, memory-mapped, written atomically, built streaming and in shards |
//! | [`mod@pagein`] | page-in of a map that stores no heights: its keys' heights and normals straight from the pyramid's nodes |
//! | [`mod@record`] | one node's record in the map file: compact keys, quantised or no heights |
//! | [`mod@source`] | [`MeshedSource`]: a pyramid whose nodes come with their maps |
//! | [`mod@shards`] | a dataset built by N shards and merged: their parts, the merge |

pub mod block;
pub mod build;
pub mod file;
pub mod pagein;
pub mod record;
pub mod reference;
pub mod shards;
pub mod source;

pub use block::build_map_shared;
pub use build::build_map;
pub use file::{
    build_store, merge_parts, merge_stores, pyramid_identity, MapFile, StoreInfo, MAP_FILE_NAME,
};
pub use source::MeshedSource;

use crate::mesh::MeshError;
use crate::node::{NodeError, NodeId, NodeLayout};

/// How the maps are built.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeshOptions {
    /// How many levels finer than the node its reference lattice may be:
    /// the map of a node of level `l` takes posts of level
    /// `l - min(l, depth)`. With 64-cell nodes, 5 gives at most 2049^2 posts.
    pub depth: u8,
    /// Every mesh of a node splits at least to squares of this many node
    /// posts, so tiles of that size or larger cut whole triangles.
    pub tile_cells: u32,
    /// The largest K / tau (pixels) the maps serve at the rings' floor:
    /// a sparse map keeps the splits a mesh of level `l` needs down to
    /// [`MeshOptions::floor_m`]; a finer view widens its rings instead.
    pub finest_view_px: f64,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions { depth: DEPTH, tile_cells: 8, finest_view_px: FINEST_VIEW_PX }
    }
}

/// The default [`MeshOptions::depth`]: 2049^2 posts a side with 64-cell
/// nodes.
pub const DEPTH: u8 = 5;

// A share square coarser than the depth is built on a coarser lattice than
// level 0's maps, which then share none of its edges (`block::share_square`).
const _: () = assert!(crate::node::SHARE_LEVEL <= DEPTH, "share squares within the depth");

/// The K / tau the maps are built for: 2000 pixels (a 1920-pixel display
/// over 51 degrees at tau 1, or 1280 pixels over 60 degrees at tau 0.55).
pub const FINEST_VIEW_PX: f64 = 2000.0;

impl MeshOptions {
    /// The smallest error a sparse map of `level` serves, metres: a tile
    /// (half a node) at three tile sizes, the nearest its ring puts it,
    /// with the morph's 30 % kept back, seen with K / tau
    /// `finest_view_px`: `0.7 * 3 * node / 2 / finest_view_px`.
    pub fn floor_m(&self, layout: &NodeLayout, level: u8) -> f64 {
        let [x, y] = layout.node_size_m(level);
        0.7 * 3.0 * x.max(y) / 2.0 / self.finest_view_px
    }

    /// Checks the options against a pyramid's layout.
    pub fn validate(&self, layout: &NodeLayout) -> Result<(), MeshesError> {
        let fail = |why: String| Err(MeshesError::Options(why));
        if !(self.finest_view_px.is_finite() && self.finest_view_px > 0.0) {
            return fail(format!("finest view {} px must be above 0", self.finest_view_px));
        }
        let posts = (layout.node_size as u64) << self.depth;
        if self.depth > 10 || posts > 1 << 15 {
            return fail(format!(
                "mesh depth {} with {}-cell nodes gives {posts} posts a side; at most 32768",
                self.depth, layout.node_size
            ));
        }
        let t = self.tile_cells;
        if !t.is_power_of_two() || t < 2 || t > layout.node_size {
            return fail(format!(
                "mesh tile of {t} cells must be a power of two between 2 and the node size {}",
                layout.node_size
            ));
        }
        Ok(())
    }
}

/// Why meshes cannot be built, written or read.
#[derive(Debug, thiserror::Error)]
pub enum MeshesError {
    /// The options do not fit the pyramid.
    #[error("mesh options: {0}")]
    Options(String),
    /// A node's reference grid or mesh was refused.
    #[error("node {id:?}: {source}")]
    Mesh {
        /// The node.
        id: NodeId,
        /// Why.
        source: MeshError,
    },
    /// Reading the pyramid failed.
    #[error(transparent)]
    Node(#[from] NodeError),
    /// The mesh file is damaged, truncated, of another version, or was
    /// built for another pyramid.
    #[error("{path}: {problem}")]
    Corrupt {
        /// The mesh file.
        path: std::path::PathBuf,
        /// What the check found.
        problem: String,
    },
    /// Reading or writing the mesh file failed.
    #[error("{path}: {source}")]
    Io {
        /// The mesh file.
        path: std::path::PathBuf,
        /// The I/O failure.
        source: std::io::Error,
    },
}
