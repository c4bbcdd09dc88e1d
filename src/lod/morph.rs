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

/// The height drawn for a vertex.
pub fn morphed_height(height: f32, target: f32, factor: f64) -> f64 {
    height as f64 + (target as f64 - height as f64) * factor
}
