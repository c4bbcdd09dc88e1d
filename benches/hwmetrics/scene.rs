//! The benchmark's terrain on the GL: `side x side` tiles of 64 x 64
//! vertices in one long vertex buffer pair (grid xy and the project's
//! 20-byte `TileVertex`, its heights read) and one long index buffer, and the frame loops that
//! draw it with one operation per tile added (Polok, "Hardware Metrics").

use glow::HasContext;
use ridgeline::gl::{Buffer, BufferTarget, BufferUsage, GlContext, GlError, Program, VertexArray};
use ridgeline::gl_check;
use ridgeline::tiles::block::HEIGHT_OFFSET;
use ridgeline::tiles::TileVertex;
use std::rc::Rc;

/// Vertices per tile side (Polok's 64 x 64).
pub const GRID: u32 = 64;
const TILE_VERTICES: u32 = GRID * GRID;
/// Indices per tile: a strip of 63 rows joined by degenerate pairs, plus the
/// first and last index repeated so tiles concatenate into one strip.
pub const TILE_INDICES: u32 = (GRID - 1) * GRID * 2 + (GRID - 2) * 2 + 2;

const A_GRID: u32 = 0;
const A_HEIGHT: u32 = 1;
const A_OFFSET: u32 = 2;
const GRID_STRIDE: usize = 8;
const HEIGHT_STRIDE: usize = std::mem::size_of::<TileVertex>();
/// Bytes of one tile's vertex data: 64 x 64 of the project's `TileVertex`
/// (the project's own tiles add skirts and indices, see `tiles::grid::tile_bytes`).
pub const TILE_BYTES: u32 = TILE_VERTICES * HEIGHT_STRIDE as u32;

const VERTEX_SOURCE: &str = "#version 100
attribute vec2 a_grid;
attribute float a_height;
attribute vec2 a_offset;
uniform vec2 u_offset;
uniform vec2 u_scale;
varying float v_shade;
void main() {
    vec2 xy = a_grid + a_offset + u_offset;
    v_shade = fract(a_height * 0.01);
    gl_Position = vec4(xy * u_scale - 1.0, 0.0, 1.0);
}
";

const FRAGMENT_SOURCE: &str = "#version 100
precision mediump float;
varying float v_shade;
void main() {
    gl_FragColor = vec4(v_shade, 0.6, 0.3, 1.0);
}
";

/// What a frame adds to the baseline's single draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Operation {
    /// Everything in one glDrawElements.
    Baseline,
    /// Baseline drawn at a 2 x 2 viewport (the paper's raster-bound check).
    TinyViewport,
    /// One glDrawElements per tile, nothing else changed: the cost every
    /// per-tile operation below carries too.
    SplitDraws,
    /// glBindBuffer(ARRAY_BUFFER) alternating between two buffers before each
    /// tile; pointers are not re-set (the paper's figure excludes that).
    VertexBufferSwap,
    /// glBindBuffer(ELEMENT_ARRAY_BUFFER) alternating between two identical
    /// index buffers before each tile.
    IndexBufferSwap,
    /// Tile 0's data drawn 1024 times, moved by glUniform2f per tile.
    UniformUpdate,
    /// Tile 0's data drawn 1024 times, moved by glVertexAttrib2f per tile.
    ConstantAttribute,
    /// Tile 0's indices drawn 1024 times, both attribute pointers moved to
    /// the tile's vertices by glVertexAttribPointer per tile.
    AttributePointer,
    /// A quarter of the tiles' vertex data re-sent per frame with
    /// glBufferSubData in runs of `batch` tiles, then the baseline draw.
    TileUpload { batch: u32 },
}

/// Uniform locations the loops write.
struct Uniforms {
    offset: glow::UniformLocation,
    scale: glow::UniformLocation,
}

pub struct Scene {
    gl: Rc<ridgeline::gl::Gl>,
    viewport: [i32; 2],
    side: u32,
    program: Program,
    at: Uniforms,
    vertex_array: Option<VertexArray>,
    grid: Buffer,
    spare_vertices: Buffer,
    heights: Buffer,
    indices: [Buffer; 2],
    /// CPU copy of every tile's vertex data, the source of the uploads.
    staging: Vec<TileVertex>,
    /// First tile of the next upload run.
    upload_cursor: u32,
    frame_number: u64,
}

