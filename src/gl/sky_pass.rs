//! The sky pass: one full-screen triangle shaded by view direction, with the
//! horizon lowered by the earth's curvature at the aircraft's height.

use std::rc::Rc;

use glow::HasContext;

use super::error::GlError;
use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, BufferUsage, Program, VertexArray};
use crate::gl_check;
use crate::render::{palette, FrameUniforms};

const VERTEX_SOURCE: &str = include_str!("../../shaders/gles/sky.vert");
const FRAGMENT_SOURCE: &str = include_str!("../../shaders/gles/sky.frag");
const CORNER: u32 = 0;
/// Covers the screen with one triangle.
const TRIANGLE: [[f32; 2]; 3] = [[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]];
/// Ground colour below the horizon where there is no terrain data.
const GROUND: [f32; 3] = [0.36, 0.31, 0.24];

pub struct SkyPass {
    gl: Rc<Gl>,
    program: Program,
    inverse_view_projection: Option<glow::UniformLocation>,
    horizon: Option<glow::UniformLocation>,
    zenith: Option<glow::UniformLocation>,
    haze: Option<glow::UniformLocation>,
    ground: Option<glow::UniformLocation>,
    corners: Buffer,
    vertex_array: Option<VertexArray>,
}

impl SkyPass {
    pub fn new(gl: &Rc<Gl>) -> Result<SkyPass, GlError> {
        let program =
            Program::build(gl, "sky", VERTEX_SOURCE, FRAGMENT_SOURCE, &[(CORNER, "a_corner")])?;
        let bytes: &[u8] = bytemuck::cast_slice(&TRIANGLE);
        let corners = Buffer::new(gl, BufferTarget::Vertices, bytes.len(), BufferUsage::Static)?;
        corners.upload_range(0, bytes)?;
        let vertex_array =
            if gl.caps().vertex_array_objects { Some(VertexArray::new(gl)?) } else { None };
        Ok(SkyPass {
            gl: Rc::clone(gl),
            inverse_view_projection: program.uniform_location("u_inverse_view_projection"),
            horizon: program.uniform_location("u_horizon"),
            zenith: program.uniform_location("u_zenith"),
            haze: program.uniform_location("u_haze"),
            ground: program.uniform_location("u_ground"),
            program,
            corners,
            vertex_array,
        })
    }

    /// Fills the target with sky and horizon. Sets the state it relies on:
    /// no depth test or writes, no culling, no blending.
    #[allow(unsafe_code)]
    pub fn draw(&self, frame: &FrameUniforms) -> Result<(), GlError> {
        let gl = &self.gl;
        let inverse = frame.view_projection.inverse().to_cols_array();
        // Sine of the dip of the horizon seen from the aircraft's altitude.
        let r = crate::camera::EARTH_RADIUS_M;
        let altitude = frame.camera_altitude.max(0.0);
        let dip = if frame.curvature { (1.0 - (r / (r + altitude)).powi(2)).sqrt() } else { 0.0 };
        // SAFETY: all objects are live in this context; three vertices are read.
        unsafe {
            gl.viewport(0, 0, frame.viewport[0] as i32, frame.viewport[1] as i32);
            gl.disable(glow::DEPTH_TEST);
            gl.depth_mask(false);
            gl.disable(glow::CULL_FACE);
            gl.disable(glow::BLEND);
            self.program.bind();
            gl.uniform_matrix_4_f32_slice(self.inverse_view_projection.as_ref(), false, &inverse);
            gl.uniform_4_f32(self.horizon.as_ref(), dip as f32, 0.0, 0.0, 0.0);
            let [z, h, g] = [palette::SKY_ZENITH, palette::SKY_HORIZON, GROUND];
            gl.uniform_3_f32(self.zenith.as_ref(), z[0], z[1], z[2]);
            gl.uniform_3_f32(self.haze.as_ref(), h[0], h[1], h[2]);
            gl.uniform_3_f32(self.ground.as_ref(), g[0], g[1], g[2]);
            if let Some(vertex_array) = &self.vertex_array {
                vertex_array.bind();
            }
            self.corners.bind();
            gl.enable_vertex_attrib_array(CORNER);
            gl.vertex_attrib_pointer_f32(CORNER, 2, glow::FLOAT, false, 0, 0);
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.disable_vertex_attrib_array(CORNER);
            gl.depth_mask(true);
        }
        gl_check!(gl)
    }
}
