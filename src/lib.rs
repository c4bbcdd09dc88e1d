//! Ridgeline: a synthetic-vision terrain display for low-power OpenGL ES boards.
//!
//! The crate is split into a GL-free core, which tests and benchmarks drive
//! without any context, and (from the renderer on) a thin GL layer that only
//! consumes what the core produces.
//!
//! | module | owns |
//! |---|---|
//! | [`accuracy`] | the accuracy tool's measurements: per-pixel screen-space error of the LOD against full resolution, its statistics and heat map |
//! | [`allocator`] | the contiguous two-pass buffer allocator: one address space, its staging copy, who holds which bytes |
//! | [`geo`] | georeference conventions and the local metric frame |
//! | [`earth`] | the WGS 84 ellipsoid (geodetic and ECEF), the projections grids are placed with, where a grid's posts are on the earth |
//! | [`dem`] | elevation importers (GeoTIFF, SRTM, DTED, ASCII grid) producing an [`dem::ElevationGrid`] |
//! | [`camera`] | the viewer's position and attitude, projection, frustum, earth curvature |
//! | [`lod`] | UDLOD tiling on the CPU: distance rings with Ulrich's bound, quadtree selection, morph |
//! | [`mesh`] | adaptive chunk meshes, GL-free: the RTIN error map and extraction, exact mesh delta against level 0, morph-target lookup, view-dependent RTIN refinement |
//! | [`meshes`] | node meshes (Ulrich's chunks): each stored node's RTIN error map of the best data under it, the map file beside the pyramid (one for every tau), and the source that pages nodes with their maps |
//! | [`tiles`] | per-tile mesh blocks (vertices, then indices), the regular grid mesh, vertex data, the tile cache on the allocator |
//! | [`clusters`] | cluster batches (Judnich & Ling): the frame's tiles gathered into two-level clusters, each cluster's block (its members' vertices, one 16-bit index list) in the cluster buffer |
//! | [`render`] | the GL-free half of drawing: draw lists, the backend trait, the counting null backend, the palette |
//! | [`symbology`] | the reference symbols over the terrain (zero-pitch line and heading marks, aircraft symbol, flight path marker) and the failure flag, as GL-free geometry; the built-in stroke font |
//! | [`flight`] | camera paths for `fly`: the `--path` CSV, interpolation, frame times, the built-in approach |
//! | [`scene`] | one frame of the display, GL-free: rings, selection, tile uploads, draw list, stage times |
//! | [`pipeline`] | the frame pipeline: owns the clipmap, the scene and the frame budget's tau controller, plans memory, makes one frame per call on any render backend |
//! | [`dataset`] | which terrain a run uses; the built-in SRTM tile, built into `cache/` on first use |
//! | [`gl`] | the thin GL layer: contexts (window, EGL, OSMesa), owner types for GL objects, error checks |
//! | [`input`] | live aircraft state over UDP (FlightGear, X-Plane, GDL 90): decoders, plausibility, the receiver thread, staleness, extrapolation |
//! | [`display`] | the display put together: GL context, renderer and frame pipeline; one call per frame |
//! | [`node`] | the node pyramid's vocabulary: node ids, layout, node data, the `NodeSource` trait |
//! | [`pyramid`] | building the node pyramid from a grid (split, downsample, stitch, delta), its checksummed file, writing it atomically, opening it memory-mapped |
//! | [`spill`] | memory-mapped scratch arrays of an import bigger than memory, and its scratch directory |
//! | [`procedural`] | a deterministic earth-sized `NodeSource` computed on demand, for scale tests |
//! | [`clipmap`] | the chunked clipmap: node atlas, clipped quadtrees per view, loader, height queries |
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod accuracy;
pub mod allocator;
pub mod camera;
pub mod clipmap;
pub mod clusters;
pub mod dataset;
pub mod dem;
pub mod display;
pub mod earth;
pub mod flight;
pub mod geo;
pub mod gl;
pub(crate) mod hash;
pub mod input;
pub mod lod;
pub mod mesh;
pub mod meshes;
pub mod node;
pub mod pipeline;
pub mod procedural;
pub mod pyramid;
pub mod render;
pub mod scene;
pub mod spill;
pub mod symbology;
pub mod tiles;
