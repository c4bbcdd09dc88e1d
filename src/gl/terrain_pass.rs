//! The terrain pass: shared grid positions and indices, one vertex buffer
//! mirroring the tile allocator's staging copy, and per tile only uniforms
//! and an attribute offset (Polok). Vertex shaders read no textures.
//!
//! Two fragment programs share the vertex shader: the display's colours, and
//! camera-relative positions for the accuracy tool ([`TerrainOutput`]), so
//! what the accuracy tool measures is the geometry the display draws.

use std::rc::Rc;

use glow::HasContext;

use super::error::GlError;
use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, BufferUsage, Program, VertexArray};
use crate::gl_check;
use crate::render::{palette, DrawList, FrameUniforms, TileUniforms};
use crate::tiles::{TileGrid, TileVertex};

const VERTEX_SOURCE: &str = include_str!("../../shaders/gles/terrain.vert");
const FRAGMENT_SOURCE: &str = include_str!("../../shaders/gles/terrain.frag");
const POSITION_SOURCE: &str = include_str!("../../shaders/gles/position.frag");

const GRID: u32 = 0;
const HEIGHT: u32 = 1;
const NORMAL: u32 = 2;
const VERTEX_STRIDE: i32 = std::mem::size_of::<TileVertex>() as i32;
const NORMAL_OFFSET: i32 = 8;

struct Locations {
    view_projection: Option<glow::UniformLocation>,
    tile: Option<glow::UniformLocation>,
    posts: Option<glow::UniformLocation>,
    morph: Option<glow::UniformLocation>,
    frame: Option<glow::UniformLocation>,
    sun: Option<glow::UniformLocation>,
    awareness: Option<glow::UniformLocation>,
    haze: Option<glow::UniformLocation>,
}

/// What the terrain pass writes per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TerrainOutput {
    /// The display's shaded colours.
    Colour,
    /// The camera-relative surface position, into an RGBA32F target.
    Position,
}

/// Where each tile's vertex data is.
#[derive(Clone, Copy)]
pub enum TileVertices<'a> {
    /// At the tile's byte offset in the pass's one height buffer (Polok's batching).
    Shared,
    /// In a buffer of the tile's own, from byte 0 (plain Chunked LOD: a
    /// vertex buffer swap per draw); tiles without a buffer are skipped.
    PerTile(&'a dyn Fn(&TileUniforms) -> Option<&'a Buffer>),
}

/// A linked terrain program and its uniform locations (the position program
/// has no lighting uniforms: those locations are `None`, and setting them is
/// a no-op).
struct TerrainProgram {
    program: Program,
    at: Locations,
}

impl TerrainProgram {
    fn build(gl: &Rc<Gl>, name: &str, fragment: &str) -> Result<TerrainProgram, GlError> {
        let attributes = [(GRID, "a_grid"), (HEIGHT, "a_height"), (NORMAL, "a_normal")];
        let program = Program::build(gl, name, VERTEX_SOURCE, fragment, &attributes)?;
        let at = Locations {
            view_projection: program.uniform_location("u_view_projection"),
            tile: program.uniform_location("u_tile"),
            posts: program.uniform_location("u_posts"),
            morph: program.uniform_location("u_morph"),
            frame: program.uniform_location("u_frame"),
            sun: program.uniform_location("u_sun"),
            awareness: program.uniform_location("u_awareness"),
            haze: program.uniform_location("u_haze"),
        };
        Ok(TerrainProgram { program, at })
    }
}

pub struct TerrainPass {
    gl: Rc<Gl>,
    colour: TerrainProgram,
    position: TerrainProgram,
    grid_vertices: Buffer,
    grid_indices: Buffer,
    heights: Buffer,
    vertex_array: Option<VertexArray>,
    index_count: i32,
    grid_size: u32,
}

