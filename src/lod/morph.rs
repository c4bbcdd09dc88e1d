//! The per-vertex morph, written once here in Rust and mirrored line for line
//! by `shaders/gles/terrain.vert`: tests check on the CPU what the shader will
//! do, and a source test keeps the two formulas in step.
//!
//! A vertex of a level-`l` tile carries its own height and its morph target,
//! the height of the level-`l+1` surface at the same horizontal place (for
//! posts that level `l+1` also has, the two are equal). The shader blends
//! them by the vertex's distance to the camera (CDLOD-style, vertical only as
//! in Ulrich section 12), so the blend reaches the parent's surface exactly
//! where the parent takes over.

/// Morph factor for a vertex at `distance` metres in a tile whose morph runs
/// from `start` (factor 0) to `end` (factor 1).
pub fn morph_factor(distance: f64, start: f64, end: f64) -> f64 {
    if !start.is_finite() {
        return 0.0;
    }
    ((distance - start) / (end - start)).clamp(0.0, 1.0)
}

/// The morph range of a vertex of morph band `band` in a tile whose own
/// range is `own` (its level's, toward the level above) and whose
/// sub-level 1 morph ends at `sub_end`: band 0 `own`; band `k >= 1`
/// sub-level `k`'s, toward sub-level `k - 1`, ending at `sub_end` halved
/// `k - 1` times and starting `start_share` of the way there (every
/// morph's start over its end). In f32, as the shader computes it.
pub fn band_range(own: [f32; 2], sub_end: f32, start_share: f32, band: u8) -> [f32; 2] {
    if band == 0 {
        return own;
    }
    let end = sub_end * (1.0 - band as f32).exp2();
    [end * start_share, end]
}

/// The height drawn for a vertex.
pub fn morphed_height(height: f32, target: f32, factor: f64) -> f64 {
    height as f64 + (target as f64 - height as f64) * factor
}
