//! What Ridgeline's test binaries share, as one library so that nothing in
//! it is compiled per binary or left unused in silence:
//!
//! | module | holds |
//! |---|---|
//! | [`alloc`] | a global allocator that counts allocations (the no-allocation tests) |
//! | [`cli`] | the `ridgeline` binary run, its exit checked, its stderr shown on failure |
//! | [`dem`] | writers of every elevation format the importers read, scratch folders |
//! | [`flight`] | the one flight loop: cameras flown on a pipeline or a display, a callback per frame |
//! | [`pyramid`] | random grids, pyramids built and written |
//! | [`clipmap`] | a small-node procedural earth and checks of the clipmap's state |
//! | [`scene`] | the frame pipeline over the built-in terrain on the null backend, shared-edge checks |
//! | [`live`] | the scripted flight the live-input tests play, and each protocol's datagrams of it |
//! | [`gl`] | one GL context at a time, loud skips of optional backends, Xvfb, child processes |
//! | [`render`] | displays over the built-in terrain, the fixed views, image comparison ([`compare`]) and hole detection ([`coverage`]) |
//!
//! Everything a test writes goes under [`target_tmp`]; the built-in terrain
//! is built there once ([`builtin_pyramid`], with its node meshes:
//! [`builtin_terrain`]) and shared by every binary.

pub mod alloc;
pub mod cli;
pub mod clipmap;
pub mod compare;
pub mod coverage;
pub mod dem;
pub mod flight;
pub mod gl;
pub mod live;
pub mod mesh;
pub mod pyramid;
pub mod render;
pub mod scene;

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use glam::DVec3;
use ridgeline::camera::Camera;
use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::pyramid::{Pyramid, Silent};
use ridgeline::scene::TerrainSummary;

/// The target folder's `tmp` (Cargo's `CARGO_TARGET_TMPDIR` for tests):
/// the running test binary is `target/<profile>/deps/<name>`.
pub fn target_tmp() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let exe = std::env::current_exe().expect("the test binary's path");
        let target = exe.ancestors().nth(3).expect("target/<profile>/deps/<binary>");
        let dir = target.join("tmp");
        std::fs::create_dir_all(&dir).expect("target/tmp");
        dir
    })
}

/// A fresh, empty folder under [`target_tmp`] for one test of this process.
pub fn fresh_dir(name: &str) -> PathBuf {
    let dir = target_tmp().join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

/// The built-in terrain, built on first use into one cache under
/// [`target_tmp`] that every test binary shares (pyramids are written
/// beside and renamed into place, so a reader never sees half a file).
pub fn builtin_pyramid() -> Arc<Pyramid> {
    static PYRAMID: OnceLock<Arc<Pyramid>> = OnceLock::new();
    let pyramid = PYRAMID.get_or_init(|| {
        let cache = target_tmp().join("builtin-terrain");
        std::fs::create_dir_all(&cache).expect("terrain cache directory");
        Arc::new(ridgeline::dataset::open(None, &cache, &Silent).expect("built-in terrain"))
    });
    Arc::clone(pyramid)
}

/// The built-in terrain with each node's error map, as `fly` draws it
/// (the map file is built once beside [`builtin_pyramid`]'s, and serves
/// every tau).
pub fn builtin_terrain() -> Arc<MeshedSource> {
    static TERRAIN: OnceLock<Arc<MeshedSource>> = OnceLock::new();
    Arc::clone(TERRAIN.get_or_init(|| Arc::new(meshed(builtin_pyramid()))))
}

/// `pyramid` with its error maps, built beside it when missing.
pub fn meshed(pyramid: Arc<Pyramid>) -> MeshedSource {
    MeshedSource::open_or_build(pyramid, MeshOptions::default(), &Silent).expect("meshes")
}

/// What the rings of a display over `source` are computed from.
pub fn summary_of(source: &MeshedSource) -> TerrainSummary {
    TerrainSummary::of_maps(source.pyramid().info(), source.info())
}

/// The built-in SRTM tile alone, without any layer under it: a real tile
/// whose data end at its edges (built once under [`target_tmp`]).
pub fn srtm_tile_pyramid() -> Arc<Pyramid> {
    static PYRAMID: OnceLock<Arc<Pyramid>> = OnceLock::new();
    Arc::clone(PYRAMID.get_or_init(|| asset_pyramid("srtm-tile", "srtm3_n39e040_1000.tif")))
}

/// The pyramid of `assets/dem/<file>` alone, built once into
/// `<target_tmp>/<name>` (and opened from there by later runs).
pub fn asset_pyramid(name: &str, file: &str) -> Arc<Pyramid> {
    // Tests of one binary run in parallel: one builds, the others wait and
    // open what it wrote.
    static BUILDING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = BUILDING.lock().unwrap_or_else(|e| e.into_inner());
    let dir = target_tmp().join(name);
    if let Ok(pyramid) = Pyramid::open(&dir) {
        return Arc::new(pyramid);
    }
    std::fs::create_dir_all(&dir).expect("pyramid cache directory");
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/dem").join(file);
    let grid = ridgeline::dem::import_file(&source)
        .unwrap_or_else(|e| panic!("{} imports: {e}", source.display()));
    let built = ridgeline::pyramid::build(&grid, &Default::default(), &Silent).expect("build");
    ridgeline::pyramid::write_atomic(&built, &dir.join(ridgeline::pyramid::FILE_NAME), &Silent)
        .expect("write");
    Arc::new(Pyramid::open(&dir).unwrap_or_else(|e| panic!("open the {name} pyramid: {e}")))
}

/// The built-in terrain's SRTM tile's south-west post in the pyramid's local
/// frame, metres: the built-in terrain is the tile over a larger ETOPO5
/// base, and the tests place their views relative to the tile
/// ([`over_tile`], [`render::ground`], [`render::VIEWS`]), as they were
/// before the base was added.
pub fn builtin_origin() -> glam::DVec2 {
    static ORIGIN: OnceLock<glam::DVec2> = OnceLock::new();
    *ORIGIN.get_or_init(|| glam::DVec2::from(builtin_pyramid().finest_area_m().0))
}

/// The point `(x, y)` metres from the built-in SRTM tile's south-west post
/// ([`builtin_origin`]), `altitude` metres up, in the pyramid's local frame.
pub fn over_tile(x: f64, y: f64, altitude: f64) -> DVec3 {
    let origin = builtin_origin();
    DVec3::new(origin.x + x, origin.y + y, altitude)
}

/// The tests' one camera: at `position` (local metres), heading and pitch
/// in degrees, no roll, a 60 degree field of view, over `viewport` pixels.
/// A test that needs a roll or another field of view sets it on the result.
pub fn camera(viewport: [u32; 2], position: DVec3, heading: f64, pitch: f64) -> Camera {
    Camera {
        position,
        heading_deg: heading,
        pitch_deg: pitch,
        roll_deg: 0.0,
        fov_x_deg: 60.0,
        viewport,
    }
}
