//! The subcommands of the `ridgeline` binary: `fly` (the main job) flies a
//! camera path over a terrain, `import` builds a node pyramid cache, `info`
//! describes one.

pub mod fly;
pub mod import;
pub mod info;
mod progress;

/// Writes `text` to standard output. A reader that has gone away (a closed
/// pipe, as in `ridgeline info ... | head`) is not an error.
pub fn print(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(error) if error.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => Ok(other?),
    }
}
