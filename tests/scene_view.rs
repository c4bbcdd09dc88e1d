//! A frame computes its view geometry once: `scene::View::new` is the
//! only place that computes the clip planes, frustum and horizons, and the
//! pipeline makes one view per frame, however often the tau policy selects
//! again (a triangle budget's band), the buffer coarsens the selection, or
//! the clusters are formed.

use ridgeline::clipmap::LoaderMode;
use ridgeline::lod::budget::{BudgetConfig, BudgetTarget};
use ridgeline::pipeline::{FramePipeline, PipelineConfig};
use ridgeline::scene::{clip_planes_computed, SceneConfig};
use testkit::scene::{null_backend, VIEWPORT};
use testkit::{camera, over_tile};

#[test]
fn every_frame_computes_its_view_geometry_once() {
    let terrain = testkit::builtin_terrain();
    let summary = testkit::summary_of(&terrain);
    // A budget well under the view's triangles selects again within frames.
    let scene = SceneConfig { clusters: true, ..SceneConfig::default() };
    let config = PipelineConfig {
        scene,
        loader: LoaderMode::Inline,
        load_budget: 4096,
        budget: Some(BudgetConfig::new(BudgetTarget::Triangles(20_000))),
        ..PipelineConfig::new(VIEWPORT)
    };
    let mut pipeline = FramePipeline::new(&config, terrain, summary).expect("pipeline");
    let mut backend = null_backend(&pipeline);
    let (mut reselected, mut clusters) = (0, 0);
    for k in 0..24 {
        let cam = camera(
            VIEWPORT,
            over_tile(12_000.0 + 1_200.0 * k as f64, 20_000.0, 2_500.0),
            60.0,
            -8.0,
        );
        pipeline.settle(&cam, 1000).expect("paging");
        let before = clip_planes_computed();
        let stats = pipeline.frame(&cam, &mut backend).expect("a frame");
        assert_eq!(clip_planes_computed() - before, 1, "frame {k}: {:?}", stats.scene);
        reselected += stats.scene.reselected;
        clusters += stats.scene.clusters;
    }
    assert!(reselected > 0, "the band never selected again: the test would miss its retries");
    assert!(clusters > 0, "no clusters drawn");
}
