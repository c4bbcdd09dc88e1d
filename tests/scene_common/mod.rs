//! The built-in terrain, built once per test process into a temporary cache,
//! and cameras over it.
#![allow(dead_code)] // each test file uses part of this

use glam::DVec3;
use ridgeline::camera::Camera;
use ridgeline::pyramid::{Pyramid, Silent};
use ridgeline::scene::PreloadedTerrain;
use std::sync::OnceLock;

pub fn cache_dir() -> &'static std::path::Path {
    static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("ridgeline-scene-tests-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp cache");
        dir
    })
}

pub fn pyramid() -> Pyramid {
    ridgeline::dataset::open(None, cache_dir(), &Silent).expect("built-in terrain")
}

pub fn terrain() -> &'static PreloadedTerrain {
    static TERRAIN: OnceLock<PreloadedTerrain> = OnceLock::new();
    TERRAIN.get_or_init(|| PreloadedTerrain::load(&pyramid()).expect("all nodes read"))
}

pub fn camera(x: f64, y: f64, altitude: f64, heading: f64, pitch: f64) -> Camera {
    Camera {
        position: DVec3::new(x, y, altitude),
        heading_deg: heading,
        pitch_deg: pitch,
        roll_deg: 0.0,
        fov_x_deg: 60.0,
        viewport: [320, 180],
    }
}
