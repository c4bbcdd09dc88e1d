//! The sky pass: one full-screen triangle shaded by view direction, with the
//! horizon lowered by the earth's curvature at the aircraft's height.

use std::rc::Rc;

use super::calls::Calls;
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

pub struct SkyPass {
    gl: Rc<Gl>,
    program: Program,
    inverse_view_projection: Option<glow::UniformLocation>,
    horizon: Option<glow::UniformLocation>,
    zenith: Option<glow::UniformLocation>,
    haze: Option<glow::UniformLocation>,
    no_data: Option<glow::UniformLocation>,
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
            no_data: program.uniform_location("u_no_data"),
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
        let inverse = frame.view_projection.inverse();
        let dip = if frame.curvature { horizon_dip_sine(frame) } else { 0.0 };
        let calls = Calls::new(gl);
        // SAFETY: all objects are live in this context; three vertices are read.
        unsafe {
            calls.viewport(frame.viewport[0], frame.viewport[1]);
            calls.disable(glow::DEPTH_TEST);
            calls.depth_mask(false);
            calls.disable(glow::CULL_FACE);
            calls.disable(glow::BLEND);
            calls.use_program(&self.program);
            calls.uniform_matrix(self.inverse_view_projection.as_ref(), &inverse);
            calls.uniform_4(self.horizon.as_ref(), [dip as f32, 0.0, 0.0, 0.0]);
            calls.uniform_3(self.zenith.as_ref(), palette::SKY_ZENITH);
            calls.uniform_3(self.haze.as_ref(), palette::SKY_HORIZON);
            calls.uniform_3(self.no_data.as_ref(), palette::NO_DATA_HATCH);
            if let Some(vertex_array) = &self.vertex_array {
                calls.bind_vertex_array(Some(vertex_array));
            }
            calls.bind_buffer(&self.corners);
            calls.enable_attribute(CORNER);
            calls.attribute_pointer(CORNER, 2, glow::FLOAT, false, 0, 0);
            calls.draw_array_triangles(3);
            calls.disable_attribute(CORNER);
            calls.depth_mask(true);
        }
        gl_check!(gl)
    }
}

/// Sine of the dip, below level, of the horizon of a sphere at
/// `frame.horizon_floor_m` seen from the aircraft's altitude: below it a
/// pixel no terrain covered is one whose ray would meet terrain the display
/// does not have (the no-data hatching); above it, one whose ray passes over
/// every height there can be (the sky).
fn horizon_dip_sine(frame: &FrameUniforms) -> f64 {
    let floor = frame.horizon_floor_m as f64;
    let r = crate::camera::EARTH_RADIUS_M + floor;
    let height = (frame.camera_altitude - floor).max(0.0);
    (1.0 - (r / (r + height)).powi(2)).sqrt()
}
