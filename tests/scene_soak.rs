//! A long soak of the frame loop, headless and GL-free: 10^4 frames flying
//! the same closed circuit again and again. After the first lap nothing is
//! allocated; every lap ends with the same tiles and the same bytes in use;
//! the buffer's workspace (where fragmentation shows) wanders with the order
//! tiles come and go but does not grow. One test in this binary, since the
//! allocation counter sees the whole process.

mod alloc_counter;
mod scene_common;

use ridgeline::render::{NullBackend, RenderBackend};
use ridgeline::scene::{Scene, SceneConfig};
use scene_common::{camera, terrain};

const LAP: u32 = 400;
const LAPS: u32 = 25;

#[test]
fn ten_thousand_frames_keep_memory_and_free_space_flat() {
    let terrain = terrain();
    let config = SceneConfig::default();
    let mut scene = Scene::new(config, terrain).unwrap();
    let mut backend = NullBackend::new(config.buffer_bytes);
    // A circle of 12 km radius around the middle of the data, heading along it.
    let at = |frame: u32| {
        let a = std::f64::consts::TAU * (frame % LAP) as f64 / LAP as f64;
        let (x, y) = (36_000.0 + 12_000.0 * a.cos(), 46_000.0 + 12_000.0 * a.sin());
        camera(x, y, 3_800.0, (270.0 - a.to_degrees()).rem_euclid(360.0), -6.0)
    };
    let mut lap_ends = Vec::new();
    let mut allocations_after_first_lap = 0;
    for frame in 0..LAP * LAPS {
        let before = alloc_counter::allocations();
        let report = scene.frame(&at(frame), terrain).unwrap();
        let (staging, ranges) = scene.uploads();
        backend.upload(staging, ranges).unwrap();
        backend.draw(scene.draw_list()).unwrap();
        if frame >= LAP {
            allocations_after_first_lap += alloc_counter::allocations() - before;
        }
        if frame % LAP == LAP - 1 {
            lap_ends.push((
                report.allocator_used_bytes,
                report.allocator_workspace_bytes,
                report.tiles,
            ));
        }
    }
    let counts = backend.counts();
    assert_eq!(counts.frames, (LAP * LAPS) as u64);
    assert!(counts.bytes_uploaded > 0, "the circuit keeps changing tiles");
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
    let peak = lap_ends.iter().map(|l| l.1).max().unwrap() as f64;
    assert!(peak <= 2.0 * lap_ends[0].0 as f64, "workspace {peak} exceeds twice the bytes in use");
}
