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
//! - **Split and stitch in one pass**: every post of every level is the
//!   composite surface of all layers sampled at that post ([`layers`]), so
//!   a node's window, border included, holds the neighbours' posts in its
//!   border (Kühnert's stitch), positions past the data's edge take the edge
//!   post (his edge rule), and a post of level `l + 1` is the post of level
//!   `l` at the same place (subsampling). No level is held whole: nodes are
//!   cut one by one.
//! - **Layers and absent nodes**: the layers (files of different
//!   resolutions, extents and lattices in one coordinate system) are placed
//!   on the finest layer's lattice; a node of level `l` is stored only where
//!   a layer whose native level is `l` or finer reaches it (and its data are
//!   not all missing), plus every ancestor of a stored node. Other nodes are
//!   *absent*: listed in the file's node table without a record, and never
//!   requested by the clipmap, which draws the deepest present ancestor
//!   (best-available data, not an error). A 5' base under a 3" tile is thus
//!   stored from level 6 (3.2' posts) up, and level 0 only where the tile is.
//! - **Delta is computed, never assumed to halve**: for every post of the
//!   best data under a node (the finest present node at each place), the
//!   vertical distance to the node's surface (each cell split from its
//!   south-west to its north-east corner), in `f64`, stored rounded up to
//!   `f32` so the stored bound is never below the true one. Level 0 passes
//!   through every post, so its delta is exactly 0.
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
mod built;
mod bytes;
mod delta;
mod error;
pub mod format;
pub mod layers;
mod limits;
mod open;
pub(crate) use open::release_map_pages;
mod progress;
pub mod shard;
pub mod spilled;
mod stream;
mod synthetic;
mod write;

pub use build::{build, build_layers, BuildOptions};
pub use built::BuiltPyramid;
pub use error::{BuildError, PyramidError, StreamError};
pub use format::{GridStats, LevelSummary, NodeSummary, PostWindow, PyramidInfo, FILE_NAME};
pub use layers::BLEND_MARGIN_M;
pub use limits::{MAX_BORDER, MAX_LEVELS, MAX_NODE_SIZE, MAX_POSTS_PER_SIDE};
pub use open::Pyramid;
pub use progress::{Progress, Silent};
pub use stream::{build_streaming, StreamOptions};
pub use synthetic::{synthetic_grid, MAX_SYNTHETIC_SIZE};
pub use write::{replace_file, sync_dir, write_atomic};
