//! Writing a pyramid so that a crash or kill at any moment leaves either the
//! old file or the new one, never a mixture: write `NAME.tmp-PID` beside it,
//! flush it to disk, rename it over the old file, flush the directory.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::built::BuiltPyramid;
use super::error::PyramidError;
use super::format::{encode_header, encode_record, record_len};
use super::progress::Progress;

/// Records encoded per write call: large enough to keep both cores busy
/// computing checksums, small enough to bound the extra memory (~5 MB).
const RECORDS_PER_BATCH: usize = 256;

/// Writes `pyramid` to `path` atomically. The directory must exist.
pub fn write_atomic(
    pyramid: &BuiltPyramid,
    path: &Path,
    progress: &dyn Progress,
) -> Result<(), PyramidError> {
    replace_file(
        path,
        |temporary| write_file(pyramid, temporary, progress),
        |path, source| PyramidError::Io { path: path.to_path_buf(), source },
    )
}

/// Replaces the file at `path` so that a crash at any moment leaves the old
/// file or the new one: `write` fills `NAME.tmp-PID` beside it (and flushes
/// it), which is then renamed over `path`, and the directory flushed. `io`
/// turns an I/O failure on a path into the caller's error.
pub fn replace_file<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    io: impl Fn(&Path, std::io::Error) -> E,
) -> Result<(), E> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().ok_or_else(|| {
        io(path, std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"))
    })?;
    remove_stale_temporaries(dir, &name.to_string_lossy());
    let temporary = dir.join(format!("{}.tmp-{}", name.to_string_lossy(), std::process::id()));
    let written = write(&temporary).and_then(|()| {
        fs::rename(&temporary, path).map_err(|e| io(path, e))?;
        sync_dir(dir).map_err(|e| io(dir, e))
    });
    if written.is_err() {
        // Best effort: the error being returned matters more than this one.
        let _ = fs::remove_file(&temporary);
    }
    written
}

/// Writes the whole file at `path` and flushes it to disk.
fn write_file(
    pyramid: &BuiltPyramid,
    path: &Path,
    progress: &dyn Progress,
) -> Result<(), PyramidError> {
    let layout = pyramid.layout();
    let header = encode_header(&pyramid.info, &pyramid.node_summaries());
    let record_len = record_len(layout) as usize;
    let present: u64 = pyramid.info.levels.iter().map(|l| l.present).sum();
    progress.phase("write", header.len() as u64 + present * record_len as u64);
    let mut file = File::create(path).map_err(PyramidError::io(path))?;
    file.write_all(&header).map_err(PyramidError::io(path))?;
    progress.advance(header.len() as u64);
    let posts = (layout.stored_side() as usize).pow(2);
    let mut batch = vec![0u8; RECORDS_PER_BATCH * record_len];
    let indices = pyramid.present_indices();
    let mut written = 0usize;
    for (heights, summaries) in pyramid.levels() {
        for (nodes, summaries) in
            heights.chunks(RECORDS_PER_BATCH * posts).zip(summaries.chunks(RECORDS_PER_BATCH))
        {
            let bytes = &mut batch[..summaries.len() * record_len];
            let batch_indices = &indices[written..written + summaries.len()];
            written += summaries.len();
            bytes
                .par_chunks_mut(record_len)
                .zip(nodes.par_chunks(posts))
                .zip(summaries)
                .zip(batch_indices)
                .for_each(|(((record, heights), summary), &index)| {
                    encode_record(index, heights, summary, record)
                });
            file.write_all(bytes).map_err(PyramidError::io(path))?;
            progress.advance(bytes.len() as u64);
        }
    }
    file.sync_all().map_err(PyramidError::io(path))
}

/// Makes the rename durable: on Unix a directory entry reaches the disk only
/// when the directory itself is flushed.
pub fn sync_dir(dir: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    File::open(dir).and_then(|d| d.sync_all())?;
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

/// Removes `NAME.tmp-PID` files left by imports that were killed, judging a
/// process gone when `/proc/PID` is missing; without `/proc` nothing is removed.
fn remove_stale_temporaries(dir: &Path, name: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let prefix = format!("{name}.tmp-");
    let Ok(entries) = fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name.to_str().and_then(|n| n.strip_prefix(&prefix)) else { continue };
        let alive = PathBuf::from("/proc").join(pid).exists();
        if pid.parse::<u32>().is_ok() && !alive {
            let _ = fs::remove_file(entry.path());
        }
    }
}