impl Scene {
    /// Builds the buffers and program for `side x side` tiles.
    pub fn new(context: &GlContext, side: u32) -> Result<Scene, GlError> {
        let gl = Rc::clone(context.gl());
        let tiles = side * side;
        let attributes = [(A_GRID, "a_grid"), (A_HEIGHT, "a_height"), (A_OFFSET, "a_offset")];
        let program =
            Program::build(&gl, "hwmetrics", VERTEX_SOURCE, FRAGMENT_SOURCE, &attributes)?;
        let missing =
            |name: &str| GlError::InvalidRequest(format!("hwmetrics shader lost uniform {name}"));
        let at = Uniforms {
            offset: program.uniform_location("u_offset").ok_or_else(|| missing("u_offset"))?,
            scale: program.uniform_location("u_scale").ok_or_else(|| missing("u_scale"))?,
        };
        let vertex_array =
            if gl.caps().vertex_array_objects { Some(VertexArray::new(&gl)?) } else { None };
        if let Some(vao) = &vertex_array {
            vao.bind();
        }
        let grid = static_buffer(
            &gl,
            BufferTarget::Vertices,
            bytemuck::cast_slice(&grid_positions(side)),
        )?;
        let spare_vertices =
            static_buffer(&gl, BufferTarget::Vertices, bytemuck::cast_slice(&grid_positions(1)))?;
        let staging = tile_vertices(tiles);
        let heights = Buffer::new(
            &gl,
            BufferTarget::Vertices,
            staging.len() * HEIGHT_STRIDE,
            BufferUsage::Dynamic,
        )?;
        heights.upload_range(0, bytemuck::cast_slice(&staging))?;
        let index_data = strip_indices(tiles);
        let indices = [
            static_buffer(&gl, BufferTarget::Indices, bytemuck::cast_slice(&index_data))?,
            static_buffer(&gl, BufferTarget::Indices, bytemuck::cast_slice(&index_data))?,
        ];
        let size = context.size();
        let viewport = [size.x as i32, size.y as i32];
        let scene = Scene {
            gl,
            viewport,
            side,
            program,
            at,
            vertex_array,
            grid,
            spare_vertices,
            heights,
            indices,
            staging,
            upload_cursor: 0,
            frame_number: 0,
        };
        if let Some(vao) = &scene.vertex_array {
            // The index uploads above unbound it (Buffer::upload_range).
            vao.bind();
        }
        scene.set_state(context)?;
        Ok(scene)
    }

    /// Draws at `size` pixels from now on (the corner of the target).
    #[allow(unsafe_code)]
    pub fn set_viewport(&mut self, size: [i32; 2]) {
        self.viewport = size;
        // SAFETY: viewport changes take plain values.
        unsafe { self.gl.viewport(0, 0, size[0], size[1]) };
    }

    pub fn tiles(&self) -> u32 {
        self.side * self.side
    }

    /// Tiles re-sent per frame: 25 %, as in the paper.
    pub fn uploads_per_frame(&self) -> u32 {
        (self.tiles() / 4).max(1)
    }

    /// Frames one upload schedule of `batch` takes to repeat: a run longer
    /// than a frame's quarter is sent whole every `batch / quarter` frames.
    pub fn upload_period(&self, batch: u32) -> u32 {
        batch.div_ceil(self.uploads_per_frame()).max(1)
    }

    #[allow(unsafe_code)]
    fn set_state(&self, context: &GlContext) -> Result<(), GlError> {
        context.bind_target();
        self.program.bind();
        self.indices[0].bind();
        self.point_attributes(0);
        let world = (self.side * (GRID - 1)) as f32;
        // SAFETY: the program is bound and both locations belong to it; the
        // constant attribute and the viewport take plain values.
        unsafe {
            self.gl.enable_vertex_attrib_array(A_GRID);
            self.gl.enable_vertex_attrib_array(A_HEIGHT);
            self.gl.disable_vertex_attrib_array(A_OFFSET);
            self.gl.vertex_attrib_2_f32(A_OFFSET, 0.0, 0.0);
            self.gl.uniform_2_f32(Some(&self.at.offset), 0.0, 0.0);
            self.gl.uniform_2_f32(Some(&self.at.scale), 2.0 / world, 2.0 / world);
            self.gl.clear_color(0.1, 0.1, 0.2, 1.0);
            self.gl.viewport(0, 0, self.viewport[0], self.viewport[1]);
        }
        gl_check!(self.gl)
    }

