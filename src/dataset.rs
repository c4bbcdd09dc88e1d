//! Which terrain a run uses: a pyramid in the cache named on the command line,
//! or the built-in default, a real SRTM tile compiled into the binary and
//! built into `cache/` on first use (and rebuilt if the cache was damaged).

use crate::dem::{self, ImportError};
use crate::pyramid::{self, BuildError, BuildOptions, Progress, Pyramid, PyramidError, FILE_NAME};
use std::path::{Path, PathBuf};

/// The built-in terrain's cache name.
pub const DEFAULT_DATASET: &str = "srtm3_n39e040";

/// SRTM 3" around Erzincan and Tercan, eastern Turkey (1000 x 1000 posts,
/// 1111 to 3270 m; see assets/dem/README.md for source and licence).
const DEFAULT_TIFF: &[u8] = include_bytes!("../assets/dem/srtm3_n39e040_1000.tif");

/// Why a dataset cannot be opened or the built-in terrain cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// The built-in terrain's source could not be written to the cache.
    #[error("{path}: cannot write the built-in terrain: {source}")]
    Write {
        /// The file being written.
        path: PathBuf,
        /// The I/O failure.
        source: std::io::Error,
    },
    /// The built-in terrain's source failed to import.
    #[error(transparent)]
    Import(#[from] ImportError),
    /// The built-in terrain's pyramid failed to build.
    #[error("building the built-in terrain: {0}")]
    Build(#[from] BuildError),
    /// The pyramid file failed to open.
    #[error(transparent)]
    Pyramid(#[from] PyramidError),
    /// No pyramid exists for a dataset name.
    #[error("dataset {name}: no pyramid at {path} (build one with `ridgeline import FILES --out {path}`)")]
    Missing {
        /// The dataset name asked for.
        name: String,
        /// Where its pyramid was looked for.
        path: PathBuf,
    },
}

/// Opens the dataset `name` (a cache name under `cache_root`, or a path to a
/// cache directory or pyramid file); `None` is the built-in default.
pub fn open(
    name: Option<&str>,
    cache_root: &Path,
    progress: &dyn Progress,
) -> Result<Pyramid, DatasetError> {
    let Some(name) = name else {
        return open_default(cache_root, progress);
    };
    let as_path = Path::new(name);
    let dir = if as_path.exists() { as_path.to_path_buf() } else { cache_root.join(name) };
    if !dir.exists() {
        if name == DEFAULT_DATASET {
            return open_default(cache_root, progress);
        }
        return Err(DatasetError::Missing { name: name.to_string(), path: dir });
    }
    Ok(Pyramid::open(&dir)?)
}

/// Opens the built-in terrain, building it first when it is missing or damaged.
pub fn open_default(cache_root: &Path, progress: &dyn Progress) -> Result<Pyramid, DatasetError> {
    let dir = cache_root.join(DEFAULT_DATASET);
    match Pyramid::open(&dir) {
        Ok(pyramid) => return Ok(pyramid),
        Err(error) if dir.join(FILE_NAME).exists() => {
            eprintln!("ridgeline: rebuilding the built-in terrain: {error}");
        }
        Err(_) => {}
    }
    build_default(&dir, progress)?;
    Ok(Pyramid::open(&dir)?)
}

fn build_default(dir: &Path, progress: &dyn Progress) -> Result<(), DatasetError> {
    let write_error = |path: &Path| {
        let path = path.to_path_buf();
        move |source| DatasetError::Write { path, source }
    };
    std::fs::create_dir_all(dir).map_err(write_error(dir))?;
    // The importer reads files; the source goes beside the pyramid, written
    // under a temporary name and renamed so a crash never leaves half of it.
    let source = dir.join("source.tif");
    let partial = dir.join(format!("source.tif.tmp-{}", std::process::id()));
    std::fs::write(&partial, DEFAULT_TIFF).map_err(write_error(&partial))?;
    std::fs::rename(&partial, &source).map_err(write_error(&source))?;
    let grid = dem::import_file(&source)?;
    let built = pyramid::build(&grid, &BuildOptions::default(), progress)?;
    pyramid::write_atomic(&built, &dir.join(FILE_NAME), progress)?;
    Ok(())
}
