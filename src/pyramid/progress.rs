//! Progress reporting for long imports, kept free of any terminal code: the
//! command line adapts it to a progress bar, tests and benches stay silent.

/// Receives progress from [`build`](super::build) and
/// [`write_atomic`](super::write_atomic), possibly from several threads.
pub trait Progress: Sync {
    /// A new phase begins, measured in `total` units (nodes, rows or bytes).
    fn phase(&self, name: &str, total: u64);
    /// `units` more units of the current phase are done.
    fn advance(&self, units: u64);
}

/// Reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn phase(&self, _name: &str, _total: u64) {}
    fn advance(&self, _units: u64) {}
}
