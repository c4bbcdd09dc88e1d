//! Ridgeline: a synthetic-vision terrain display for low-power OpenGL ES boards.
//!
//! The crate is split into a GL-free core, which tests and benchmarks drive
//! without any context, and (from the renderer on) a thin GL layer that only
//! consumes what the core produces.
//!
//! | module | owns |
//! |---|---|
//! | [`allocator`] | the contiguous two-pass buffer allocator: one address space, its staging copy, who holds which bytes |
//! | [`geo`] | georeference conventions and the local metric frame |
//! | [`dem`] | elevation importers (GeoTIFF, SRTM, DTED, ASCII grid) producing an [`dem::ElevationGrid`] |
//! | [`gl`] | the thin GL layer: contexts (window, EGL, OSMesa), owner types for GL objects, error checks |
//! | [`node`] | the node pyramid's vocabulary: node ids, layout, node data, the `NodeSource` trait |
#![deny(unsafe_code)]

pub mod allocator;
pub mod dem;
pub mod geo;
pub mod gl;
pub mod node;
