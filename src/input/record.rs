//! `--record FILE.csv`: the poses received, one row per sample taken, in
//! the `--path` CSV format with `lat,lon` positions
//! ([`crate::flight::csv`]), so a live flight replays with `--path`.
//!
//! Rows are written through a fixed buffer without allocating; the file
//! is written beside its name and renamed into place when the recording
//! ends, so a reader never sees half a file under it.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::pose::GeoPose;

/// The header the recording starts with.
pub const HEADER: &str = "t,lat,lon,alt,heading,pitch,roll";

/// A recording in progress.
pub struct Recorder {
    writer: BufWriter<File>,
    partial: PathBuf,
    path: PathBuf,
    start: Option<Instant>,
    last_t: f64,
    rows: u64,
}

/// A recording that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: cannot record the live flight: {source}")]
pub struct RecordError {
    /// The recording's file.
    pub path: PathBuf,
    /// The I/O failure.
    pub source: std::io::Error,
}

impl Recorder {
    /// Starts a recording at `path` (written beside it until finished).
    pub fn create(path: &Path) -> Result<Recorder, RecordError> {
        let mut partial = path.as_os_str().to_owned();
        partial.push(".partial");
        let partial = PathBuf::from(partial);
        let fail = |source| RecordError { path: path.to_path_buf(), source };
        let mut writer = BufWriter::new(File::create(&partial).map_err(fail)?);
        writeln!(
            writer,
            "# ridgeline fly --record: live poses, t seconds from the first\n{HEADER}"
        )
        .map_err(fail)?;
        Ok(Recorder {
            writer,
            partial,
            path: path.to_path_buf(),
            start: None,
            last_t: -1.0,
            rows: 0,
        })
    }

    /// Writes `pose`, received at `at`. Rows whose time does not advance
    /// (two samples within a microsecond) are left out: the path format
    /// needs strictly increasing times.
    pub fn write(&mut self, pose: &GeoPose, at: Instant) -> Result<(), RecordError> {
        let start = *self.start.get_or_insert(at);
        let t = (at.saturating_duration_since(start).as_secs_f64() * 1e6).round() / 1e6;
        if t <= self.last_t {
            return Ok(());
        }
        self.last_t = t;
        let p = pose;
        writeln!(
            self.writer,
            "{t},{},{},{},{},{},{}",
            p.lat_deg, p.lon_deg, p.alt_m, p.heading_deg, p.pitch_deg, p.roll_deg
        )
        .map_err(|source| RecordError { path: self.path.clone(), source })?;
        self.rows += 1;
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Flushes the file and renames it into place; the rows written.
    pub fn finish(mut self) -> Result<u64, RecordError> {
        let fail = |source| RecordError { path: self.path.clone(), source };
        self.writer.flush().map_err(fail)?;
        std::fs::rename(&self.partial, &self.path).map_err(fail)?;
        Ok(self.rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_recording_is_a_flight_path_with_increasing_times() {
        let dir = std::env::temp_dir().join(format!("ridgeline-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("flight.csv");
        let mut recorder = Recorder::create(&path).unwrap();
        let t0 = Instant::now();
        let pose = GeoPose { lat_deg: 39.5, lon_deg: 40.2, alt_m: 3000.0, ..GeoPose::default() };
        recorder.write(&pose, t0).unwrap();
        recorder.write(&pose, t0).unwrap();
        recorder.write(&pose, t0 + Duration::from_millis(40)).unwrap();
        assert!(!path.exists(), "not under its name until finished");
        assert_eq!(recorder.finish().unwrap(), 2);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("\nt,lat,lon,alt,heading,pitch,roll\n0,39.5,40.2,3000,0,0,0\n0.04,"),
            "{text}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
