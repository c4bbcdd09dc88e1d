//! What can go wrong building, writing and opening a pyramid.

use std::path::PathBuf;

/// Why a grid could not be turned into a pyramid.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The elevation grid cannot be tiled (empty, too large, non-finite heights).
    #[error("elevation grid: {0}")]
    InvalidGrid(String),
    /// The node size or border is out of range.
    #[error("pyramid options: {0}")]
    InvalidOptions(String),
}

/// Why a streaming build ([`super::build_streaming`]) failed.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// The layers or options cannot be built.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// Writing the file failed.
    #[error(transparent)]
    Write(#[from] PyramidError),
    /// The memory bound is too small for one band of this input.
    #[error("memory: {0}")]
    Memory(String),
    /// A shard's part could not be read (it names the file and node).
    #[error(transparent)]
    Part(crate::node::NodeError),
}

/// Why a pyramid file could not be written or opened. Every variant names
/// the file.
#[derive(Debug, thiserror::Error)]
pub enum PyramidError {
    /// Reading, writing or renaming the file failed.
    #[error("{path}: {source}")]
    Io {
        /// The pyramid file.
        path: PathBuf,
        /// The I/O failure.
        source: std::io::Error,
    },
    /// The file does not start with the pyramid magic.
    #[error("{path}: not a Ridgeline pyramid (bad magic); rebuild it with `ridgeline import`")]
    NotAPyramid {
        /// The file.
        path: PathBuf,
    },
    /// The file was written by another format version.
    #[error("{path}: pyramid format version {found}, this build reads version {supported}; rebuild it with `ridgeline import`")]
    Version {
        /// The pyramid file.
        path: PathBuf,
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The file ends before its header or node table says it should.
    #[error("{path}: truncated: {problem}")]
    Truncated {
        /// The pyramid file.
        path: PathBuf,
        /// What was cut short.
        problem: String,
    },
    /// The header or node table contradicts itself or fails its checksum.
    #[error("{path}: damaged: {problem}; rebuild it with `ridgeline import`")]
    Corrupt {
        /// The pyramid file.
        path: PathBuf,
        /// What was found.
        problem: String,
    },
}

impl PyramidError {
    pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> PyramidError + '_ {
        move |source| PyramidError::Io { path: path.to_path_buf(), source }
    }

    pub(crate) fn corrupt(path: &std::path::Path, problem: impl Into<String>) -> PyramidError {
        PyramidError::Corrupt { path: path.to_path_buf(), problem: problem.into() }
    }
}
