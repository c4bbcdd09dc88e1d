//! Node meshes (Ulrich's chunks on Polok's buffers, issue 11): every node a pyramid
//! stores gets an adaptive mesh of the best data under it, simplified to its
//! level's error, instead of the regular grid of its own posts. Built once
//! per error beside the pyramid (`meshes-12m.rlm`), read with each node by the loader, and
//! drawn by the tiles from vertex buffers (no texture reads).
//!
//! Why: a regular grid of level `l` subsamples every `2^l`-th post, and on
//! rugged data its error is large from the first coarse level on (99.5 m
//! at level 1 on the built-in SRTM tile), so the error bound keeps level 0
//! out to 157 km at tau 1 px. A mesh may take any post of the data under
//! the node, and needs 3 to 19 times fewer triangles for the same error.
//!
//! | module | owns |
//! |---|---|
//! | [`mod@reference`] | the best data under a node on a finer level's lattice |
//! | [`mod@build`] | per node: RTIN mesh, exact delta, morph targets, normals |
//! | [`mod@fan`] | cells split four ways so a mesh, fully morphed, is its parent's surface |
//! | [`mod@file`] | the mesh file: versioned, checksummed, memory-mapped, written atomically |
//! | [`mod@source`] | [`MeshedSource`]: a pyramid whose nodes come with their meshes |

pub mod build;
pub mod fan;
pub mod file;
pub mod reference;
pub mod source;

pub use build::{build_meshes, BuiltMeshes};
pub use file::{mesh_file_name, write_meshes, MeshFile};
pub use source::MeshedSource;

use crate::mesh::MeshError;
use crate::node::{NodeError, NodeId, NodeLayout};

/// How the meshes are built.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeshOptions {
    /// The error of level 1, metres; level `l` gets `error_m * 2^(l-1)`
    /// (Ulrich's halving toward the fine levels) and level 0 none: it
    /// draws the data exactly wherever the error bound lets it be seen.
    pub error_m: f32,
    /// How many levels finer than the node its reference lattice may be:
    /// the mesh of a node of level `l` takes posts of level
    /// `l - min(l, depth)`. With 64-cell nodes, 5 gives at most 2049^2 posts.
    pub depth: u8,
    /// Every triangle lies inside one square of this many node posts, so
    /// tiles of that size (or any larger power of two) take whole triangles.
    pub tile_cells: u32,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions { error_m: ERROR_PER_PIXEL_M, depth: 5, tile_cells: 8 }
    }
}

/// Level 1's mesh error per pixel of tau, metres: meshes are built for the
/// display's tau (see [`MeshOptions::for_tau`]).
pub const ERROR_PER_PIXEL_M: f32 = 12.0;

impl MeshOptions {
    /// The meshes for a display of screen-space error bound `tau_px`:
    /// level 1's error `ERROR_PER_PIXEL_M * tau_px`. Ulrich's rings are
    /// `delta K / tau`, so every level then appears at the same distance
    /// whatever tau is, and a larger tau draws coarser meshes there. With
    /// one fixed set of meshes the rings soon fall below the floor that
    /// keeps neighbours within one level, and tau stops mattering.
    pub fn for_tau(tau_px: f64) -> MeshOptions {
        let error_m = (ERROR_PER_PIXEL_M as f64 * tau_px) as f32;
        MeshOptions { error_m, ..MeshOptions::default() }
    }

    /// The error level `level`'s meshes are simplified to, metres.
    pub fn level_error(&self, level: u8) -> f32 {
        if level == 0 {
            0.0
        } else {
            self.error_m * (1u64 << (level - 1).min(60)) as f32
        }
    }

    /// Checks the options against a pyramid's layout.
    pub fn validate(&self, layout: &NodeLayout) -> Result<(), MeshesError> {
        let fail = |why: String| Err(MeshesError::Options(why));
        if !(self.error_m.is_finite() && self.error_m > 0.0) {
            return fail(format!("mesh error {} m must be a finite number above 0", self.error_m));
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
