//! Ridgeline: a synthetic-vision terrain display for low-power OpenGL ES boards.
//!
//! The crate is split into a GL-free core, which tests and benchmarks drive
//! without any context, and (from the renderer on) a thin GL layer that only
//! consumes what the core produces.
//!
//! | module | owns |
//! |---|---|
//! | [`allocator`] | the contiguous two-pass buffer allocator: one address space, its staging copy, who holds which bytes |
#![deny(unsafe_code)]

pub mod allocator;
