//! The node pyramid on disk: building it from an [`ElevationGrid`](crate::dem::ElevationGrid) (Kühnert
//! 4.5.6: split, downsample, stitch), measuring each node's geometric error
//! (Ulrich's delta, section 10), writing it atomically, and opening it again as
//! a memory-mapped, checksummed [`NodeSource`](crate::node::NodeSource)
//! (Ulrich section 15: self-contained nodes paged on demand).
//!
//! # Choices
//! - **Node size 64 cells, border 2** by default. 65 × 65 posts per node is a
//!   vertex count a 16-bit index buffer holds with room for skirts, a node is
//!   19 KB on disk (one read per page-in) and a view needs a few hundred of
//!   them, the chunk count Ulrich's traversal is designed for. Kühnert (6.x)
//!   found one border post enough for seamless sampling and two needed for
//!   normals at node edges, hence 2.
//! - **Downsampling subsamples**: a post of level `l + 1` is the post of level
//!   `l` at the same place, so every post of every level is a real level-0
//!   sample. Kühnert filters linearly instead; subsampling keeps peaks at
//!   their measured height where a post falls on them, keeps parent posts on
//!   their children's posts (Ulrich's vertical morph moves only the posts in
//!   between), and makes delta the honest bound of what the coarse node
//!   leaves out.
//! - **Split and stitch in one pass**: each level is first held as one whole
//!   raster of posts (level 0 is the grid itself, level `l + 1` every other
//!   post of level `l`); cutting a node's window out of it, border included,
//!   copies the neighbours' posts into the border (Kühnert's stitch) and
//!   clamping at the raster's edge extends the centre (his edge rule). The
//!   result is the same as his split, downsample, stitch sequence without a
//!   pass over node borders.
//! - **Delta is computed, never assumed to halve**: for every level-0 sample
//!   under a node, the vertical distance to the node's surface (each cell
//!   split from its south-west to its north-east corner), in `f64`, stored
//!   rounded up to `f32` so the stored bound is never below the true one.
//!   Level 0 passes through every sample, so its delta is exactly 0.
//! - **Verification at page-in**: [`Pyramid::open`] checks the header and its
//!   checksum (which covers the node table) and nothing else, so opening a
//!   10 GB pyramid costs what opening a 1 MB one does; `read_node` checks
//!   each node's checksum when the node is paged in (microseconds), which
//!   also catches a file changed in place after opening. The clipmap treats a
//!   node that fails as missing and draws its coarser ancestor.
//!   [`Pyramid::verify`] checks every node at once (in parallel; CRC-32 runs
//!   at several GB/s), as `ridgeline info` does.
//!
//! See [`mod@format`] for the bytes on disk.

mod build;
mod bytes;
mod delta;
mod error;
pub mod format;
mod limits;
mod open;
mod progress;
mod raster;
mod synthetic;
mod write;

pub use build::{build, BuildOptions, BuiltPyramid};
pub use error::{BuildError, PyramidError};
pub use format::{GridStats, LevelSummary, NodeSummary, PyramidInfo, FILE_NAME};
pub use limits::{MAX_BORDER, MAX_LEVELS, MAX_NODE_SIZE};
pub use open::Pyramid;
pub use progress::{Progress, Silent};
pub use synthetic::{synthetic_grid, MAX_SYNTHETIC_SIZE};
pub use write::write_atomic;
