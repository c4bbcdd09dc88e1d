//! With clusters on, buffers too small for the view coarsen the tiles and
//! say so (the frame's bound is loosened): they never fail the frame. At
//! this size the tile buffer fills first; the cluster cache's own full
//! cases (no window with room, a full run) are unit-tested in
//! `clusters::cache` and coarsen through the same path in `Scene::frame`.

use ridgeline::scene::SceneConfig;
use testkit::scene::{fly, null_backend, pipeline, VIEWPORT};
use testkit::{camera, over_tile};

#[test]
fn a_cluster_buffer_too_small_coarsens_the_tiles_instead_of_failing() {
    // 512 kB: under a window of cluster vertices, and a tile buffer the
    // view at tau 1 overfills (the meshes extracted for this 320-pixel view
    // fit 1 MB: they carry what its K needs, no more).
    let config = SceneConfig { clusters: true, buffer_bytes: 1 << 19, ..SceneConfig::default() };
    let mut pipeline = pipeline(config);
    let mut backend = null_backend(&pipeline);
    let mut coarsened = 0;
    for k in 0..6 {
        let at =
            camera(VIEWPORT, over_tile(20_000.0 + 400.0 * k as f64, 30_000.0, 1_500.0), 55.0, -8.0);
        let stats = fly(&mut pipeline, &mut backend, &at).expect("a coarser frame, not an error");
        assert!(stats.scene.triangles > 0 && stats.scene.clusters > 0, "frame {k}: {stats:?}");
        assert_eq!(stats.tau_loosened(), stats.scene.coarsened > 0, "frame {k}");
        coarsened += stats.scene.coarsened;
    }
    assert!(coarsened > 0, "the buffer never filled: the test proves nothing");
}
