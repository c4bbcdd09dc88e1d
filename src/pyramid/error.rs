//! What can go wrong building, writing and opening a pyramid.

use std::path::PathBuf;

/// Why a grid could not be turned into a pyramid.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    #[error("elevation grid: {0}")]
    InvalidGrid(String),
    #[error("pyramid options: {0}")]
    InvalidOptions(String),
}

/// Why a pyramid file could not be written or opened. Every variant names
/// the file.
#[derive(Debug, thiserror::Error)]
pub enum PyramidError {
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: not a Ridgeline pyramid (bad magic); rebuild it with `ridgeline import`")]
    NotAPyramid { path: PathBuf },
    #[error("{path}: pyramid format version {found}, this build reads version {supported}; rebuild it with `ridgeline import`")]
    Version { path: PathBuf, found: u32, supported: u32 },
    #[error("{path}: truncated: {problem}")]
    Truncated { path: PathBuf, problem: String },
    #[error("{path}: damaged: {problem}; rebuild it with `ridgeline import`")]
    Corrupt { path: PathBuf, problem: String },
}

impl PyramidError {
    pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> PyramidError + '_ {
        move |source| PyramidError::Io { path: path.to_path_buf(), source }
    }

    pub(crate) fn corrupt(path: &std::path::Path, problem: impl Into<String>) -> PyramidError {
        PyramidError::Corrupt { path: path.to_path_buf(), problem: problem.into() }
    }
}