impl TerrainPass {
    /// Builds the program, the shared grid of `grid_size` and a height
    /// buffer of `buffer_bytes` (the tile allocator's capacity).
    pub fn new(gl: &Rc<Gl>, grid_size: u32, buffer_bytes: u32) -> Result<TerrainPass, GlError> {
        let colour = TerrainProgram::build(gl, "terrain", FRAGMENT_SOURCE)?;
        let position = TerrainProgram::build(gl, "terrain positions", POSITION_SOURCE)?;
        let grid = TileGrid::new(grid_size);
        let vertex_bytes: &[u8] = bytemuck::cast_slice(&grid.vertices);
        let grid_vertices =
            Buffer::new(gl, BufferTarget::Vertices, vertex_bytes.len(), BufferUsage::Static)?;
        grid_vertices.upload_range(0, vertex_bytes)?;
        let index_bytes: &[u8] = bytemuck::cast_slice(&grid.indices);
        let grid_indices =
            Buffer::new(gl, BufferTarget::Indices, index_bytes.len(), BufferUsage::Static)?;
        grid_indices.upload_range(0, index_bytes)?;
        let heights =
            Buffer::new(gl, BufferTarget::Vertices, buffer_bytes as usize, BufferUsage::Dynamic)?;
        let vertex_array =
            if gl.caps().vertex_array_objects { Some(VertexArray::new(gl)?) } else { None };
        Ok(TerrainPass {
            gl: Rc::clone(gl),
            colour,
            position,
            grid_vertices,
            grid_indices,
            heights,
            vertex_array,
            index_count: grid.indices.len() as i32,
            grid_size,
        })
    }

    /// Copies the dirty ranges of the staging copy into the height buffer at
    /// the same offsets: one glBufferSubData per range (per run piece).
    pub fn upload(&self, staging: &[u8], ranges: &[std::ops::Range<u32>]) -> Result<(), GlError> {
        for range in ranges {
            let bytes = &staging[range.start as usize..range.end as usize];
            self.heights.upload_range(range.start as usize, bytes)?;
        }
        Ok(())
    }

    /// Draws every tile of `list`, writing `output`, in the frame's depth
    /// slices (far first, depth cleared between). Sets all the state it
    /// relies on: depth test and writes on, back faces culled, no blending,
    /// no scissor.
    pub fn draw(&self, list: &DrawList, output: TerrainOutput) -> Result<(), GlError> {
        self.draw_from(list, output, TileVertices::Shared)
    }

    /// [`Self::draw`] with the tiles' vertex data where `vertices` says.
    #[allow(unsafe_code)]
    pub fn draw_from(
        &self,
        list: &DrawList,
        output: TerrainOutput,
        vertices: TileVertices<'_>,
    ) -> Result<(), GlError> {
        let Some(frame) = list.frame else { return Ok(()) };
        let gl = &self.gl;
        let program = match output {
            TerrainOutput::Colour => &self.colour,
            TerrainOutput::Position => &self.position,
        };
        // SAFETY: every object bound is live in this context; attribute
        // pointers stay inside the buffers (grid vertices are indexed by the
        // shared indices, each tile's offset leaves room for a whole tile, as
        // the allocator placed it).
        unsafe {
            gl.viewport(0, 0, frame.viewport[0] as i32, frame.viewport[1] as i32);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(true);
            gl.enable(glow::CULL_FACE);
            gl.cull_face(glow::BACK);
            gl.front_face(glow::CCW);
            gl.disable(glow::BLEND);
            // The depth clear between slices must reach the whole target.
            gl.disable(glow::SCISSOR_TEST);
            program.program.bind();
            set_frame_uniforms(gl, &program.at, &frame);
            if let Some(vertex_array) = &self.vertex_array {
                vertex_array.bind();
            }
            self.grid_indices.bind();
            self.grid_vertices.bind();
            gl.enable_vertex_attrib_array(GRID);
            gl.vertex_attrib_pointer_f32(GRID, 3, glow::UNSIGNED_SHORT, false, 8, 0);
            self.heights.bind();
            gl.enable_vertex_attrib_array(HEIGHT);
            gl.enable_vertex_attrib_array(NORMAL);
            // Far slice first; then a clear depth for the near slice.
            let slices = &frame.slices;
            if let Some(far) = slices.far {
                self.draw_slice(&program.at, list, &frame, far, false, vertices);
                gl.clear(glow::DEPTH_BUFFER_BIT);
            }
            self.draw_slice(&program.at, list, &frame, slices.near, true, vertices);
            gl.disable_vertex_attrib_array(GRID);
            gl.disable_vertex_attrib_array(HEIGHT);
            gl.disable_vertex_attrib_array(NORMAL);
        }
        gl_check!(gl)
    }

