//! The built-in terrain, built once into a cache under the target folder,
//! the frame pipeline over it on the null backend, shared-edge checks.

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

/// [`pipeline_over`] the built-in terrain with its node meshes for the
/// config's tau (what `ridgeline fly` draws).
pub fn pipeline(config: SceneConfig) -> FramePipeline {
    let terrain = crate::builtin_terrain();
    let summary = crate::summary_of(&terrain);
    pipeline_over(terrain, summary, config)
}

/// [`pipeline_over`] the built-in terrain drawn as regular grids.
pub fn pipeline_grid(config: SceneConfig) -> FramePipeline {
    let pyramid = crate::builtin_pyramid();
    let summary = TerrainSummary::from_pyramid(pyramid.info());
    pipeline_over(pyramid, summary, config)
}

/// A null backend for `pipeline`'s buffers, standing for an ES 3 context
/// with the sky on.
pub fn null_backend(pipeline: &FramePipeline) -> NullBackend {
    NullBackend::new(&pipeline.buffer_plan(), CostModel { vertex_arrays: true, sky: true })
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
        .get_or_init(|| PreloadedTerrain::load(crate::builtin_pyramid().as_ref()).expect("all nodes read"))
}

/// [`terrain`] with each node's mesh (the meshes of tau 1 px).
pub fn terrain_meshed() -> &'static PreloadedTerrain {
    static TERRAIN: OnceLock<PreloadedTerrain> = OnceLock::new();
    TERRAIN.get_or_init(|| {
        PreloadedTerrain::load(crate::builtin_terrain().as_ref()).expect("all nodes read")
    })
}

/// One tile's drawn height at an edge point, and how far the skirt hung
/// from that edge reaches below it (0 where the edge hangs none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeHeight {
    /// The morphed height the shader draws there, metres.
    pub height: f64,
    /// The tile's skirt depth on that side, or 0.
    pub skirt_m: f64,
}

/// For every point of a tile side, the drawn heights of all tiles there,
/// keyed by level-0 post coordinates (doubled, so midpoints are integers).
/// Each side is read from the tile's block (its surface triangles' edges
/// on the side, whatever the mesh) and sampled every `2^(level-1)` level-0
/// posts, so a tile's samples include those of a neighbour one level
/// coarser: every shared point is compared, T-junctions of irregular meshes
/// included.
pub fn edge_heights(
    list: &DrawList,
    staging: &[u8],
    altitude: f64,
    grid: u32,
) -> HashMap<(i64, i64), Vec<EdgeHeight>> {
    let mut heights: HashMap<(i64, i64), Vec<EdgeHeight>> = HashMap::new();
    let frame = list.uniforms.expect("a built list has its frame");
    let (posts, share) = (frame.posts, frame.morph_start_share);
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
            let [start, end] = tile.vertex_morph(&v, share);
            morphed_height(v.height, v.target, morph_factor(distance, start as f64, end as f64))
        };
        // Tile sides in half level-0 posts from its south-west corner (a
        // mesh tile's vertices count half its lattice's steps).
        let side = (2 * grid as i64) << tile.key.level;
        let base = (tile.key.x as i64 * side, tile.key.y as i64 * side);
        let scale = (2.0 * tile.vertex_step) as i64;
        let step = (1i64 << tile.key.level).max(2);
        for t in (0..block.triangle_count()).filter(|&t| !block.is_skirt(t)) {
            let corners = block.triangle(t).map(|v| block.vertex(v as usize));
            for k in 0..3 {
                let (p, q) = (corners[k], corners[(k + 1) % 3]);
                let (a, b) = (drawn(p), drawn(q));
                let at = |v: TileVertex| [v.post[0] as i64 * scale, v.post[1] as i64 * scale];
                let (pa, pb) = (at(p), at(q));
                let Some(edge) = side_of(pa, pb, side) else { continue };
                if a.is_nan() || b.is_nan() {
                    continue;
                }
                let skirt_m = tile.edge_skirt_m(edge) as f64;
                // Samples on the segment, both ends included.
                let axis = if pa[0] == pb[0] { 1 } else { 0 };
                let (lo, hi) = (pa[axis].min(pb[axis]), pa[axis].max(pb[axis]));
                let mut u = lo.div_euclid(step) * step;
                while u <= hi {
                    if u >= lo {
                        let f = (u - pa[axis]) as f64 / (pb[axis] - pa[axis]) as f64;
                        let mut point = pa;
                        point[axis] = u;
                        let key = (base.0 + point[0], base.1 + point[1]);
                        let height = a + f * (b - a);
                        let entry = heights.entry(key).or_default();
                        // Each tile once per point (segments share their ends).
                        if entry.last().is_none_or(|e| e.height != height || e.skirt_m != skirt_m) {
                            entry.push(EdgeHeight { height, skirt_m });
                        }
                    }
                    u += step;
                }
            }
        }
    }
    heights
}

/// The side (0 south, 1 east, 2 north, 3 west: the skirt bits' order) of
/// a tile `side` half level-0 posts wide that the segment `p`-`q` lies on.
fn side_of(p: [i64; 2], q: [i64; 2], side: i64) -> Option<usize> {
    match () {
        _ if p[1] == 0 && q[1] == 0 => Some(0),
        _ if p[0] == side && q[0] == side => Some(1),
        _ if p[1] == side && q[1] == side => Some(2),
        _ if p[0] == 0 && q[0] == 0 => Some(3),
        _ => None,
    }
}

/// The largest disagreement, metres, between tiles sharing an edge point
/// where none of them hangs a skirt.
pub fn worst_edge_disagreement(list: &DrawList, staging: &[u8], altitude: f64, grid: u32) -> f64 {
    edge_heights(list, staging, altitude, grid)
        .values()
        .filter(|values| values.len() > 1 && values.iter().all(|v| v.skirt_m == 0.0))
        .map(|values| {
            let (lo, hi) = values
                .iter()
                .fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v.height), hi.max(v.height)));
            hi - lo
        })
        .fold(0.0, f64::max)
}
