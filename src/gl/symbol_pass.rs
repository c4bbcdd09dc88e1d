//! The symbol pass: draws a [`SymbolMesh`] (the reference symbols, or the
//! failure flag) over whatever the frame holds, in one glDrawArrays from
//! a stream buffer of fixed size. Its GL objects are its own (program,
//! buffer, vertex array where the context has them); it sets every piece
//! of state it relies on and gives back the fixed-function state the
//! renderer documents leaving (depth test and writes, culling).
//!
//! Call for call mirrored by `render::cost::symbols`.

use std::rc::Rc;

use super::calls::Calls;
use super::error::GlError;
use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, BufferUsage, Program, VertexArray};
use crate::gl_check;
use crate::symbology::{SymbolMesh, MAX_SYMBOL_VERTICES, VERTEX_BYTES};

const VERTEX_SOURCE: &str = include_str!("../../shaders/gles/symbol.vert");
const FRAGMENT_SOURCE: &str = include_str!("../../shaders/gles/symbol.frag");
const POSITION: u32 = 0;
const COLOUR: u32 = 1;

/// The symbol pass's objects on one context.
pub struct SymbolPass {
    gl: Rc<Gl>,
    program: Program,
    viewport: Option<glow::UniformLocation>,
    vertices: Buffer,
    vertex_array: Option<VertexArray>,
}

impl SymbolPass {
    /// Compiles the pass's program and makes its buffer, room for
    /// [`MAX_SYMBOL_VERTICES`].
    pub fn new(gl: &Rc<Gl>) -> Result<SymbolPass, GlError> {
        let program = Program::build(
            gl,
            "symbol",
            VERTEX_SOURCE,
            FRAGMENT_SOURCE,
            &[(POSITION, "a_position"), (COLOUR, "a_colour")],
        )?;
        let bytes = MAX_SYMBOL_VERTICES * VERTEX_BYTES;
        let vertices = Buffer::new(gl, BufferTarget::Vertices, bytes, BufferUsage::Stream)?;
        let vertex_array =
            if gl.caps().vertex_array_objects { Some(VertexArray::new(gl)?) } else { None };
        Ok(SymbolPass {
            gl: Rc::clone(gl),
            viewport: program.uniform_location("u_viewport"),
            program,
            vertices,
            vertex_array,
        })
    }

    /// Draws `mesh` over the bound target: no depth test or writes, no
    /// culling or blending; afterwards depth test and writes and back-face
    /// culling are on again. An empty mesh issues no call.
    #[allow(unsafe_code)]
    pub fn draw(&self, mesh: &SymbolMesh) -> Result<(), GlError> {
        if mesh.is_empty() {
            return Ok(());
        }
        let bytes = mesh.bytes();
        if bytes.len() > self.vertices.size() {
            return Err(GlError::InvalidRequest(format!(
                "{} bytes of symbols overrun their buffer of {}",
                bytes.len(),
                self.vertices.size()
            )));
        }
        let [width, height] = mesh.viewport();
        let calls = Calls::new(&self.gl);
        let stride = VERTEX_BYTES as i32;
        // SAFETY: every object is live in this context; the upload lies
        // inside the buffer (checked above) and the draw reads exactly the
        // vertices uploaded, whose attributes the pointers describe.
        unsafe {
            calls.viewport(width, height);
            calls.disable(glow::DEPTH_TEST);
            calls.depth_mask(false);
            calls.disable(glow::CULL_FACE);
            calls.disable(glow::BLEND);
            calls.use_program(&self.program);
            calls.uniform_4(self.viewport.as_ref(), [width as f32, height as f32, 0.0, 0.0]);
            if let Some(vertex_array) = &self.vertex_array {
                calls.bind_vertex_array(Some(vertex_array));
            }
            calls.bind_buffer(&self.vertices);
            calls.buffer_sub_data(&self.vertices, 0, bytes);
            calls.enable_attribute(POSITION);
            calls.enable_attribute(COLOUR);
            calls.attribute_pointer(POSITION, 2, glow::FLOAT, false, stride, 0);
            calls.attribute_pointer(COLOUR, 4, glow::UNSIGNED_BYTE, true, stride, 8);
            calls.draw_array_triangles(mesh.vertices().len() as i32);
            calls.disable_attribute(POSITION);
            calls.disable_attribute(COLOUR);
            if self.vertex_array.is_some() {
                calls.bind_vertex_array(None);
            }
            calls.depth_mask(true);
            calls.enable(glow::DEPTH_TEST);
            calls.enable(glow::CULL_FACE);
        }
        gl_check!(self.gl)
    }
}
