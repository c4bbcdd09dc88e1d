//! The subcommands of the `ridgeline` binary that work on terrain data:
//! `import` builds a node pyramid cache, `info` describes one.

pub mod import;
pub mod info;
