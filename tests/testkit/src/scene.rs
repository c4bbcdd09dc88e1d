//! The built-in terrain, built once into a cache under the target folder,
//! and cameras over it.

use ridgeline::camera::Camera;
use ridgeline::clipmap::LoaderMode;
use ridgeline::lod::morph::{morph_factor, morphed_height};
use ridgeline::node::NodeSource;
use ridgeline::pipeline::{FrameError, FramePipeline, FrameStats, PipelineConfig};
use ridgeline::render::DrawList;
use ridgeline::render::{CostModel, NullBackend, RenderBackend};
use ridgeline::scene::PreloadedTerrain;
use ridgeline::scene::{SceneConfig, TerrainSummary};
use ridgeline::tiles::vertex::is_no_data;
use ridgeline::tiles::TileVertex;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

/// The viewport of the scene tests' cameras.
pub const VIEWPORT: [u32; 2] = [320, 180];

/// The frame pipeline, clipmap included, over `source` at `config`, with
/// nodes loaded inline so that every frame is complete and repeatable.
pub fn pipeline_over(
    source: Arc<dyn NodeSource>,
    summary: TerrainSummary,
    config: SceneConfig,
) -> FramePipeline {
    let pipeline = PipelineConfig {
        scene: config,
        loader: LoaderMode::Inline,
        load_budget: 4096,
        ..PipelineConfig::new(VIEWPORT)
    };
    FramePipeline::new(&pipeline, source, summary).expect("pipeline")
}

/// [`pipeline_over`] the built-in terrain.
pub fn pipeline(config: SceneConfig) -> FramePipeline {
    let terrain = crate::builtin_terrain();
    let summary = crate::summary_of(&terrain);
    pipeline_over(terrain, summary, config)
}

/// A null backend standing for an ES 3 context with the sky on.
pub fn null_backend(config: &SceneConfig) -> NullBackend {
    NullBackend::new(config.buffer_bytes, CostModel { vertex_arrays: true, sky: true })
}

/// Pages in everything `camera` wants, then draws one frame on `backend`.
pub fn fly<B: RenderBackend>(
    pipeline: &mut FramePipeline,
    backend: &mut B,
    camera: &Camera,
) -> Result<FrameStats, FrameError<B::Error>> {
    pipeline.settle(camera, 1000)?;
    pipeline.frame(camera, backend)
}

/// Every node of the built-in terrain, read once (the scene tests that need
/// no paging).
pub fn terrain() -> &'static PreloadedTerrain {
    static TERRAIN: OnceLock<PreloadedTerrain> = OnceLock::new();
    TERRAIN
        .get_or_init(|| PreloadedTerrain::load(crate::builtin_terrain().as_ref()).expect("all nodes read"))
}

/// A camera over the scene tests' viewport ([`VIEWPORT`]) at `(x, y)`
/// metres from the built-in SRTM tile's south-west post
/// ([`crate::builtin_origin`]).
pub fn camera(x: f64, y: f64, altitude: f64, heading: f64, pitch: f64) -> Camera {
    let origin = crate::builtin_origin();
    crate::camera(VIEWPORT, origin.x + x, origin.y + y, altitude, heading, pitch)
}

/// Drawn height at every edge post and edge-segment midpoint of every tile,
/// keyed by level-0 post coordinates (doubled, so midpoints are integers).
/// Read from each tile's block: its surface triangles' edges that lie on
/// the tile's sides, each side walked counter-clockwise (each edge point
/// once per tile), whatever the tile's mesh.
pub fn edge_heights(
    list: &DrawList,
    staging: &[u8],
    altitude: f64,
    grid: u32,
) -> HashMap<(i64, i64), Vec<f64>> {
    let mut heights: HashMap<(i64, i64), Vec<f64>> = HashMap::new();
    let posts = list.uniforms.expect("a built list has its frame").posts;
    for tile in &list.tiles {
        let block = tile.block(staging);
        let drawn = |v: TileVertex| {
            if is_no_data(v.height) {
                // Triangles touching it are not drawn: no edge to agree on.
                return f64::NAN;
            }
            let [i, j] = v.post.map(f32::from);
            let [x, y] = tile.vertex_position(&posts, i, j).map(f64::from);
            let distance = (x * x + y * y + (v.height as f64 - altitude).powi(2)).sqrt();
            morphed_height(
                v.height,
                v.target,
                morph_factor(distance, tile.morph[0] as f64, tile.morph[1] as f64),
            )
        };
        let stride = 1i64 << tile.key.level;
        let base =
            (tile.key.x as i64 * grid as i64 * stride, tile.key.y as i64 * grid as i64 * stride);
        let at = |[i, j]: [u16; 2]| {
            (2 * (base.0 + i as i64 * stride), 2 * (base.1 + j as i64 * stride))
        };
        for t in (0..block.triangle_count()).filter(|&t| !block.is_skirt(t)) {
            let corners = block.triangle(t).map(|v| block.vertex(v as usize));
            for k in 0..3 {
                let (p, q) = (corners[k], corners[(k + 1) % 3]);
                let (a, b) = (drawn(p), drawn(q));
                if !on_one_side(p.post, q.post, grid) || a.is_nan() || b.is_nan() {
                    continue;
                }
                heights.entry(at(p.post)).or_default().push(a);
                let (p, q) = (at(p.post), at(q.post));
                heights.entry(((p.0 + q.0) / 2, (p.1 + q.1) / 2)).or_default().push((a + b) / 2.0);
            }
        }
    }
    heights
}

/// Whether posts `p` and `q` of a tile of `grid` cells lie on the same side of it.
fn on_one_side(p: [u16; 2], q: [u16; 2], grid: u32) -> bool {
    (0..2).any(|axis| p[axis] == q[axis] && (p[axis] == 0 || u32::from(p[axis]) == grid))
}

/// The largest disagreement, metres, between tiles sharing an edge point.
pub fn worst_edge_disagreement(list: &DrawList, staging: &[u8], altitude: f64, grid: u32) -> f64 {
    edge_heights(list, staging, altitude, grid)
        .values()
        .filter(|values| values.len() > 1)
        .map(|values| {
            let (lo, hi) =
                values.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
            hi - lo
        })
        .fold(0.0, f64::max)
}
