//! Once warmed up, a frame of the scene allocates nothing: ring updates, tile
//! selection, the tile cache (slots, allocator, vertex generation) and the
//! draw list all reuse buffers sized at start; so do the clusters (their
//! formation, cache and allocators) when the tiles are drawn as clusters.
//! One test in this binary, since the counter sees the whole process.

use ridgeline::earth::GridPlacement;
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::scene::{Scene, SceneConfig, TriangleBand};
use ridgeline::tiles::ResidentNodes;
use testkit::scene::{terrain, VIEWPORT};
use testkit::{camera, over_tile};

#[test]
fn steady_state_frames_allocate_nothing() {
    frames_allocate_nothing(SceneConfig::default(), false);
    frames_allocate_nothing(SceneConfig { clusters: true, ..SceneConfig::default() }, false);
    // With the valid life (the path moves 47 m a frame) and a triangle band
    // that makes the scene select again within frames.
    let mut config = SceneConfig::default();
    config.lod.max_travel_m = Some(50.0);
    frames_allocate_nothing(config, true);
    // On the ellipsoid: node places, camera boxes and the ellipsoid's
    // horizon are all on the stack.
    let layout = *terrain().layout();
    let georef = GeoRef { crs: Crs::Geographic, origin: [7.5, 45.9], spacing: [1.0 / 1200.0; 2] };
    let placement = GridPlacement::new(&georef, layout.posts, layout.spacing_m);
    frames_allocate_nothing(
        SceneConfig { earth: Some(placement), ..SceneConfig::default() },
        false,
    );
}

fn frames_allocate_nothing(config: SceneConfig, budget: bool) {
    let terrain = terrain();
    let mut scene = Scene::new(config, terrain).unwrap();
    if budget {
        scene.set_triangle_band(Some(TriangleBand { target: 60_000.0, tolerance: 0.04 }));
        scene.set_tau(1.5).unwrap();
    }
    let path = |k: u32| {
        camera(
            VIEWPORT,
            over_tile(20_000.0 + 40.0 * k as f64, 30_000.0 + 25.0 * k as f64, 3_000.0),
            55.0,
            -7.0,
        )
    };
    // Warm-up: the hash map and tables reach their working size.
    for k in 0..40 {
        scene.frame(&path(k), terrain).unwrap();
    }
    let before = testkit::alloc::allocations();
    let (mut generated, mut reselected) = (0, 0);
    for k in 40..120 {
        let stats = scene.frame(&path(k), terrain).unwrap();
        generated += stats.tiles_generated;
        reselected += stats.reselected;
        // Alternate the band's target so the scene keeps selecting again.
        let target = if k % 2 == 0 { 30_000.0 } else { 90_000.0 };
        if budget {
            scene.set_triangle_band(Some(TriangleBand { target, tolerance: 0.04 }));
        }
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
    assert!(!budget || reselected > 0, "the band never made the scene select again");
    if budget {
        let stats = scene.frame(&still, terrain).unwrap();
        assert!(
            stats.split_tests.candidates > 0 && !stats.split_tests.full,
            "{:?}",
            stats.split_tests
        );
    }
    assert_eq!(uploaded, 0, "a still camera uploads nothing (clusters: {})", config.clusters);
    assert_eq!(
        (moving, resting),
        (0, 0),
        "allocations in 80 moving and 20 still frames (clusters: {})",
        config.clusters
    );
}