    /// Points both arrays at `tile`'s vertices.
    #[allow(unsafe_code)]
    fn point_attributes(&self, tile: u32) {
        let first = (tile * TILE_VERTICES) as usize;
        self.grid.bind();
        // SAFETY: the grid buffer is bound and holds every tile's positions;
        // the offset is inside it (tile < tiles).
        unsafe {
            self.gl.vertex_attrib_pointer_f32(
                A_GRID,
                2,
                glow::FLOAT,
                false,
                8,
                (first * GRID_STRIDE) as i32,
            )
        };
        self.heights.bind();
        // SAFETY: as above for the height buffer; the height lies
        // `HEIGHT_OFFSET` bytes into a `TileVertex`.
        unsafe {
            self.gl.vertex_attrib_pointer_f32(
                A_HEIGHT,
                1,
                glow::FLOAT,
                false,
                HEIGHT_STRIDE as i32,
                (first * HEIGHT_STRIDE) as i32 + HEIGHT_OFFSET as i32,
            )
        };
    }

    /// Draws `count` tiles' indices starting at tile `first`.
    #[allow(unsafe_code)]
    fn draw(&self, first: u32, count: u32) {
        let offset = (first * TILE_INDICES * 4) as i32;
        // SAFETY: an index buffer of every tile's u32 indices is bound (to
        // the VAO or the context) and [first, first + count) are tiles.
        unsafe {
            self.gl.draw_elements(
                glow::TRIANGLE_STRIP,
                (count * TILE_INDICES) as i32,
                glow::UNSIGNED_INT,
                offset,
            )
        };
    }

    fn tile_origin(&self, tile: u32) -> (f32, f32) {
        let step = (GRID - 1) as f32;
        ((tile % self.side) as f32 * step, (tile / self.side) as f32 * step)
    }

    /// Renders one frame with `operation` and waits for the GL (glFinish).
    /// Returns the seconds spent inside glBufferSubData calls.
    #[allow(unsafe_code)]
    pub fn frame(&mut self, operation: Operation) -> Result<f64, GlError> {
        let gl = Rc::clone(&self.gl);
        // SAFETY: clearing the bound target takes no pointers.
        unsafe { gl.clear(glow::COLOR_BUFFER_BIT) };
        let mut upload_secs = 0.0;
        let tiles = self.tiles();
        match operation {
            Operation::Baseline => self.draw(0, tiles),
            Operation::TinyViewport => {
                // SAFETY: viewport changes take plain values.
                unsafe { gl.viewport(0, 0, 2, 2) };
                self.draw(0, tiles);
                // SAFETY: as above.
                unsafe { gl.viewport(0, 0, self.viewport[0], self.viewport[1]) };
            }
            Operation::SplitDraws => (0..tiles).for_each(|t| self.draw(t, 1)),
            Operation::VertexBufferSwap => {
                for t in 0..tiles {
                    if t % 2 == 0 {
                        self.grid.bind()
                    } else {
                        self.spare_vertices.bind()
                    }
                    self.draw(t, 1);
                }
            }
            Operation::IndexBufferSwap => {
                for t in 0..tiles {
                    self.indices[(t % 2) as usize].bind();
                    self.draw(t, 1);
                }
                self.indices[0].bind();
            }
            Operation::UniformUpdate => {
                for t in 0..tiles {
                    let (x, y) = self.tile_origin(t);
                    // SAFETY: the location belongs to the bound program.
                    unsafe { gl.uniform_2_f32(Some(&self.at.offset), x, y) };
                    self.draw(0, 1);
                }
                // SAFETY: as above.
                unsafe { gl.uniform_2_f32(Some(&self.at.offset), 0.0, 0.0) };
            }
            Operation::ConstantAttribute => {
                for t in 0..tiles {
                    let (x, y) = self.tile_origin(t);
                    // SAFETY: A_OFFSET is a disabled array, so the constant is used.
                    unsafe { gl.vertex_attrib_2_f32(A_OFFSET, x, y) };
                    self.draw(0, 1);
                }
                // SAFETY: as above.
                unsafe { gl.vertex_attrib_2_f32(A_OFFSET, 0.0, 0.0) };
            }
            Operation::AttributePointer => {
                for t in 0..tiles {
                    self.point_attributes(t);
                    self.draw(0, 1);
                }
                self.point_attributes(0);
            }
            Operation::TileUpload { batch } => {
                upload_secs = self.upload(batch)?;
                self.draw(0, tiles);
            }
        }
        // SAFETY: glFinish takes no arguments.
        unsafe { gl.finish() };
        self.frame_number += 1;
        gl_check!(gl)?;
        Ok(upload_secs)
    }