    /// Draws the tiles of `list` that reach into one depth slice
    /// (`near_slice` or the far one) with its `view_projection`.
    #[allow(unsafe_code)]
    fn draw_slice(
        &self,
        at: &Locations,
        list: &DrawList,
        frame: &FrameUniforms,
        view_projection: glam::Mat4,
        near_slice: bool,
        vertices: TileVertices<'_>,
    ) {
        // SAFETY: the terrain program is bound and its location comes from it.
        unsafe {
            self.gl.uniform_matrix_4_f32_slice(
                at.view_projection.as_ref(),
                false,
                &view_projection.to_cols_array(),
            )
        };
        for tile in &list.tiles {
            let (in_near, in_far) =
                frame.slices.tile_slices(tile, &frame.posts, self.grid_size as f32);
            if !(if near_slice { in_near } else { in_far }) {
                continue;
            }
            let offset = match vertices {
                TileVertices::Shared => tile.byte_offset,
                TileVertices::PerTile(buffer_of) => match buffer_of(tile) {
                    Some(buffer) => {
                        buffer.bind();
                        0
                    }
                    None => continue,
                },
            };
            self.draw_tile(at, tile, offset);
        }
    }

    #[allow(unsafe_code)]
    fn draw_tile(&self, at: &Locations, tile: &TileUniforms, byte_offset: u32) {
        let gl = &self.gl;
        let offset = byte_offset as i32;
        // SAFETY: the tile's vertex buffer is bound and holds a whole tile's
        // vertices from `offset`.
        unsafe {
            gl.uniform_4_f32(
                at.tile.as_ref(),
                tile.first_post[0],
                tile.first_post[1],
                tile.post_step,
                0.0,
            );
            gl.uniform_4_f32(
                at.morph.as_ref(),
                tile.morph[0],
                tile.morph[1],
                tile.skirt_depth,
                0.0,
            );
            gl.vertex_attrib_pointer_f32(HEIGHT, 2, glow::FLOAT, false, VERTEX_STRIDE, offset);
            gl.vertex_attrib_pointer_f32(
                NORMAL,
                4,
                glow::BYTE,
                true,
                VERTEX_STRIDE,
                offset + NORMAL_OFFSET,
            );
            gl.draw_elements(glow::TRIANGLES, self.index_count, glow::UNSIGNED_SHORT, 0);
        }
    }
}

/// Sets the per-frame uniforms of the bound program `at` belongs to.
#[allow(unsafe_code)]
fn set_frame_uniforms(gl: &Gl, at: &Locations, frame: &FrameUniforms) {
    let curvature = if frame.curvature { 1.0 / (2.0 * crate::camera::EARTH_RADIUS_M) } else { 0.0 };
    let sun = frame.sun_direction;
    let haze = palette::SKY_HORIZON;
    // SAFETY: the program is bound; locations come from it.
    unsafe {
        gl.uniform_4_f32(
            at.frame.as_ref(),
            frame.camera_altitude as f32,
            curvature as f32,
            0.0,
            0.0,
        );
        let posts = &frame.posts;
        gl.uniform_4_f32(
            at.posts.as_ref(),
            posts.spacing[0],
            posts.spacing[1],
            posts.offset[0],
            posts.offset[1],
        );
        gl.uniform_3_f32(at.sun.as_ref(), sun.x, sun.y, sun.z);
        let awareness = (frame.warning_above_m, frame.caution_below_m, frame.fog_distance_m);
        gl.uniform_4_f32(at.awareness.as_ref(), awareness.0, awareness.1, awareness.2, 0.0);
        gl.uniform_3_f32(at.haze.as_ref(), haze[0], haze[1], haze[2]);
    }
}
