//! [`GlRenderer`]: the GL implementation of [`RenderBackend`]: clears, draws
//! the sky, then the terrain tiles, and uploads the frame's dirty ranges;
//! and, for the accuracy tool, draws the same tiles as positions.

use std::rc::Rc;

use glow::HasContext;

use super::error::GlError;
use super::handle::Gl;
use super::sky_pass::SkyPass;
use super::terrain_pass::{TerrainOutput, TerrainPass};
use crate::gl_check;
use crate::render::{palette, DrawList, RenderBackend};

pub struct GlRenderer {
    gl: Rc<Gl>,
    terrain: TerrainPass,
    sky: SkyPass,
    /// Clear colour with the sky pass off, so tests can look for gaps.
    sentinel: Option<[f32; 4]>,
}

impl GlRenderer {
    pub fn new(gl: &Rc<Gl>, grid_size: u32, buffer_bytes: u32) -> Result<GlRenderer, GlError> {
        Ok(GlRenderer {
            gl: Rc::clone(gl),
            terrain: TerrainPass::new(gl, grid_size, buffer_bytes)?,
            sky: SkyPass::new(gl)?,
            sentinel: None,
        })
    }

    /// With `Some(colour)` the sky is not drawn and the target is cleared to
    /// `colour`: any pixel still that colour below the horizon is a hole.
    pub fn set_sentinel(&mut self, colour: Option<[f32; 4]>) {
        self.sentinel = colour;
    }

    /// Clears the bound RGBA32F target to 0 (alpha 0: no terrain) and draws
    /// `list`'s tiles as camera-relative positions.
    pub fn draw_positions(&mut self, list: &DrawList) -> Result<(), GlError> {
        let Some(frame) = list.frame else { return Ok(()) };
        self.clear(frame.viewport, [0.0; 4])?;
        self.terrain.draw(list, TerrainOutput::Position)
    }

    /// Clears colour (to `colour`) and depth of the bound target, every
    /// write mask open and no scissor.
    #[allow(unsafe_code)]
    fn clear(&self, viewport: [u32; 2], colour: [f32; 4]) -> Result<(), GlError> {
        // SAFETY: clearing the bound target with every write mask open.
        unsafe {
            self.gl.viewport(0, 0, viewport[0] as i32, viewport[1] as i32);
            self.gl.disable(glow::SCISSOR_TEST);
            self.gl.color_mask(true, true, true, true);
            self.gl.depth_mask(true);
            self.gl.clear_color(colour[0], colour[1], colour[2], colour[3]);
            self.gl.clear_depth_f32(1.0);
            self.gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
        }
        gl_check!(self.gl)
    }

    /// Waits until the GPU has finished every command (for frame timing).
    #[allow(unsafe_code)]
    pub fn finish(&self) {
        // SAFETY: glFinish needs only a current context.
        unsafe { self.gl.finish() };
    }
}

impl RenderBackend for GlRenderer {
    type Error = GlError;

    fn upload(&mut self, staging: &[u8], ranges: &[std::ops::Range<u32>]) -> Result<(), GlError> {
        self.terrain.upload(staging, ranges)
    }

    fn draw(&mut self, list: &DrawList) -> Result<(), GlError> {
        let Some(frame) = list.frame else { return Ok(()) };
        let horizon = palette::SKY_HORIZON;
        self.clear(
            frame.viewport,
            self.sentinel.unwrap_or([horizon[0], horizon[1], horizon[2], 1.0]),
        )?;
        if self.sentinel.is_none() {
            self.sky.draw(&frame)?;
        }
        self.terrain.draw(list, TerrainOutput::Colour)
    }
}
