//! A long soak of the frame pipeline (clipmap paging, tiles, uploads) on
//! the null backend, headless and GL-free: 10^4 frames flying
//! the same closed circuit again and again. After the first lap nothing is
//! allocated; every lap ends with the same tiles and the same bytes in use;
//! the buffer's workspace (where fragmentation shows) wanders with the order
//! tiles come and go but does not grow. The frames run on the test's thread
//! and its allocations are counted (the harness's main thread allocates
//! when a test runs past a minute). One test in this binary.

use ridgeline::scene::SceneConfig;
use testkit::scene::{null_backend, pipeline, VIEWPORT};
use testkit::{camera, over_tile};

const LAP: u32 = 400;
const LAPS: u32 = 25;

#[test]
fn ten_thousand_frames_keep_memory_and_free_space_flat() {
    let config = SceneConfig::default();
    let mut pipeline = pipeline(config);
    let mut backend = null_backend(&pipeline);
    let (mut frames, mut bytes_uploaded, mut nodes_loaded) = (0u64, 0u64, 0u64);
    // A circle of 12 km radius around the middle of the data, heading along it.
    let at = |frame: u32| {
        let a = std::f64::consts::TAU * (frame % LAP) as f64 / LAP as f64;
        let (x, y) = (36_000.0 + 12_000.0 * a.cos(), 46_000.0 + 12_000.0 * a.sin());
        camera(VIEWPORT, over_tile(x, y, 3_800.0), (270.0 - a.to_degrees()).rem_euclid(360.0), -6.0)
    };
    let mut lap_ends = Vec::new();
    let mut allocations_after_first_lap = 0;
    for frame in 0..LAP * LAPS {
        let before = testkit::alloc::thread_allocations();
        testkit::alloc::trace(frame >= LAP);
        // No settling: the frame pages what it needs itself (inline loads).
        let stats = pipeline.frame(&at(frame), &mut backend).unwrap();
        let report = stats.scene;
        frames += stats.calls.frames;
        bytes_uploaded += stats.calls.bytes_uploaded;
        nodes_loaded += stats.nodes_loaded as u64;
        if frame >= LAP {
            allocations_after_first_lap += testkit::alloc::thread_allocations() - before;
        }
        if frame % LAP == LAP - 1 {
            lap_ends.push((
                report.allocator_used_bytes,
                report.allocator_workspace_bytes,
                report.tiles,
            ));
        }
    }
    testkit::alloc::trace(false);
    assert_eq!(frames, (LAP * LAPS) as u64);
    assert!(bytes_uploaded > 0, "the circuit keeps changing tiles");
    assert!(nodes_loaded > 0, "the clipmap pages nodes in");
    assert_eq!(allocations_after_first_lap, 0, "allocations after the first lap");
    // The tile cache keeps only what the view uses: every lap ends with the
    // same tiles in the same number of bytes.
    assert!(
        lap_ends.windows(2).all(|w| (w[0].0, w[0].2) == (w[1].0, w[1].2)),
        "lap ends differ: {lap_ends:?}"
    );
    // Fragmentation: no trend from the first third of the laps to the last.
    let third = lap_ends.len() / 3;
    let mean = |laps: &[(u64, u32, usize)]| {
        laps.iter().map(|l| l.1 as f64).sum::<f64>() / laps.len() as f64
    };
    let (early, late) = (mean(&lap_ends[..third]), mean(&lap_ends[lap_ends.len() - third..]));
    assert!(
        late <= early * 1.05,
        "workspace grows: {early:.0} then {late:.0} bytes ({lap_ends:?})"
    );
    // The peak against the bytes in use: 2.11 times since tiles are
    // extracted at the whole error the bound allows (752 kB in use; the
    // frame's run of new blocks is about as large as before).
    let peak = lap_ends.iter().map(|l| l.1).max().unwrap() as f64;
    assert!(
        peak <= 2.25 * lap_ends[0].0 as f64,
        "workspace {peak} exceeds 2.25 times the bytes in use: {lap_ends:?}"
    );
}
