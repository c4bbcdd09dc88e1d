//! The brute-force ground truth: every level-0 post of a region drawn as a
//! vertex, with no LOD, no morph, no skirts and no culling, by the terrain
//! pass itself. Each chunk of the [`TruthMesh`] is a tile of
//! [`CHUNK_CELLS`] cells whose morph never starts and whose skirts hang 0 m
//! (so they have no area); its south-west post is numbered from the frame's
//! anchor post, exactly as tiles are placed, and the frame uniforms are the
//! scene's, so an image of it compares pixel for pixel with
//! the LOD image. Chunks are drawn nearest first, as the display's tiles
//! are, so that both get the same early depth rejection.
//!
//! [`crate::display::Display::render_truth`] draws it into the display's own
//! context (clear and sky as the display does, then this pass).

mod mesh;

pub use mesh::{
    TruthChunk, TruthError, TruthMesh, TruthRegion, CHUNK_CELLS, CHUNK_TRIANGLES, MAX_TRUTH_POSTS,
};

use std::rc::Rc;

use super::error::GlError;
use super::handle::Gl;
use super::terrain_pass::{TerrainOutput, TerrainPass};
use crate::lod::TileKey;
use crate::render::{DrawList, FrameUniforms, TileUniforms};
use crate::tiles::grid;
use crate::tiles::vertex::tile_bytes;

/// `u_morph` that never morphs: the factor is 0 at every distance a frame can have.
const NO_MORPH: [f32; 2] = [1e30, 2e30];

/// What drawing the truth cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TruthFrameStats {
    /// Surface triangles (the chunks' zero-depth skirts are submitted too).
    pub triangles: u64,
    pub draw_calls: usize,
    /// Clear, sky and every chunk, measured up to glFinish.
    pub frame_ms: f64,
}

struct ChunkDraw {
    key: TileKey,
    /// South-west level-0 post (numbered from the frame's anchor per frame).
    first_post: [i64; 2],
    /// Where the chunk's vertices start in the vertex buffer.
    byte_offset: u32,
}

/// The truth mesh on the GPU, drawn by a terrain pass of its own.
pub struct TruthPass {
    terrain: TerrainPass,
    chunks: Vec<ChunkDraw>,
    triangles: u64,
}

impl TruthPass {
    /// Uploads `mesh` into the vertex buffer of a terrain pass whose tile
    /// grid is a chunk.
    pub fn new(gl: &Rc<Gl>, mesh: &TruthMesh) -> Result<TruthPass, GlError> {
        let vertices: Vec<_> =
            mesh.chunks.iter().flat_map(|c| c.vertices.iter().copied()).collect();
        let bytes: &[u8] = bytemuck::cast_slice(&vertices);
        let too_large = || {
            GlError::InvalidRequest(format!("truth mesh of {} bytes exceeds 2^32-1", bytes.len()))
        };
        let size = u32::try_from(bytes.len()).map_err(|_| too_large())?;
        let terrain = TerrainPass::new(gl, CHUNK_CELLS, size)?;
        terrain.upload(bytes, &[0..size])?;
        debug_assert!(mesh
            .chunks
            .iter()
            .all(|c| c.vertices.len() == grid::vertex_count(CHUNK_CELLS)));
        let chunks = mesh
            .chunks
            .iter()
            .enumerate()
            .map(|(k, chunk)| ChunkDraw {
                key: TileKey::new(
                    0,
                    chunk.first_post[0] / CHUNK_CELLS,
                    chunk.first_post[1] / CHUNK_CELLS,
                ),
                first_post: mesh.chunk_first_post(chunk),
                byte_offset: k as u32 * tile_bytes(CHUNK_CELLS),
            })
            .collect();
        Ok(TruthPass { terrain, chunks, triangles: mesh.triangles() })
    }

    /// Surface triangles drawn per frame (all of them: nothing is culled).
    pub fn triangles(&self) -> u64 {
        self.triangles
    }

    /// Draw calls per frame: one per chunk.
    pub fn draw_calls(&self) -> usize {
        self.chunks.len()
    }

