//! The subcommands of the `ridgeline` binary: `fly` (the main job) flies a
//! camera path over a terrain, `import` builds a node pyramid cache, `info`
//! describes one.

pub mod fly;
pub mod import;
pub mod info;
mod progress;
