//! [`GlRenderer`]: the GL implementation of [`RenderBackend`]: uploads the
//! frame's dirty ranges, clears, draws the sky, then the terrain tiles. The
//! accuracy tool's passes reuse its parts: the same tiles drawn as
//! positions, and the clear and sky under the truth.
//!
//! Every call goes through [`Calls`], so [`RenderBackend::take_calls`]
//! reports what the driver was asked to do.
//!
//! **Embedding.** A frame draws into whatever framebuffer is bound, over the
//! viewport of the frame's camera, and sets every piece of state it relies
//! on. It leaves behind (`examples/embed.rs` checks each):
//! - the viewport of the frame; depth test on with `GL_LESS`, depth and
//!   colour writes on; back faces culled, counter-clockwise front faces;
//!   blending and the scissor test off; all other state (stencil, dithering,
//!   polygon offset, pixel storage) as the caller left it;
//! - the terrain program in use, `GL_ARRAY_BUFFER` bound to the tile
//!   buffer (every tile's vertices and indices), every vertex attribute
//!   array disabled;
//! - no vertex array object bound where the context has them (where it has
//!   none, `GL_ELEMENT_ARRAY_BUFFER` of the default one is the tile buffer too);
//! - clear colour the sky's horizon colour, clear depth 1.
//!
//! With reference symbols drawn over the frame
//! ([`SymbolBackend::draw_symbols`], `FramePipeline::frame_with_symbols`)
//! and on a withdrawn frame, the same but for the program and buffers: the
//! symbol pass's program is in use and `GL_ARRAY_BUFFER` is bound to its
//! vertex buffer. A withdrawn frame's clear colour is
//! [`WITHDRAWN_CLEAR`](crate::symbology::flag::WITHDRAWN_CLEAR).

use std::rc::Rc;

use super::calls::Calls;
use super::error::GlError;
use super::handle::Gl;
use super::sky_pass::SkyPass;
use super::symbol_pass::SymbolPass;
use super::terrain_pass::{TerrainOutput, TerrainPass};
use crate::gl_check;
use crate::render::{
    palette, BufferPlan, CallStats, CostModel, DrawList, FrameOutput, FrameUniforms, RenderBackend,
    SymbolBackend,
};
use crate::symbology::{flag::WITHDRAWN_CLEAR, SymbolMesh};

/// The display's passes on one context.
pub struct GlRenderer {
    gl: Rc<Gl>,
    terrain: TerrainPass,
    sky: SkyPass,
    symbols: SymbolPass,
    /// Clear colour with the sky pass off, so tests can look for gaps.
    sentinel: Option<[f32; 4]>,
}

impl GlRenderer {
    /// The passes over the buffers of `plan` (a pipeline's,
    /// `FramePipeline::buffer_plan`): the tile buffer and, when the plan
    /// has clusters, the cluster index buffer and, with vertex array
    /// objects, one per window of the vertex buffer, its pointers set here
    /// once (calls made before any frame, not counted).
    pub fn new(gl: &Rc<Gl>, plan: &BufferPlan) -> Result<GlRenderer, GlError> {
        let mut terrain = TerrainPass::new(gl, plan.buffer_bytes)?;
        if let Some(index_bytes) = plan.cluster_index_bytes {
            terrain.prepare_clusters(index_bytes)?;
        }
        Ok(GlRenderer {
            gl: Rc::clone(gl),
            terrain,
            sky: SkyPass::new(gl)?,
            symbols: SymbolPass::new(gl)?,
            sentinel: None,
        })
    }

    /// With `Some(colour)` the sky is not drawn and the target is cleared to
    /// `colour`: any pixel still that colour below the horizon is a hole.
    pub fn set_sentinel(&mut self, colour: Option<[f32; 4]>) {
        self.sentinel = colour;
    }

    /// What the null backend must model to count this renderer's calls.
    pub fn cost_model(&self) -> CostModel {
        CostModel {
            vertex_arrays: self.gl.caps().vertex_array_objects,
            sky: self.sentinel.is_none(),
        }
    }

    /// Clears the bound RGBA32F target to 0 (alpha 0: no terrain) and draws
    /// `list`'s tiles (built for the frame of `frame`) as camera-relative
    /// positions (the accuracy tool's position pass over the tiles this
    /// renderer holds).
    pub fn draw_positions(
        &mut self,
        list: &DrawList,
        frame: &FrameUniforms,
    ) -> Result<(), GlError> {
        self.clear(frame.viewport, [0.0; 4])?;
        self.terrain.draw(list, frame, TerrainOutput::Position)
    }

    /// Clears the bound target and draws the sky of `frame` (or clears to the
    /// sentinel): what a frame shows before its terrain, for passes that
    /// draw other terrain (the truth) under the display's sky.
    pub fn draw_background(&mut self, frame: &FrameUniforms) -> Result<(), GlError> {
        let horizon = palette::SKY_HORIZON;
        let sky = [horizon[0], horizon[1], horizon[2], 1.0];
        self.clear(frame.viewport, self.sentinel.unwrap_or(sky))?;
        if self.sentinel.is_none() {
            self.sky.draw(frame)?;
        }
        Ok(())
    }

    /// Clears colour (to `colour`) and depth of the bound target, every
    /// write mask open and no scissor.
    #[allow(unsafe_code)]
    fn clear(&self, viewport: [u32; 2], colour: [f32; 4]) -> Result<(), GlError> {
        let calls = Calls::new(&self.gl);
        // SAFETY: clearing the bound target with every write mask open.
        unsafe {
            calls.viewport(viewport[0], viewport[1]);
            calls.disable(glow::SCISSOR_TEST);
            calls.color_mask(true);
            calls.depth_mask(true);
            calls.clear_color(colour);
            calls.clear_depth(1.0);
            calls.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
        }
        gl_check!(self.gl)
    }
}

impl RenderBackend for GlRenderer {
    type Error = GlError;

    /// One glBufferSubData per dirty range, into the tile buffer (and the
    /// cluster index buffer) at the same offsets.
    fn upload_frame(&mut self, frame: &FrameOutput<'_>) -> Result<(), GlError> {
        self.terrain.upload(frame.staging, frame.dirty)?;
        if let Some((staging, dirty)) = frame.indices {
            self.terrain.upload_indices(staging, dirty)?;
        }
        Ok(())
    }

    /// Clears, draws the sky and the tiles of `list` from the tile buffer.
    fn draw_frame(&mut self, list: &DrawList, uniforms: &FrameUniforms) -> Result<(), GlError> {
        self.gl.tally(|c| c.frames += 1);
        self.draw_background(uniforms)?;
        self.terrain.draw(list, uniforms, TerrainOutput::Colour)
    }

    #[allow(unsafe_code)]
    fn finish(&mut self) {
        // SAFETY: glFinish needs only a current context. Not counted: it
        // waits, it draws nothing, and the null backend has nothing to wait for.
        unsafe { glow::HasContext::finish(&**self.gl) };
    }

    fn take_calls(&mut self) -> CallStats {
        self.gl.take_calls()
    }
}

impl SymbolBackend for GlRenderer {
    fn draw_symbols(&mut self, symbols: &SymbolMesh) -> Result<(), GlError> {
        self.symbols.draw(symbols)
    }

    fn render_withdrawn(&mut self, flag: &SymbolMesh) -> Result<(), GlError> {
        self.gl.tally(|c| c.frames += 1);
        self.clear(flag.viewport(), WITHDRAWN_CLEAR)?;
        self.symbols.draw(flag)
    }
}
