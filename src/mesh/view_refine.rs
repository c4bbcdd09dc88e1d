//! View-dependent RTIN refinement of a full-resolution grid: the fewest
//! triangles a bisection mesh needs to hold every pixel within tau, the floor
//! a tiled LOD is compared against ("RTIN triangles at tau").
//!
//! A triangle splits while its error exceeds `tau D / K` (Ulrich's bound
//! solved for the error), `D` the distance from the eye to the box around
//! everything the split refines. The boxes are nested (a split's box holds its
//! children's), so `D` never grows down the hierarchy and the errors never
//! grow: the split set stays closed and the mesh conforming, and `D` is never
//! more than the distance to any point the triangle draws, so the estimate is
//! conservative.

use super::error::MeshError;
use super::rtin::{Rtin, SplitBounds, Triangle};

/// A camera as plain numbers, in the grid's frame: post `(i, j)` lies at
/// `(i * spacing[0], j * spacing[1])` metres, heights in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewParams {
    /// Eye position: east, north, up, metres.
    pub eye: [f64; 3],
    /// Metres between posts east and north.
    pub spacing: [f64; 2],
    /// Ulrich's K: viewport width / (2 tan(fov_x / 2)), pixels.
    pub k: f64,
    /// Screen-space error bound, pixels.
    pub tau: f64,
}

impl ViewParams {
    /// The vertical error allowed at distance `d` metres.
    pub fn allowed_error(&self, d: f64) -> f64 {
        self.tau * d / self.k
    }

    /// Distance from the eye to a split's box, metres (0 inside it).
    pub fn distance(&self, b: &SplitBounds) -> f64 {
        let gap = |lo: f64, hi: f64, e: f64| (lo - e).max(e - hi).max(0.0);
        let dx =
            gap(b.min[0] as f64 * self.spacing[0], b.max[0] as f64 * self.spacing[0], self.eye[0]);
        let dy =
            gap(b.min[1] as f64 * self.spacing[1], b.max[1] as f64 * self.spacing[1], self.eye[1]);
        let dz = gap(b.z[0] as f64, b.z[1] as f64, self.eye[2]);
        (dx * dx + dy * dy + dz * dz).sqrt()
    }
}

/// Refines `rtin` (built with `bounds: true`) for one view, calls `emit` for
/// every triangle of the mesh and returns how many there are.
pub fn view_refine(
    rtin: &Rtin,
    view: &ViewParams,
    emit: &mut impl FnMut(Triangle),
) -> Result<u64, MeshError> {
    if !(view.tau > 0.0 && view.k > 0.0) {
        return Err(MeshError::View { tau: view.tau, k: view.k });
    }
    if rtin.bounds_at(0, 0).is_none() {
        return Err(MeshError::NoBounds);
    }
    let mut count = 0u64;
    let mut split = |_: &Triangle, [i, j]: [u32; 2]| {
        let error = rtin.error_at(i, j) as f64;
        // Bounds exist: checked above. Cheap test first: most splits are decided by error.
        error > 0.0 && error > view.allowed_error(view.distance(&rtin.bounds_at(i, j).unwrap()))
    };
    rtin.walk(&mut split, &mut |t| {
        count += 1;
        emit(t);
    });
    Ok(count)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{HeightGrid, RtinOptions};

    #[test]
    fn far_away_two_triangles_close_up_many() {
        let side = 65u32;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| ((k % side) as f32 * 0.7).sin() * 50.0 + (k / side) as f32)
            .collect();
        let grid = HeightGrid::new(side, &heights).unwrap();
        let rtin =
            Rtin::new(&grid, RtinOptions { bounds: true, ..RtinOptions::default() }).unwrap();
        let view = |eye| ViewParams { eye, spacing: [90.0, 90.0], k: 1000.0, tau: 1.0 };
        let far = view_refine(&rtin, &view([1e9, 0.0, 0.0]), &mut |_| {}).unwrap();
        let near = view_refine(&rtin, &view([2900.0, 2900.0, 200.0]), &mut |_| {}).unwrap();
        assert_eq!(far, 2);
        assert!(near > 1000, "{near}");
        let plain = Rtin::new(&grid, RtinOptions::default()).unwrap();
        assert!(view_refine(&plain, &view([0.0; 3]), &mut |_| {}).is_err());
    }
}
