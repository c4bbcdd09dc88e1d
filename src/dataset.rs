//! Which terrain a run uses: a pyramid in the cache named on the command line,
//! or the built-in default, a real SRTM tile over a regional ETOPO5 base,
//! both compiled into the binary and built into `cache/` on first use as one
//! layered pyramid (and rebuilt if the cache was damaged or is of an older
//! format).
//!
//! The base is ETOPO5 relief, land and sea floor. A synthetic-vision
//! display shows the sea as its surface, so the base's heights below 0 m
//! (the Black Sea floor, to -2173 m) are raised to 0 m, sea level; the SRTM
//! tile is kept as it is.

use crate::dem::{self, ImportError};
use crate::meshes::{MeshOptions, MeshedSource, MeshesError};
use crate::pyramid::{self, BuildError, BuildOptions, Progress, Pyramid, PyramidError, FILE_NAME};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The built-in terrain's cache name.
pub const DEFAULT_DATASET: &str = "srtm3_n39e040_etopo5";

/// SRTM 3" around Erzincan and Tercan, eastern Turkey (1000 x 1000 posts,
/// 1111 to 3270 m; see assets/dem/README.md for source and licence).
const DEFAULT_TIFF: &[u8] = include_bytes!("../assets/dem/srtm3_n39e040_1000.tif");

/// ETOPO5 5' relief, 37-44 E, 37-42.5 N, the base under the SRTM tile
/// (see assets/dem/README.md).
const DEFAULT_BASE: &[u8] = include_bytes!("../assets/dem/etopo5_e37_e44_n37_n42.nc");

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
    /// The adaptive meshes could not be built or read.
    #[error("meshes: {0}")]
    Chunks(#[from] MeshesError),
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

/// [`open`], with each node's adaptive mesh: the mesh file beside the
/// pyramid is built first when it is missing, damaged, of another pyramid
/// or of other `options`.
pub fn open_meshed(
    name: Option<&str>,
    cache_root: &Path,
    options: MeshOptions,
    progress: &dyn Progress,
) -> Result<MeshedSource, DatasetError> {
    let pyramid = Arc::new(open(name, cache_root, progress)?);
    Ok(MeshedSource::open_or_build(pyramid, options, progress)?)
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
    // The importers read files; the sources go beside the pyramid, written
    // under a temporary name and renamed so a crash never leaves half of one.
    let write_source = |name: &str, bytes: &[u8]| -> Result<PathBuf, DatasetError> {
        let source = dir.join(name);
        let partial = dir.join(format!("{name}.tmp-{}", std::process::id()));
        std::fs::write(&partial, bytes).map_err(write_error(&partial))?;
        std::fs::rename(&partial, &source).map_err(write_error(&source))?;
        Ok(source)
    };
    let tile = dem::import_file(&write_source("source.tif", DEFAULT_TIFF)?)?;
    let mut base = dem::import_file(&write_source("base.nc", DEFAULT_BASE)?)?;
    dem::sea::raise_to_sea_surface(&mut base.heights);
    let built = pyramid::build_layers(&[tile, base], &BuildOptions::default(), progress)?;
    pyramid::write_atomic(&built, &dir.join(FILE_NAME), progress)?;
    Ok(())
}
