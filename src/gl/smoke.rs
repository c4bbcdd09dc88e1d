//! [`SmokePass`]: clears the target and draws one flat triangle with a GLSL
//! ES 1.00 program, the smallest drawing that proves a context, its shaders
//! and its read-back work. The triangle's right angle sits at the bottom
//! left, so a read-back also shows which way is up.

use std::rc::Rc;

use glam::{UVec2, Vec4};
use glow::HasContext;

use super::error::GlError;
use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, BufferUsage, Program, VertexArray};
use crate::gl_check;

const VERTEX_SOURCE: &str = include_str!("../../shaders/gles/smoke.vert");
const FRAGMENT_SOURCE: &str = include_str!("../../shaders/gles/smoke.frag");
const POSITION: u32 = 0;

/// The triangle in clip space: corners at bottom left, bottom right and top
/// left of a square 90 % the size of the target. It covers 40.5 % of it.
pub const SMOKE_TRIANGLE: [[f32; 2]; 3] = [[-0.9, -0.9], [0.9, -0.9], [-0.9, 0.9]];

/// The program, the triangle's vertices and (where the context has them) a
/// vertex array.
pub struct SmokePass {
    gl: Rc<Gl>,
    program: Program,
    colour: Option<glow::UniformLocation>,
    vertices: Buffer,
    vertex_array: Option<VertexArray>,
}

impl SmokePass {
    /// Builds the program and uploads the triangle's vertices.
    pub fn new(gl: &Rc<Gl>) -> Result<SmokePass, GlError> {
        let program = Program::build(
            gl,
            "smoke",
            VERTEX_SOURCE,
            FRAGMENT_SOURCE,
            &[(POSITION, "a_position")],
        )?;
        let colour = program.uniform_location("u_colour");
        let bytes: &[u8] = bytemuck::cast_slice(&SMOKE_TRIANGLE);
        let vertices = Buffer::new(gl, BufferTarget::Vertices, bytes.len(), BufferUsage::Static)?;
        vertices.upload_range(0, bytes)?;
        let vertex_array =
            if gl.caps().vertex_array_objects { Some(VertexArray::new(gl)?) } else { None };
        Ok(SmokePass { gl: Rc::clone(gl), program, colour, vertices, vertex_array })
    }

    /// Clears the bound target of `size` to `clear` and draws the triangle in
    /// `colour`. Sets every piece of state it relies on.
    #[allow(unsafe_code)]
    pub fn draw(&self, size: UVec2, clear: Vec4, colour: Vec4) -> Result<(), GlError> {
        let gl = &self.gl;
        // SAFETY: every object used is live in this context; the attribute
        // reads 3 vec2s from a buffer holding exactly that many.
        unsafe {
            gl.viewport(0, 0, size.x as i32, size.y as i32);
            for capability in
                [glow::DEPTH_TEST, glow::BLEND, glow::CULL_FACE, glow::SCISSOR_TEST, glow::DITHER]
            {
                gl.disable(capability);
            }
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.clear_color(clear.x, clear.y, clear.z, clear.w);
            gl.clear_depth_f32(1.0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            self.program.bind();
            gl.uniform_4_f32(self.colour.as_ref(), colour.x, colour.y, colour.z, colour.w);
            if let Some(vertex_array) = &self.vertex_array {
                vertex_array.bind();
            }
            self.vertices.bind();
            gl.enable_vertex_attrib_array(POSITION);
            gl.vertex_attrib_pointer_f32(POSITION, 2, glow::FLOAT, false, 0, 0);
            gl.draw_arrays(glow::TRIANGLES, 0, SMOKE_TRIANGLE.len() as i32);
            gl.disable_vertex_attrib_array(POSITION);
        }
        gl_check!(gl)
    }
}
