//! The streaming build (`build_streaming` over layers in spills, what
//! `ridgeline import` runs) writes the very bytes of the in-memory build
//! (`build_layers` then `write_atomic`), whatever the band size: layered
//! inputs with a large void, and a 2 x 2 mosaic of SRTM3 tiles with small
//! and large voids read from files. A memory bound too small for one band
//! is refused, and the scratch directory is gone after the build.

use std::path::{Path, PathBuf};

use ridgeline::dem::{import_layers, ElevationGrid, GridView};
use ridgeline::pyramid::spilled::spill_layers;
use ridgeline::pyramid::{
    build_layers, build_streaming, write_atomic, BuildOptions, Silent, StreamError, StreamOptions,
    FILE_NAME,
};
use ridgeline::spill::ScratchDir;
use testkit::dem::{write_hgt, HGT_VOID};
use testkit::fresh_dir;

const OPTIONS: BuildOptions = BuildOptions { node_size: 32, border: 2 };

fn terrain(x: f64, y: f64) -> f64 {
    800.0 + 300.0 * (x / 7000.0).sin() * (y / 9000.0).cos() + 0.01 * x
}

fn layer(origin: [f64; 2], spacing: f64, posts: [u32; 2], offset: f64) -> ElevationGrid {
    testkit::pyramid::projected_grid(origin, [spacing; 2], posts, |x, y| terrain(x, y) + offset)
}

/// The in-memory build's bytes.
fn in_memory(layers: &[ElevationGrid], dir: &Path) -> Vec<u8> {
    let built = build_layers(layers, &OPTIONS, &Silent).expect("build in memory");
    let path = dir.join("memory.rlp");
    write_atomic(&built, &path, &Silent).expect("write");
    std::fs::read(path).expect("read back")
}

/// The streaming build's bytes, with bands of `band_bytes`.
fn streamed(views: &[GridView], dir: &Path, band_bytes: u64) -> Result<Vec<u8>, StreamError> {
    let scratch = ScratchDir::create(dir).expect("scratch");
    let options = StreamOptions { build: OPTIONS, band_bytes };
    let path = dir.join(FILE_NAME);
    build_streaming(views, &scratch, &options, &path, &|| {}, &Silent)?;
    Ok(std::fs::read(path).expect("read back"))
}

#[test]
fn layers_with_a_void_stream_to_the_same_bytes_in_any_band_size() {
    let dir = fresh_dir("stream-layers");
    let coarse = layer([0.0, 0.0], 900.0, [60, 60], 0.0);
    let mut fine = layer([15_030.0, 12_060.0], 90.0, [240, 200], 25.0);
    // A large void the coarse layer shows through.
    for j in 80..120 {
        for i in 100..150 {
            fine.heights[j * 240 + i] = f32::NAN;
        }
    }
    let layers = [coarse, fine];
    let expected = in_memory(&layers, &dir);
    let views: Vec<GridView> = layers.iter().map(ElevationGrid::view).collect();
    let record = 4 * (36 * 36 + 4) as u64;
    for band_bytes in [1 << 30, 3 * 40 * record] {
        let bytes = streamed(&views, &dir, band_bytes).expect("stream");
        assert!(bytes == expected, "band bytes {band_bytes}: the files differ");
    }
    let scratch_left = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .any(|e| e.file_name().to_string_lossy().starts_with(".import-"));
    assert!(!scratch_left, "the scratch directory is removed");
    let refused = streamed(&views, &dir, record).expect_err("one row does not fit");
    assert!(refused.to_string().contains("--memory-mb"), "{refused}");
}

/// Writes a 2 x 2 mosaic of SRTM3 tiles (continuous across the seams),
/// with a small void inside one tile and a large one inside another.
fn write_tiles(dir: &Path) -> Vec<PathBuf> {
    let side = 1201usize;
    let mut paths = Vec::new();
    for (lat, lon) in [(45, 7), (45, 8), (46, 7), (46, 8)] {
        let mut heights: Vec<i16> = (0..side * side)
            .map(|k| {
                let (i, j) = ((k % side) as f64, (k / side) as f64);
                let (x, y) = ((lon - 7) as f64 * 1200.0 + i, (lat - 45) as f64 * 1200.0 + j);
                terrain(x * 90.0, y * 90.0) as i16
            })
            .collect();
        if (lat, lon) == (45, 8) {
            (600..603).for_each(|j| (500..504).for_each(|i| heights[j * side + i] = HGT_VOID));
        }
        if (lat, lon) == (46, 7) {
            (300..340).for_each(|j| (300..360).for_each(|i| heights[j * side + i] = HGT_VOID));
        }
        let path = dir.join(format!("N{lat:02}E{lon:03}.hgt"));
        write_hgt(&path, side, &heights);
        paths.push(path);
    }
    paths
}

#[test]
fn a_mosaic_of_tiles_with_voids_streams_to_the_same_bytes() {
    let dir = fresh_dir("stream-tiles");
    let paths = write_tiles(&dir);
    let layers = import_layers(&paths).expect("import in memory");
    let expected = in_memory(&layers, &dir);
    let scratch = ScratchDir::create(&dir).expect("scratch");
    let spilled = spill_layers(&paths, &scratch, &Silent).expect("spill the tiles");
    assert_eq!(spilled[0].voids_filled, layers[0].voids_filled, "12 posts of the small void");
    let views: Vec<GridView> = spilled.iter().map(|l| l.view()).collect();
    let record = 4 * (36 * 36 + 4) as u64;
    let bytes = streamed(&views, &dir, 3 * 76 * record * 2).expect("stream");
    assert!(bytes == expected, "the files differ");
}
