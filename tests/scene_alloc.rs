//! Once warmed up, a frame of the scene allocates nothing: ring updates, tile
//! selection, the tile cache (slots, allocator, vertex generation) and the
//! draw list all reuse buffers sized at start; so do the clusters (their
//! formation, cache and allocators) when the tiles are drawn as clusters.
//! One test in this binary, since the counter sees the whole process.

use ridgeline::scene::{Scene, SceneConfig};
use testkit::scene::{camera, terrain};

#[test]
fn steady_state_frames_allocate_nothing() {
    steady_state(SceneConfig::default());
    steady_state(SceneConfig { clusters: true, ..SceneConfig::default() });
}

fn steady_state(config: SceneConfig) {
    let terrain = terrain();
    let mut scene = Scene::new(config, terrain).unwrap();
    let path = |k: u32| {
        camera(20_000.0 + 40.0 * k as f64, 30_000.0 + 25.0 * k as f64, 3_000.0, 55.0, -7.0)
    };
    // Warm-up: the hash map and tables reach their working size.
    for k in 0..40 {
        scene.frame(&path(k), terrain).unwrap();
    }
    let before = testkit::alloc::allocations();
    let mut generated = 0;
    for k in 40..120 {
        generated += scene.frame(&path(k), terrain).unwrap().generated;
    }
    let moving = testkit::alloc::allocations() - before;
    let still = path(120);
    scene.frame(&still, terrain).unwrap();
    let before = testkit::alloc::allocations();
    let mut uploaded = 0;
    for _ in 0..20 {
        let stats = scene.frame(&still, terrain).unwrap();
        uploaded += stats.bytes_uploaded + stats.cluster_bytes_uploaded;
    }
    let resting = testkit::alloc::allocations() - before;
    assert!(generated > 0, "the flight made new tiles");
    assert_eq!(uploaded, 0, "a still camera uploads nothing (clusters: {})", config.clusters);
    assert_eq!(
        (moving, resting),
        (0, 0),
        "allocations in 80 moving and 20 still frames (clusters: {})",
        config.clusters
    );
}
