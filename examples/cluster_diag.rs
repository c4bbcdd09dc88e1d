//! Temporary: cluster statistics along the default flight on the null backend.
use ridgeline::clipmap::LoaderMode;
use ridgeline::flight::default_flight;
use ridgeline::pipeline::{FramePipeline, PipelineConfig};
use ridgeline::render::{CostModel, NullBackend};
use ridgeline::scene::TerrainSummary;

fn main() {
    let pyramid = std::sync::Arc::new(
        ridgeline::dataset::open(None, std::path::Path::new("cache"), &ridgeline::pyramid::Silent)
            .expect("built-in"),
    );
    let summary = TerrainSummary::from_pyramid(pyramid.info());
    let size: Vec<u32> = std::env::args()
        .nth(1)
        .unwrap_or("1280x720".into())
        .split('x')
        .map(|s| s.parse().unwrap())
        .collect();
    let mut config = PipelineConfig::new([size[0], size[1]]);
    config.loader = LoaderMode::Inline;
    config.load_budget = 1000;
    config.scene.clusters = true;
    let mut pipeline = FramePipeline::new(&config, pyramid.clone(), summary).unwrap();
    let mut null =
        NullBackend::new(config.scene.buffer_bytes, CostModel { vertex_arrays: true, sky: true });
    let path = default_flight(&pyramid);
    for (k, t) in path.frame_times(24).enumerate() {
        let camera = path.sample(t).camera(60.0, [size[0], size[1]]);
        pipeline.settle(&camera, 1000).unwrap();
        let s = pipeline.frame(&camera, &mut null).unwrap();
        let c = pipeline.scene().clusters().unwrap().stats();
        let list = pipeline.draw_list();
        let verts: u64 =
            list.tiles.iter().map(|t| ((t.index_byte_offset - t.byte_offset) / 20) as u64).sum();
        println!("{k}: tiles {} clusters {} draws {} ptr {} bases {} made {} used {:.1} MB verts {} ({:.1} windows) up {:.0} KB",
            s.scene.tiles, c.clusters, s.calls.draw_calls - 1, s.calls.attribute_pointer_changes - 1, c.bases, c.made,
            c.used_bytes as f64 / 1e6, verts, verts as f64 / 65536.0, s.calls.bytes_uploaded as f64 / 1e3);
    }
}
