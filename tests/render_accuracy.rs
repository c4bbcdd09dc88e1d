//! The accuracy tool on the GPU, over the built-in terrain at the test size:
//! the measured error stays within tau where the bound promises it (at
//! p99.9, as the issue asks, and at every pixel), the
//! CPU mirror of the drawn surface agrees with what the GPU drew (morph
//! included), the measurement sees the error of coarse tiles, and the LOD
//! and full-resolution images cover the same pixels.

use ridgeline::camera::Camera;
use ridgeline::display::measure::AccuracyRun;
use testkit::builtin_pyramid;
use testkit::render::{measure_accuracy, measure_accuracy_of, VIEWS};

fn measure(tau_px: f64) -> AccuracyRun {
    let views: Vec<(f64, Camera)> =
        VIEWS.iter().enumerate().map(|(k, v)| (k as f64, v.camera())).collect();
    measure_accuracy(builtin_pyramid(), &views, tau_px)
}

fn print(run: &AccuracyRun) {
    let s = &run.summary;
    let lod: u64 = run.views.iter().map(|v| v.triangles_lod).sum();
    let truth: u64 = run.views.iter().map(|v| v.triangles_truth).sum();
    let mirror = run.views.iter().map(|v| v.mirror_p99_m).fold(0.0, f64::max);
    println!(
        "tau {}: p50 {:.4} p99 {:.4} p99.9 {:.4} max {:.3} px ({:.3} off {} skirt pixels), mismatch {:.5}, holes {}, mirror p99 {:.4} m, triangles {lod} / {truth}",
        run.tau_px, s.p50_px, s.p99_px, s.p999_px, s.max_px, run.max_surface_px, run.skirt_pixels, run.coverage_mismatch, run.holes, mirror
    );
}

#[test]
fn measured_error_confirms_tau_and_grows_with_it() {
    let runs: Vec<AccuracyRun> = [1.0, 4.0, 16.0].into_iter().map(measure).collect();
    for run in &runs {
        print(run);
        assert_eq!(run.views.len(), VIEWS.len());
        assert_eq!(run.holes, 0, "every ground point the truth shows has a drawn tile");
        // The 0.01 % of pixels; silhouettes are measured as error.
        assert!(run.coverage_mismatch <= 1e-4, "coverage agrees: {}", run.coverage_mismatch);
        // Skirts show only where the depth buffer cannot tell a skirt from
        // the surface in front of it (a near plane at the nearest tile keeps
        // that rare).
        assert!(run.skirt_pixels * 5000 < run.summary.pixels, "{} skirt pixels", run.skirt_pixels);
        for view in &run.views {
            // The CPU mirror reads the surface the GPU drew (skirts aside).
            assert!(
                view.mirror_p99_m < 0.05,
                "mirror p99 {} m at tau {}",
                view.mirror_p99_m,
                run.tau_px
            );
        }
        assert!(run.worst.as_ref().is_some_and(
            |w| w.heat_map.dimensions() == (testkit::render::SIZE.x, testkit::render::SIZE.y)
        ));
    }
    let [fine, medium, coarse] = [&runs[0], &runs[1], &runs[2]];
    assert!(
        fine.summary.p999_px <= 1.0 && medium.summary.p999_px <= 4.0,
        "the bound holds where it is promised"
    );
    // And at every pixel: the bound is a guarantee, not a percentile.
    assert!(
        fine.summary.max_px <= 1.0 && medium.summary.max_px <= 4.0,
        "max {} and {} px",
        fine.summary.max_px,
        medium.summary.max_px
    );
    // Coarse tiles are seen as error: the measurement is not blind.
    assert!(
        coarse.summary.p99_px > 4.0 * fine.summary.p99_px,
        "tau 16 draws measurably coarser terrain"
    );
    assert!(coarse.summary.max_px > fine.summary.max_px);
    let triangles = |run: &AccuracyRun| run.views.iter().map(|v| v.triangles_lod).sum::<u64>();
    assert!(triangles(coarse) * 2 < triangles(fine));
}

/// Node meshes (issue 11) keep the bound with fewer triangles than the
/// regular grids, and still measurably coarsen with tau (their error is
/// built per tau: `MeshOptions::for_tau`).
#[test]
fn node_meshes_keep_the_bound_with_fewer_triangles() {
    let views: Vec<(f64, Camera)> =
        VIEWS.iter().enumerate().map(|(k, v)| (k as f64, v.camera())).collect();
    let triangles = |run: &AccuracyRun| run.views.iter().map(|v| v.triangles_lod).sum::<u64>();
    let grid = measure_accuracy_of(builtin_pyramid(), &views, 1.0, false);
    let [fine, coarse] =
        [1.0, 4.0].map(|tau| measure_accuracy_of(builtin_pyramid(), &views, tau, true));
    for run in [&fine, &coarse] {
        print(run);
        assert_eq!(run.holes, 0);
        assert!(run.coverage_mismatch <= 1e-4, "coverage agrees: {}", run.coverage_mismatch);
        assert!(run.views.iter().all(|v| v.mirror_p99_m < 0.05), "the CPU mirror reads the meshes");
    }
    assert!(fine.summary.p999_px <= 1.0 && coarse.summary.p999_px <= 4.0, "the bound holds");
    assert!(
        triangles(&fine) * 2 < triangles(&grid),
        "{} against {}",
        triangles(&fine),
        triangles(&grid)
    );
    assert!(triangles(&coarse) < triangles(&fine));
}
