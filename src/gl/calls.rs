//! [`Calls`]: the GL calls the display's passes make, each counted by kind
//! as it is made ([`CallStats`]). The clear, sky and terrain passes and the
//! uploads reach GL only through this, so the counts are what the driver
//! was asked to do; the null backend's cost model must match them, and a
//! test flies a flight through both and compares.
//!
//! Every method has the contract of the glow call it wraps: a current
//! context that owns every object passed.

#![allow(unsafe_code)]
#![allow(clippy::missing_safety_doc)]

use glow::HasContext;

use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, Program, VertexArray};
use crate::render::CallStats;

/// Counting access to one context's calls.
#[derive(Clone, Copy)]
pub(crate) struct Calls<'a> {
    gl: &'a Gl,
    counted: bool,
}

impl<'a> Calls<'a> {
    pub fn new(gl: &'a Gl) -> Self {
        Calls { gl, counted: true }
    }

    /// The same calls, not counted: for state recorded into an object as
    /// it is made, before any frame (a window's vertex array), as making
    /// buffers and programs is not counted either.
    pub fn making_objects(gl: &'a Gl) -> Self {
        Calls { gl, counted: false }
    }

    fn tally(&self, f: impl FnOnce(&mut CallStats)) {
        if self.counted {
            self.gl.tally(f);
        }
    }

    fn state(&self) {
        self.tally(|c| c.state_changes += 1);
    }

    pub unsafe fn viewport(&self, width: u32, height: u32) {
        self.state();
        self.gl.viewport(0, 0, width as i32, height as i32);
    }

    pub unsafe fn enable(&self, cap: u32) {
        self.state();
        self.gl.enable(cap);
    }

    pub unsafe fn disable(&self, cap: u32) {
        self.state();
        self.gl.disable(cap);
    }

    pub unsafe fn depth_func(&self, func: u32) {
        self.state();
        self.gl.depth_func(func);
    }

    pub unsafe fn depth_mask(&self, on: bool) {
        self.state();
        self.gl.depth_mask(on);
    }

    pub unsafe fn cull_face(&self, face: u32) {
        self.state();
        self.gl.cull_face(face);
    }

    pub unsafe fn front_face(&self, winding: u32) {
        self.state();
        self.gl.front_face(winding);
    }

    pub unsafe fn color_mask(&self, on: bool) {
        self.state();
        self.gl.color_mask(on, on, on, on);
    }

    pub unsafe fn clear_color(&self, colour: [f32; 4]) {
        self.state();
        self.gl.clear_color(colour[0], colour[1], colour[2], colour[3]);
    }

    pub unsafe fn clear_depth(&self, depth: f32) {
        self.state();
        self.gl.clear_depth_f32(depth);
    }

    pub unsafe fn clear(&self, mask: u32) {
        self.tally(|c| c.clears += 1);
        self.gl.clear(mask);
    }

    pub unsafe fn use_program(&self, program: &Program) {
        self.tally(|c| c.program_binds += 1);
        program.bind();
    }

    pub unsafe fn bind_vertex_array(&self, vertex_array: Option<&VertexArray>) {
        self.tally(|c| c.vertex_array_binds += 1);
        match vertex_array {
            Some(vertex_array) => vertex_array.bind(),
            None => self.gl.bind_vertex_array(None),
        }
    }

    pub unsafe fn bind_buffer(&self, buffer: &Buffer) {
        self.tally(|c| c.buffer_binds += 1);
        buffer.bind();
    }

    /// glBindBuffer of `buffer` to `target`, whichever it was made for (a
    /// tile buffer holds vertices and indices).
    pub unsafe fn bind_buffer_to(&self, buffer: &Buffer, target: BufferTarget) {
        self.tally(|c| c.buffer_binds += 1);
        buffer.bind_to(target);
    }

    /// glBufferSubData into `buffer` (bound by the caller) at `offset`.
    pub unsafe fn buffer_sub_data(&self, buffer: &Buffer, offset: usize, bytes: &[u8]) {
        self.tally(|c| {
            c.upload_calls += 1;
            c.bytes_uploaded += bytes.len() as u64;
        });
        self.gl.buffer_sub_data_u8_slice(buffer.target().gl_enum(), offset as i32, bytes);
    }

    /// Uniform writes to a location the program lacks are no GL call.
    fn uniform(&self, at: Option<&glow::UniformLocation>) -> bool {
        if at.is_some() {
            self.tally(|c| c.uniform_writes += 1);
        }
        at.is_some()
    }

    pub unsafe fn uniform_4(&self, at: Option<&glow::UniformLocation>, v: [f32; 4]) {
        if self.uniform(at) {
            self.gl.uniform_4_f32(at, v[0], v[1], v[2], v[3]);
        }
    }

    /// glUniform4fv of `v.len() / 4` vectors from `at` on (one call).
    pub unsafe fn uniform_4v(&self, at: Option<&glow::UniformLocation>, v: &[f32]) {
        if self.uniform(at) {
            self.gl.uniform_4_f32_slice(at, v);
        }
    }

    pub unsafe fn uniform_3(&self, at: Option<&glow::UniformLocation>, v: [f32; 3]) {
        if self.uniform(at) {
            self.gl.uniform_3_f32(at, v[0], v[1], v[2]);
        }
    }

    pub unsafe fn uniform_matrix(&self, at: Option<&glow::UniformLocation>, m: &glam::Mat4) {
        if self.uniform(at) {
            self.gl.uniform_matrix_4_f32_slice(at, false, &m.to_cols_array());
        }
    }

    pub unsafe fn enable_attribute(&self, index: u32) {
        self.tally(|c| c.attribute_array_toggles += 1);
        self.gl.enable_vertex_attrib_array(index);
    }

    pub unsafe fn disable_attribute(&self, index: u32) {
        self.tally(|c| c.attribute_array_toggles += 1);
        self.gl.disable_vertex_attrib_array(index);
    }

    /// glVertexAttribPointer: `size` components of `kind` (normalised when
    /// `normalized`), `stride` and `offset` in bytes.
    pub unsafe fn attribute_pointer(
        &self,
        index: u32,
        size: i32,
        kind: u32,
        normalized: bool,
        stride: i32,
        offset: i32,
    ) {
        self.tally(|c| c.attribute_pointer_changes += 1);
        self.gl.vertex_attrib_pointer_f32(index, size, kind, normalized, stride, offset);
    }

    /// glDrawElements of `index_count` 16-bit indices from byte
    /// `index_byte_offset` of the bound index buffer, triangles.
    pub unsafe fn draw_triangles(&self, index_count: i32, index_byte_offset: i32) {
        self.tally(|c| {
            c.draw_calls += 1;
            c.triangles += index_count as u64 / 3;
        });
        self.gl.draw_elements(
            glow::TRIANGLES,
            index_count,
            glow::UNSIGNED_SHORT,
            index_byte_offset,
        );
    }

    /// glDrawArrays of `vertices` vertices as triangles.
    pub unsafe fn draw_array_triangles(&self, vertices: i32) {
        self.tally(|c| {
            c.draw_calls += 1;
            c.triangles += vertices as u64 / 3;
        });
        self.gl.draw_arrays(glow::TRIANGLES, 0, vertices);
    }
}