    /// Draws every chunk into the bound target with `frame`'s uniforms
    /// (whose post numbering places the chunks relative to the camera),
    /// writing `output`. Sets the terrain pass's state; does not clear.
    pub fn draw(&self, frame: &FrameUniforms, output: TerrainOutput) -> Result<(), GlError> {
        let tiles = self
            .chunks
            .iter()
            .map(|chunk| TileUniforms {
                key: chunk.key,
                first_post: frame.posts.number(chunk.first_post),
                post_step: 1.0,
                morph: NO_MORPH,
                skirt_depth: 0.0,
                byte_offset: chunk.byte_offset,
            })
            .collect();
        let indices_per_tile = grid::index_count(CHUNK_CELLS) as u32;
        let mut list = DrawList { frame: Some(*frame), tiles, indices_per_tile };
        // As the display does: a fair brute force gets early z too.
        list.sort_front_to_back(CHUNK_CELLS);
        self.terrain.draw(&list, output)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::clipmap::LoaderMode;
    use crate::display::{Display, DisplayConfig};
    use crate::gl::GlBackend;
    use crate::node::NodeSource;
    use crate::procedural::{EarthParams, ProceduralEarth};
    use crate::scene::TerrainSummary;
    use glam::{DVec3, UVec2};
    use image::RgbaImage;
    use std::sync::Arc;

    const SENTINEL: [u8; 4] = [255, 0, 255, 255];

    fn coverage(image: &RgbaImage) -> f64 {
        image.pixels().filter(|p| p.0 != SENTINEL).count() as f64 / image.pixels().len() as f64
    }

    fn mean_difference(a: &RgbaImage, b: &RgbaImage) -> f64 {
        let sum: u64 = a.as_raw().iter().zip(b.as_raw()).map(|(x, y)| x.abs_diff(*y) as u64).sum();
        sum as f64 / a.as_raw().len() as f64
    }

    fn small_earth() -> (Arc<ProceduralEarth>, TerrainSummary) {
        // 512 cells a side in nodes of the default tile grid.
        let params = EarthParams { node_size: 32, levels: 5, border: 1, spacing_m: 30.0, seed: 7 };
        let earth = Arc::new(ProceduralEarth::new(params).expect("small earth"));
        let [low, high] = earth.height_bounds();
        let summary = TerrainSummary {
            delta_per_level: (0..params.levels).map(|lod| earth.delta_bound(lod) as f64).collect(),
            height_range: (low as f32, high as f32),
        };
        (earth, summary)
    }

    /// Draws `camera` with the LOD display at `tau_px`, then the truth;
    /// returns both images and the levels of the tiles drawn.
    fn lod_and_truth(tau_px: f64, camera: &Camera) -> (RgbaImage, RgbaImage, Vec<u8>) {
        let (earth, summary) = small_earth();
        let mut config = DisplayConfig::new(GlBackend::Egl, UVec2::from(camera.viewport));
        config.loader = LoaderMode::Inline;
        config.load_budget = 4096;
        config.sentinel = Some(SENTINEL.map(|c| c as f32 / 255.0));
        config.scene.lod.tau_px = tau_px;
        let source: Arc<dyn NodeSource> = earth.clone();
        let mut display = Display::new(&config, source, summary).expect("display");
        display.settle(camera, 100).expect("settles");
        display.frame(camera).expect("LOD frame");
        assert_eq!(display.scene().draw_list().frame, Some(display.frame_uniforms(camera)));
        let levels = display.scene().draw_list().tiles.iter().map(|t| t.key.level).collect();
        let lod = display.read_pixels().expect("read LOD");
        let mesh =
            TruthMesh::load(earth.as_ref(), TruthRegion::whole(earth.layout())).expect("mesh");
        let truth = TruthPass::new(display.context().gl(), &mesh).expect("truth pass");
        let stats = display.render_truth(camera, &truth).expect("truth frame");
        assert_eq!((stats.triangles, stats.draw_calls), (2 * 512 * 512, 16));
        (lod, display.read_pixels().expect("read truth"), levels)
    }

    fn camera_over(earth: &ProceduralEarth) -> Camera {
        let posts = (0..64).flat_map(|j| (0..64).map(move |i| (i * 8, j * 8)));
        let highest = posts.map(|(i, j)| earth.sample(i, j)).fold(f32::MIN, f32::max);
        Camera {
            position: DVec3::new(2000.0, 1500.0, highest as f64 + 300.0),
            heading_deg: 40.0,
            pitch_deg: -20.0,
            roll_deg: 5.0,
            fov_x_deg: 60.0,
            viewport: [192, 108],
        }
    }

    /// Where the LOD display draws only level-0 tiles it is the truth, to
    /// the pixel but for rounding at triangle edges: same transform, same
    /// colours. Coarser tiles cover the same pixels with close colours.
    #[test]
    fn truth_and_lod_images_agree() {
        let camera = camera_over(&small_earth().0);
        let (lod, truth, levels) = lod_and_truth(1.0, &camera);
        assert!(levels.iter().all(|&l| l == 0), "a rough earth keeps level 0 at tau 1 px");
        let differing = lod.pixels().zip(truth.pixels()).filter(|(a, b)| a != b).count();
        println!(
            "level 0 only: {} tiles, {differing} pixels differ, coverage {:.3}",
            levels.len(),
            coverage(&truth)
        );
        assert!(coverage(&truth) > 0.6, "the truth covers the picture below the horizon");
        assert!(differing * 200 < lod.pixels().len(), "{differing} pixels differ");
        let (coarse, truth, levels) = lod_and_truth(16.0, &camera);
        let difference = mean_difference(&coarse, &truth);
        let (lod_cover, truth_cover) = (coverage(&coarse), coverage(&truth));
        let coarsest = levels.iter().max();
        println!("tau 16: coarsest {coarsest:?}, coverage {lod_cover:.3} / {truth_cover:.3}, difference {difference:.2}");
        assert!(levels.iter().any(|&l| l > 0), "tau 16 px draws coarser tiles");
        assert!((lod_cover - truth_cover).abs() < 0.02, "both cover the same pixels");
        assert!(difference < 6.0, "colours agree");
    }
}
