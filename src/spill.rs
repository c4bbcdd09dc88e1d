//! Memory-mapped scratch arrays for imports larger than memory: a *spill*
//! is an array of plain numbers in a file of the import's scratch
//! directory, mapped shared, so the kernel writes its pages back to the
//! file instead of holding them on the heap; [`Spill::release`] drops the
//! pages this process has touched from its resident set once a band of
//! work is done. The scratch directory (`OUT/.import-PID`) is removed when
//! the import ends, fails or panics, and a stale one left by a killed
//! import is removed by the next import into the same cache.

use std::fs::{self, OpenOptions};
use std::path::{Path, PathBuf};

use std::sync::Arc;

use memmap2::MmapRaw;
#[cfg(unix)]
use memmap2::UncheckedAdvice;

#[cfg(target_endian = "big")]
compile_error!("spills are read back by casting bytes");

/// The prefix of an import's scratch directory inside its cache.
const SCRATCH_PREFIX: &str = ".import-";

/// A directory of spills, removed with everything in it when dropped.
pub struct ScratchDir {
    path: PathBuf,
    next: std::cell::Cell<u32>,
}

impl ScratchDir {
    /// Creates `OUT/.import-PID`, first removing scratch directories of
    /// imports into `out` that are no longer running.
    pub fn create(out: &Path) -> std::io::Result<ScratchDir> {
        remove_stale(out);
        let path = out.join(format!("{SCRATCH_PREFIX}{}", std::process::id()));
        // A directory of this process id is a dead process's, reused pid.
        let _ = fs::remove_dir_all(&path);
        fs::create_dir_all(&path)?;
        Ok(ScratchDir { path, next: std::cell::Cell::new(0) })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A new spill of `len` values, each `fill`, named after `what`.
    pub fn spill<T: bytemuck::Pod>(
        &self,
        what: &str,
        len: usize,
        fill: T,
    ) -> std::io::Result<Spill<T>> {
        let n = self.next.get();
        self.next.set(n + 1);
        Spill::create(&self.path.join(format!("{n:04}-{what}")), len, fill)
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        // Best effort: a leftover is removed by the next import.
        let _ = fs::remove_dir_all(&self.path);
    }
}

/// Removes `out/.import-PID` directories whose process is gone (judged by
/// `/proc/PID`; without `/proc` nothing is removed).
fn remove_stale(out: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = fs::read_dir(out) else { return };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(|n| n.strip_prefix(SCRATCH_PREFIX)) else {
            continue;
        };
        if pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists() {
            let _ = fs::remove_dir_all(entry.path());
        }
    }
}

/// An array of `T` in a memory-mapped file; the file is deleted on drop.
pub struct Spill<T> {
    path: PathBuf,
    map: Option<Arc<MmapRaw>>,
    len: usize,
    marker: std::marker::PhantomData<T>,
}

impl<T: bytemuck::Pod> Spill<T> {
    /// Creates the file at `path` with `len` values set to `fill`, the
    /// pages released as they are written.
    pub fn create(path: &Path, len: usize, fill: T) -> std::io::Result<Spill<T>> {
        let bytes = len.checked_mul(std::mem::size_of::<T>()).ok_or_else(|| {
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "spill too large")
        })?;
        let file = OpenOptions::new().read(true).write(true).create_new(true).open(path)?;
        file.set_len(bytes as u64)?;
        let map = if bytes == 0 { None } else { Some(Arc::new(MmapRaw::map_raw(&file)?)) };
        #[cfg(unix)]
        if let Some(map) = &map {
            // Coarse nodes sample posts far apart; without this the kernel
            // maps whole large folios around each (16 SRTM1 tiles: 145 MB of
            // layer pages at levels 4 to 8, 11 to 18 MB with it).
            map.advise(memmap2::Advice::Random)?;
        }
        let mut spill =
            Spill { path: path.to_path_buf(), map, len, marker: std::marker::PhantomData };
        if !bytemuck::bytes_of(&fill).iter().all(|&b| b == 0) {
            // A new file reads as zeros; anything else is written in bands.
            let band = (SPILL_BAND_BYTES / std::mem::size_of::<T>().max(1)).max(1);
            for start in (0..len).step_by(band) {
                spill.as_mut_slice()[start..(start + band).min(len)].fill(fill);
                spill.release();
            }
        }
        Ok(spill)
    }

    /// The values.
    pub fn as_slice(&self) -> &[T] {
        match &self.map {
            Some(map) => &bytemuck::cast_slice(raw_bytes(map))[..self.len],
            None => &[],
        }
    }

    /// The values, to write.
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        let len = self.len;
        match &mut self.map {
            Some(map) => &mut bytemuck::cast_slice_mut(raw_bytes_mut(map))[..len],
            None => &mut [],
        }
    }

    /// Drops every page of the spill from this process's resident set; the
    /// values stay in the file (and the page cache) and are read back on
    /// the next access.
    pub fn release(&self) {
        self.releaser().release();
    }

    /// A handle that releases the spill's pages while its values are
    /// borrowed (to drop pages behind a long pass over them).
    pub fn releaser(&self) -> Releaser {
        Releaser(self.map.clone())
    }
}

/// Releases a spill's pages ([`Spill::releaser`]).
#[derive(Clone)]
pub struct Releaser(Option<Arc<MmapRaw>>);

impl Releaser {
    /// See [`Spill::release`].
    pub fn release(&self) {
        if let Some(map) = &self.0 {
            release_map(map);
        }
    }
}

impl<T> Drop for Spill<T> {
    fn drop(&mut self) {
        self.map = None;
        let _ = fs::remove_file(&self.path);
    }
}

/// Bytes written between releases while a spill is filled.
const SPILL_BAND_BYTES: usize = 32 << 20;

/// The mapped bytes.
#[allow(unsafe_code)]
fn raw_bytes(map: &MmapRaw) -> &[u8] {
    // SAFETY: the map is valid for `len` bytes while `map` lives (the
    // borrow ties the slice to it); the file was created by this process
    // in its own scratch directory with create_new and is never truncated
    // while mapped. Writes go through `raw_bytes_mut`, which needs the
    // Spill mutably, so no `&[u8]` aliases a `&mut [u8]`.
    unsafe { std::slice::from_raw_parts(map.as_ptr(), map.len()) }
}

/// The mapped bytes, to write.
#[allow(unsafe_code)]
fn raw_bytes_mut(map: &mut Arc<MmapRaw>) -> &mut [u8] {
    // SAFETY: as in `raw_bytes`; the caller holds the Spill mutably, the
    // only other clones of the Arc are Releasers, which never read or
    // write the bytes.
    unsafe { std::slice::from_raw_parts_mut(map.as_mut_ptr(), map.len()) }
}

/// Drops a shared file mapping's pages from the resident set
/// (MADV_DONTNEED); the next access reads them back.
#[cfg(unix)]
#[allow(unsafe_code)]
fn release_map(map: &MmapRaw) {
    // SAFETY: the map is a shared mapping of a file (memmap2 maps with
    // MAP_SHARED): DONTNEED only unmaps its pages, dirty ones stay in the
    // page cache and reach the file, and the next access faults them back
    // with the same bytes, so slices into the map stay valid. (On a
    // private map it would discard writes; spills are never private.)
    let _ = unsafe { map.unchecked_advise(UncheckedAdvice::DontNeed) };
}

#[cfg(not(unix))]
fn release_map(_map: &MmapRaw) {}
