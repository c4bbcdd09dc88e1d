//! A deterministic synthetic terrain of any size, for scale tests and
//! benchmarks (and the hidden `ridgeline import --synthetic SIZE`): real
//! imports read DEM files through [`crate::dem`].

use rayon::prelude::*;

use crate::dem::ElevationGrid;
use crate::geo::GeoRef;

/// Largest synthetic grid side: 16384^2 heights are 1 GiB.
pub const MAX_SYNTHETIC_SIZE: u32 = 16384;
/// Metres between synthetic samples (SRTM3-like).
const SPACING_M: f64 = 90.0;

/// A `size` x `size` grid of hills, ridges and small-scale roughness in a
/// local frame with 90 m spacing, the same for the same `size`; `None` when
/// `size` is 0 or above [`MAX_SYNTHETIC_SIZE`].
pub fn synthetic_grid(size: u32) -> Option<ElevationGrid> {
    if !(1..=MAX_SYNTHETIC_SIZE).contains(&size) {
        return None;
    }
    let mut heights = vec![0.0f32; size as usize * size as usize];
    heights.par_chunks_mut(size as usize).enumerate().for_each(|(j, row)| {
        for (i, h) in row.iter_mut().enumerate() {
            *h = height_at(i as f64 * SPACING_M, j as f64 * SPACING_M, i as u32, j as u32);
        }
    });
    Some(ElevationGrid {
        width: size,
        height: size,
        heights,
        georef: GeoRef::local([SPACING_M; 2]),
        voids_filled: 0,
    })
}

/// Height in metres at `(x, y)` metres: a few sine hills and ridges plus a
/// hash-based jitter of a few metres (so no two neighbours are collinear).
fn height_at(x: f64, y: f64, i: u32, j: u32) -> f32 {
    let hills = 900.0 * (x / 21_000.0).sin() * (y / 17_000.0).cos();
    let ridges = 350.0 * ((x + 0.6 * y) / 4_100.0).sin().abs();
    let rough = 40.0 * (x / 610.0).sin() * (y / 530.0).sin();
    let jitter = (hash(i, j) as f64 / u32::MAX as f64 - 0.5) * 6.0;
    (1200.0 + hills + ridges + rough + jitter) as f32
}

/// A well-mixed 32-bit hash of a sample position.
fn hash(i: u32, j: u32) -> u32 {
    let mut h = i.wrapping_mul(0x9E37_79B1) ^ j.wrapping_mul(0x85EB_CA77);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297A_2D39);
    h ^ (h >> 15)
}
