//! Property tests of the void fill on random grids and void masks: valid
//! heights are kept, voids are counted, every filled height lies within the
//! range of the nearest valid heights along its row and column, planes are
//! restored exactly where voids are enclosed, and an all-void grid is refused.

use std::path::Path;

use proptest::prelude::*;
use ridgeline::dem::{voids, Problem, RawGrid};
use ridgeline::geo::GeoRef;
use testkit::dem::check_filled;

fn raw(width: u32, height: u32, heights: &[Option<f64>]) -> RawGrid {
    let mut grid =
        RawGrid::voids(Path::new("random.asc"), width, height, GeoRef::local([1.0, 1.0]));
    for (h, v) in grid.heights.iter_mut().zip(heights) {
        *h = v.map_or(f32::NAN, |v| v as f32);
    }
    grid
}

/// A grid size with heights and a void mask (`true` = void).
fn grid_with_voids() -> impl Strategy<Value = (u32, u32, Vec<f64>, Vec<bool>)> {
    (1u32..30, 1u32..30, 0.0f64..1.0).prop_flat_map(|(w, h, void_share)| {
        let n = (w * h) as usize;
        (
            Just(w),
            Just(h),
            prop::collection::vec(-500i32..5000, n)
                .prop_map(|v| v.into_iter().map(f64::from).collect()),
            prop::collection::vec(prop::bool::weighted(void_share), n),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn fill_keeps_valid_heights_and_stays_in_range((w, h, values, mask) in grid_with_voids()) {
        let before: Vec<Option<f64>> = values.iter().zip(&mask).map(|(&v, &void)| (!void).then_some(v)).collect();
        let result = voids::fill(raw(w, h, &before));
        if before.iter().all(Option::is_none) {
            let err = result.expect_err("an all-void grid is refused");
            prop_assert!(matches!(err.problem, Problem::AllVoids));
            prop_assert!(err.to_string().contains("random.asc"));
            return Ok(());
        }
        let grid = result.unwrap();
        prop_assert!(grid.heights.iter().all(|h| h.is_finite()));
        // Second-pass fills come from first-pass fills: still within all valid heights.
        let (lo, hi) = before.iter().flatten().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        prop_assert!(grid.heights.iter().all(|&h| f64::from(h) >= lo - 1e-3 && f64::from(h) <= hi + 1e-3));
        check_filled(&grid, &before, None);
    }

    #[test]
    fn fill_restores_enclosed_planes(
        (w, h, _, mask) in grid_with_voids(),
        a in -20.0f64..20.0,
        b in -20.0f64..20.0,
    ) {
        let plane = |i: u32, j: u32| 1000.0 + a * f64::from(i) + b * f64::from(j);
        let before: Vec<Option<f64>> = (0..w * h)
            .map(|k| (k % w, k / w))
            .map(|(i, j)| {
                let border = i == 0 || j == 0 || i == w - 1 || j == h - 1;
                (border || !mask[(j * w + i) as usize]).then(|| plane(i, j))
            })
            .collect();
        let grid = voids::fill(raw(w, h, &before)).unwrap();
        // With a valid border every void is enclosed: all are checked against the plane.
        check_filled(&grid, &before, Some(&plane));
    }
}

#[test]
fn a_row_and_column_of_voids_takes_a_second_pass() {
    // Only (0, 0) is valid: (1, 1) sees nothing along its row or column.
    let before = [Some(7.0), None, None, None];
    let grid = voids::fill(raw(2, 2, &before)).unwrap();
    assert_eq!(grid.heights, vec![7.0; 4]);
    assert_eq!(grid.voids_filled, 3);
}