    /// This frame's share of the upload schedule for runs of `batch` tiles:
    /// runs up to a quarter of the tiles go `quarter / batch` per frame;
    /// longer runs go one every `batch / quarter` frames, so the average
    /// traffic stays a quarter of the tiles per frame either way.
    fn upload(&mut self, batch: u32) -> Result<f64, GlError> {
        let tiles = self.tiles();
        let batch = batch.min(tiles);
        let period = self.upload_period(batch) as u64;
        if self.frame_number % period != 0 {
            return Ok(0.0);
        }
        let runs = (self.uploads_per_frame() / batch).max(1);
        let tile_size = TILE_BYTES as usize;
        let start = std::time::Instant::now();
        for _ in 0..runs {
            let first = if self.upload_cursor + batch > tiles { 0 } else { self.upload_cursor };
            let begin = first as usize * TILE_VERTICES as usize;
            let vertices = &self.staging[begin..begin + (batch * TILE_VERTICES) as usize];
            self.heights
                .upload_range(first as usize * tile_size, bytemuck::cast_slice(vertices))?;
            self.upload_cursor = (first + batch) % tiles;
        }
        Ok(start.elapsed().as_secs_f64())
    }
}

fn static_buffer(
    gl: &Rc<ridgeline::gl::Gl>,
    target: BufferTarget,
    bytes: &[u8],
) -> Result<Buffer, GlError> {
    let buffer = Buffer::new(gl, target, bytes.len(), BufferUsage::Static)?;
    buffer.upload_range(0, bytes)?;
    Ok(buffer)
}

/// World xy of every vertex, tile after tile (row-major tiles and posts);
/// neighbouring tiles share their edge posts' positions.
fn grid_positions(side: u32) -> Vec<[f32; 2]> {
    let step = (GRID - 1) as f32;
    let mut out = Vec::with_capacity((side * side * TILE_VERTICES) as usize);
    for tile in 0..side * side {
        let (tx, ty) = ((tile % side) as f32 * step, (tile / side) as f32 * step);
        for post in 0..TILE_VERTICES {
            out.push([tx + (post % GRID) as f32, ty + (post / GRID) as f32]);
        }
    }
    out
}

/// Rolling synthetic heights in the project's vertex format.
fn tile_vertices(tiles: u32) -> Vec<TileVertex> {
    (0..tiles * TILE_VERTICES)
        .map(|i| {
            let h = ((i % 997) as f32 * 0.37).sin() * 120.0 + (i / TILE_VERTICES) as f32;
            TileVertex { height: h, target: h, normal: [0, 0, 127, 127], ..TileVertex::default() }
        })
        .collect()
}

/// One triangle strip per tile over its own vertices, each opened and closed
/// by a repeated index so the tiles join into one strip with degenerate
/// triangles (one draw of the lot is the baseline).
fn strip_indices(tiles: u32) -> Vec<u32> {
    let mut local = Vec::with_capacity(TILE_INDICES as usize);
    for row in 0..GRID - 1 {
        if row > 0 {
            local.push(row * GRID); // degenerate: repeat the row's first
        }
        for column in 0..GRID {
            local.push(row * GRID + column);
            local.push((row + 1) * GRID + column);
        }
        if row + 2 < GRID {
            local.push((row + 1) * GRID + GRID - 1); // degenerate: repeat the row's last
        }
    }
    local.insert(0, local[0]);
    local.push(*local.last().expect("a tile has indices"));
    debug_assert_eq!(local.len() as u32, TILE_INDICES);
    (0..tiles).flat_map(|t| local.iter().map(move |i| i + t * TILE_VERTICES)).collect()
}
