//! The terrain pass: one buffer mirroring the tile allocator's staging copy,
//! bound both as vertex and as index buffer (OpenGL ES allows it), each
//! tile's block in it holding the tile's vertices and indices
//! ([`crate::tiles::block`]); per tile only uniforms, attribute pointers at
//! its block and one glDrawElements of its indices (Polok). Vertex shaders
//! read no textures.
//!
//! Two fragment programs share the vertex shader: the display's colours, and
//! camera-relative positions for the accuracy tool ([`TerrainOutput`]), so
//! what the accuracy tool measures is the geometry the display draws.
//!
//! With clusters ([`TerrainPass::prepare_clusters`]) the buffer holds the
//! clusters' vertex blocks, in fixed windows of 2^16 vertices, and a second
//! buffer their indices. Where the context has vertex array objects, each
//! window has one, made with the pass: the index buffer bound and the
//! three attribute pointers set at the window's start, once for the
//! buffer's life. A frame then changes attribute base with one vertex
//! array bind and sets no pointer; without them (bare ES 2.0) it sets the
//! three pointers at each change of window.

use std::rc::Rc;

use super::calls::Calls;
use super::error::GlError;
use super::handle::Gl;
use super::objects::{Buffer, BufferTarget, BufferUsage, Program, VertexArray};
use crate::gl_check;
use crate::render::cluster::{window, window_count, window_of, MAX_MEMBERS, MEMBER_FLOATS};
use crate::render::{
    check_uploads, palette, Cluster, DrawList, FrameUniforms, RenderError, Slice, TileUniforms,
};
use crate::tiles::block::{HEIGHT_OFFSET, NORMAL_OFFSET, VERTEX_BYTES};

const VERTEX_SOURCE: &str = include_str!("../../shaders/gles/terrain.vert");
const FRAGMENT_SOURCE: &str = include_str!("../../shaders/gles/terrain.frag");
const POSITION_SOURCE: &str = include_str!("../../shaders/gles/position.frag");

const GRID: u32 = 0;
const HEIGHT: u32 = 1;
const NORMAL: u32 = 2;
const VERTEX_STRIDE: i32 = VERTEX_BYTES as i32;

struct Locations {
    view_projection: Option<glow::UniformLocation>,
    members: Option<glow::UniformLocation>,
    posts: Option<glow::UniformLocation>,
    frame: Option<glow::UniformLocation>,
    earth: Option<glow::UniformLocation>,
    sun: Option<glow::UniformLocation>,
    awareness: Option<glow::UniformLocation>,
    haze: Option<glow::UniformLocation>,
    no_data: Option<glow::UniformLocation>,
}

/// What the terrain pass writes per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TerrainOutput {
    /// The display's shaded colours.
    Colour,
    /// The camera-relative surface position, into an RGBA32F target.
    Position,
}

/// Where each tile's block is.
#[derive(Clone, Copy)]
pub enum TileBlocks<'a> {
    /// At the tile's byte offsets in the pass's one buffer (Polok's batching).
    Shared,
    /// In a buffer of the tile's own, from byte 0 (plain Chunked LOD: a
    /// buffer swap per draw); tiles without a buffer are skipped. Only
    /// the baseline draws so (feature `test-support`).
    #[cfg_attr(not(feature = "test-support"), allow(dead_code))]
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
            members: program.uniform_location("u_members"),
            posts: program.uniform_location("u_posts"),
            frame: program.uniform_location("u_frame"),
            earth: program.uniform_location("u_earth"),
            sun: program.uniform_location("u_sun"),
            awareness: program.uniform_location("u_awareness"),
            haze: program.uniform_location("u_haze"),
            no_data: program.uniform_location("u_no_data"),
        };
        Ok(TerrainProgram { program, at })
    }
}

pub struct TerrainPass {
    gl: Rc<Gl>,
    /// Per output, the plain program and the one that drops triangles
    /// touching posts without data (its `discard` costs early depth
    /// rejection, so only tiles with posts of no data use it).
    colour: [TerrainProgram; 2],
    position: [TerrainProgram; 2],
    /// The tiles' blocks, at the allocator's offsets (with clusters: the
    /// clusters' vertex blocks).
    blocks: Buffer,
    /// With clusters: their index blocks and the windows' vertex arrays.
    clusters: Option<ClusterArrays>,
    vertex_array: Option<VertexArray>,
}

/// The cluster index buffer and, where the context has vertex array
/// objects, one per window of the vertex buffer (empty where it has none).
struct ClusterArrays {
    indices: Buffer,
    windows: Vec<VertexArray>,
}

impl TerrainPass {
    /// Builds the programs and a tile buffer of `buffer_bytes` (the tile
    /// allocator's capacity).
    pub fn new(gl: &Rc<Gl>, buffer_bytes: u32) -> Result<TerrainPass, GlError> {
        let colour = [
            TerrainProgram::build(gl, "terrain", FRAGMENT_SOURCE)?,
            TerrainProgram::build(gl, "terrain with no data", &with_no_data(FRAGMENT_SOURCE))?,
        ];
        let position = [
            TerrainProgram::build(gl, "terrain positions", POSITION_SOURCE)?,
            TerrainProgram::build(
                gl,
                "terrain positions with no data",
                &with_no_data(POSITION_SOURCE),
            )?,
        ];
        // Uploads bind it as vertex buffer, which no vertex array records.
        let blocks =
            Buffer::new(gl, BufferTarget::Vertices, buffer_bytes as usize, BufferUsage::Dynamic)?;
        let vertex_array =
            if gl.caps().vertex_array_objects { Some(VertexArray::new(gl)?) } else { None };
        Ok(TerrainPass {
            gl: Rc::clone(gl),
            colour,
            position,
            blocks,
            clusters: None,
            vertex_array,
        })
    }

    /// Readies the pass to draw clusters: an index buffer of `index_bytes`
    /// and, with vertex array objects, one per window of the tile buffer,
    /// each recording the index buffer and the three attribute pointers at
    /// its window's start. Those calls are made here, before any frame, and
    /// not counted: they are part of making the objects.
    #[allow(unsafe_code)]
    pub fn prepare_clusters(&mut self, index_bytes: u32) -> Result<(), GlError> {
        let size = index_bytes as usize;
        let indices = Buffer::new(&self.gl, BufferTarget::Indices, size, BufferUsage::Dynamic)?;
        let mut windows = Vec::new();
        if self.vertex_array.is_some() {
            let capacity = self.blocks.size() as u32;
            let calls = Calls::making_objects(&self.gl);
            for k in 0..window_count(capacity) {
                let base = window(k, capacity).expect("counted").start;
                let vertex_array = VertexArray::new(&self.gl)?;
                // SAFETY: live objects of this context; the pointers stay
                // inside the buffer (a window starts inside it).
                unsafe {
                    calls.bind_vertex_array(Some(&vertex_array));
                    calls.bind_buffer_to(&indices, BufferTarget::Indices);
                    calls.bind_buffer(&self.blocks);
                    enable_attributes(calls, true);
                    attribute_pointers(calls, base as i32);
                    calls.bind_vertex_array(None);
                }
                windows.push(vertex_array);
            }
        }
        self.clusters = Some(ClusterArrays { indices, windows });
        gl_check!(self.gl)
    }

    /// Copies the dirty ranges of the staging copy into the tile buffer at
    /// the same offsets: one glBufferSubData per range (per run piece).
    /// Refuses a range past the buffer, as the null backend does.
    pub fn upload(&self, staging: &[u8], ranges: &[std::ops::Range<u32>]) -> Result<(), GlError> {
        check_uploads(staging, self.blocks.size() as u32, ranges)?;
        for range in ranges {
            self.sub_data(
                &self.blocks,
                range.start,
                &staging[range.start as usize..range.end as usize],
            );
        }
        gl_check!(self.gl)
    }

    /// Copies the dirty ranges of the cluster index staging copy into the
    /// index buffer ([`Self::prepare_clusters`]), as [`Self::upload`] does
    /// for the vertex buffer.
    pub fn upload_indices(
        &mut self,
        staging: &[u8],
        ranges: &[std::ops::Range<u32>],
    ) -> Result<(), GlError> {
        let buffer = &self.prepared()?.indices;
        check_uploads(staging, buffer.size() as u32, ranges)?;
        for range in ranges {
            self.sub_data(buffer, range.start, &staging[range.start as usize..range.end as usize]);
        }
        gl_check!(self.gl)
    }

    /// Writes `bytes` into the tile buffer at byte `offset`: one
    /// glBufferSubData, counted as [`Self::upload`]'s are. Refuses bytes
    /// past the buffer.
    pub fn upload_at(&self, offset: u32, bytes: &[u8]) -> Result<(), GlError> {
        let capacity = self.blocks.size() as u32;
        let end = offset as u64 + bytes.len() as u64;
        if end > capacity as u64 {
            let end = end.min(u32::MAX as u64) as u32;
            let staging = bytes.len();
            return Err(
                RenderError::UploadPastBuffer { start: offset, end, capacity, staging }.into()
            );
        }
        self.sub_data(&self.blocks, offset, bytes);
        gl_check!(self.gl)
    }

    /// The cluster buffers, or why there are none.
    fn prepared(&self) -> Result<&ClusterArrays, GlError> {
        // As the null backend refuses them: the renderer's plan had none.
        self.clusters.as_ref().ok_or(GlError::from(RenderError::ClustersNotPlanned))
    }

    /// `bytes` into `buffer` at `offset`, which the caller checked.
    #[allow(unsafe_code)]
    fn sub_data(&self, buffer: &Buffer, offset: u32, bytes: &[u8]) {
        let calls = Calls::new(&self.gl);
        // SAFETY: the range lies inside the buffer (checked by the caller);
        // the vertex array is unbound first so the bind changes none.
        unsafe {
            if self.vertex_array.is_some() {
                calls.bind_vertex_array(None);
            }
            calls.bind_buffer(buffer);
            calls.buffer_sub_data(buffer, offset as usize, bytes);
        }
    }

    /// Draws every tile of `list` (built for the frame of `frame`, its
    /// uniforms), writing `output`, in the frame's depth slices (far first,
    /// depth cleared between). Sets all the state it relies on: depth test
    /// and writes on, back faces culled, no blending, no scissor. Mirrored
    /// call for call by [`crate::render::cost::terrain`].
    pub fn draw(
        &self,
        list: &DrawList,
        frame: &FrameUniforms,
        output: TerrainOutput,
    ) -> Result<(), GlError> {
        self.draw_from(list, frame, output, TileBlocks::Shared)
    }

    /// [`Self::draw`] with the tiles' blocks where `blocks` says.
    #[allow(unsafe_code)]
    pub fn draw_from(
        &self,
        list: &DrawList,
        frame: &FrameUniforms,
        output: TerrainOutput,
        blocks: TileBlocks<'_>,
    ) -> Result<(), GlError> {
        let clusters = if list.clustered() { Some(self.prepared()?) } else { None };
        // Per window vertex arrays, where the context has them.
        let windows = clusters.map(|c| c.windows.as_slice()).filter(|w| !w.is_empty());
        let calls = Calls::new(&self.gl);
        let programs = match output {
            TerrainOutput::Colour => &self.colour,
            TerrainOutput::Position => &self.position,
        };
        let program = &programs[0];
        // SAFETY: every object bound is live in this context; attribute
        // pointers and index offsets stay inside the buffer (each tile's
        // indices number only its own block's vertices, as the allocator
        // placed and the tile cache filled it).
        set_draw_state(calls, frame);
        self.bind_blocks(calls, clusters, windows);
        unsafe {
            calls.use_program(&program.program);
            set_frame_uniforms(calls, &program.at, frame);
            // Far slice first; then a clear depth for the near slice.
            let mut on_plain = true;
            // The attribute base last set (clusters share theirs).
            let mut bound = Bound { base: None, windows };
            if let Some(far) = frame.slices.far {
                let b = &mut bound;
                let far = (far, Slice::Far);
                on_plain = self.draw_slice(calls, programs, list, *frame, far, blocks, b);
                calls.clear(glow::DEPTH_BUFFER_BIT);
            }
            if !on_plain {
                calls.use_program(&program.program);
                set_frame_uniforms(calls, &program.at, frame);
            }
            let near = (frame.slices.near, Slice::Near);
            self.draw_slice(calls, programs, list, *frame, near, blocks, &mut bound);
            if windows.is_none() {
                enable_attributes(calls, false);
            }
            // Unbound, so a caller's buffer binds cannot change it.
            if self.vertex_array.is_some() {
                calls.bind_vertex_array(None);
            }
        }
        gl_check!(self.gl)
    }

    /// Binds the buffers the frame's draws read: the index buffer (the
    /// clusters' with clusters on) and the attributes, unless per-window
    /// vertex arrays (`windows`) hold their own.
    #[allow(unsafe_code)]
    fn bind_blocks(
        &self,
        calls: Calls<'_>,
        clusters: Option<&ClusterArrays>,
        windows: Option<&[VertexArray]>,
    ) {
        // SAFETY: every object bound is live in this context.
        unsafe {
            if windows.is_none() {
                if let Some(vertex_array) = &self.vertex_array {
                    calls.bind_vertex_array(Some(vertex_array));
                }
                // The index binding is the vertex array's state where there
                // is one, the context's where there is none (ES 2.0): bound
                // here, every frame, either way.
                let indices = clusters.map_or(&self.blocks, |c| &c.indices);
                calls.bind_buffer_to(indices, BufferTarget::Indices);
            }
            // The windows' vertex arrays hold their own bindings; this one
            // is the context's, left bound for an embedding caller.
            calls.bind_buffer(&self.blocks);
            if windows.is_none() {
                enable_attributes(calls, true);
            }
        }
    }

    /// Draws the tiles of `list` that reach into depth slice `slice` with its
    /// `view_projection`: those whose posts all have data with the plain program (bound
    /// on entry), then those with posts of no data with the other. Returns whether the
    /// plain program is still bound.
    #[allow(unsafe_code, clippy::too_many_arguments)]
    fn draw_slice(
        &self,
        calls: Calls<'_>,
        programs: &[TerrainProgram; 2],
        list: &DrawList,
        frame: FrameUniforms,
        (view_projection, slice): (glam::Mat4, Slice),
        blocks: TileBlocks<'_>,
        base: &mut Bound<'_>,
    ) -> bool {
        let [plain, no_data] = programs;
        // SAFETY: the plain program is bound and its location comes from it.
        unsafe { calls.uniform_matrix(plain.at.view_projection.as_ref(), &view_projection) };
        self.draw_part(calls, &plain.at, list, slice, false, blocks, base);
        if !list.has_no_data_in(slice) {
            return true;
        }
        // SAFETY: a linked program of this context; its locations come from it.
        unsafe {
            calls.use_program(&no_data.program);
            set_frame_uniforms(calls, &no_data.at, &frame);
            calls.uniform_matrix(no_data.at.view_projection.as_ref(), &view_projection);
        }
        self.draw_part(calls, &no_data.at, list, slice, true, blocks, base);
        false
    }

    /// Draws the tiles or clusters of `slice` with or without no data.
    #[allow(clippy::too_many_arguments)]
    fn draw_part(
        &self,
        calls: Calls<'_>,
        at: &Locations,
        list: &DrawList,
        slice: Slice,
        no_data: bool,
        blocks: TileBlocks<'_>,
        bound: &mut Bound<'_>,
    ) {
        if list.clustered() {
            for cluster in list.clusters_with(slice, no_data, bound.base) {
                draw_cluster(calls, at, list, cluster, slice, bound);
            }
        } else {
            self.draw_tiles(calls, at, list.tiles_with(slice, no_data), blocks);
        }
    }

    fn draw_tiles<'t>(
        &self,
        calls: Calls<'_>,
        at: &Locations,
        tiles: impl Iterator<Item = &'t TileUniforms>,
        blocks: TileBlocks<'_>,
    ) {
        for tile in tiles {
            let offsets = match blocks {
                TileBlocks::Shared => [tile.byte_offset, tile.index_byte_offset],
                TileBlocks::PerTile(buffer_of) => match buffer_of(tile) {
                    Some(buffer) => {
                        // SAFETY: the tile's own live buffer, its block from byte 0.
                        #[allow(unsafe_code)]
                        unsafe {
                            calls.bind_buffer_to(buffer, BufferTarget::Indices);
                            calls.bind_buffer_to(buffer, BufferTarget::Vertices);
                        };
                        [0, tile.index_byte_offset - tile.byte_offset]
                    }
                    None => continue,
                },
            };
            self.draw_tile(calls, at, tile, offsets);
        }
    }

    /// Draws `tile` from the bound buffer, its vertices and indices at
    /// byte `offsets`.
    #[allow(unsafe_code)]
    fn draw_tile(&self, calls: Calls<'_>, at: &Locations, tile: &TileUniforms, offsets: [u32; 2]) {
        let [vertices, indices] = offsets.map(|offset| offset as i32);
        // SAFETY: the bound buffer holds the tile's block: its vertices
        // from `vertices`, its indices (numbering only those vertices) from
        // `indices`.
        unsafe {
            calls.uniform_4v(at.members.as_ref(), &tile.member_uniforms());
            attribute_pointers(calls, vertices);
            calls.draw_triangles(tile.index_count as i32, indices);
        }
    }
}

/// The attribute base last set in a pass, and how a change is made.
struct Bound<'a> {
    /// The base the attributes point at, if any yet.
    base: Option<u32>,
    /// The windows' vertex arrays (a change binds one), or `None` (a change
    /// sets the three pointers).
    windows: Option<&'a [VertexArray]>,
}

/// Enables (`on`) or disables the three attribute arrays.
#[allow(unsafe_code)]
unsafe fn enable_attributes(calls: Calls<'_>, on: bool) {
    for attribute in [GRID, HEIGHT, NORMAL] {
        if on {
            calls.enable_attribute(attribute);
        } else {
            calls.disable_attribute(attribute);
        }
    }
}

/// Points the three attributes at vertices from byte `vertices` of the
/// bound buffer.
#[allow(unsafe_code)]
unsafe fn attribute_pointers(calls: Calls<'_>, vertices: i32) {
    // Post, skirt edge and member slot: four 16-bit integers.
    calls.attribute_pointer(GRID, 4, glow::UNSIGNED_SHORT, false, VERTEX_STRIDE, vertices);
    let heights = vertices + HEIGHT_OFFSET as i32;
    calls.attribute_pointer(HEIGHT, 2, glow::FLOAT, false, VERTEX_STRIDE, heights);
    let normals = vertices + NORMAL_OFFSET as i32;
    calls.attribute_pointer(NORMAL, 4, glow::BYTE, true, VERTEX_STRIDE, normals);
}

/// Draws `cluster`'s members in `slice`: its members' uniforms in one
/// write, its window's vertex array (or the attribute pointers) when its
/// base is not the one `bound` last set, one glDrawElements per run of
/// members in the slice.
#[allow(unsafe_code)]
fn draw_cluster(
    calls: Calls<'_>,
    at: &Locations,
    list: &DrawList,
    cluster: &Cluster,
    slice: Slice,
    bound: &mut Bound<'_>,
) {
    let mut uniforms = [0.0; MAX_MEMBERS * MEMBER_FLOATS];
    let used = list.cluster_uniforms(cluster, &mut uniforms);
    // SAFETY: the buffer the pointers (or the window's vertex array) use
    // holds the cluster's block: its vertices from `cluster.base` on (every index numbers a vertex of the block
    // from there, below 2^16), its indices at the runs' offsets.
    unsafe {
        calls.uniform_4v(at.members.as_ref(), &uniforms[..used]);
        if bound.base != Some(cluster.base) {
            bound.base = Some(cluster.base);
            match bound.windows {
                Some(windows) => {
                    calls.bind_vertex_array(Some(&windows[window_of(cluster.base) as usize]))
                }
                None => attribute_pointers(calls, cluster.base as i32),
            }
        }
        for run in list.runs(cluster, slice) {
            calls.draw_triangles(run.index_count as i32, run.index_byte_offset as i32);
        }
    }
}

/// Sets the per-frame uniforms of the bound program `at` belongs to.
/// The fixed state the terrain is drawn with: the frame's viewport, depth
/// test and writes, back faces culled, no blending, no scissor.
#[allow(unsafe_code)]
fn set_draw_state(calls: Calls<'_>, frame: &FrameUniforms) {
    // SAFETY: state calls only, on the current context.
    unsafe {
        calls.viewport(frame.viewport[0], frame.viewport[1]);
        calls.enable(glow::DEPTH_TEST);
        calls.depth_func(glow::LESS);
        calls.depth_mask(true);
        calls.enable(glow::CULL_FACE);
        calls.cull_face(glow::BACK);
        calls.front_face(glow::CCW);
        calls.disable(glow::BLEND);
        // The depth clear between slices must reach the whole target.
        calls.disable(glow::SCISSOR_TEST);
    }
}

#[allow(unsafe_code)]
fn set_frame_uniforms(calls: Calls<'_>, at: &Locations, frame: &FrameUniforms) {
    let curvature = if frame.curvature { 1.0 / (2.0 * crate::camera::EARTH_RADIUS_M) } else { 0.0 };
    let sun = frame.sun_direction;
    let posts = &frame.posts;
    let awareness = [frame.warning_above_m, frame.caution_below_m, frame.fog_distance_m, 0.0];
    let [last_x, last_y] = posts.number(frame.last_post);
    // SAFETY: the program is bound; locations come from it.
    unsafe {
        calls.uniform_4(
            at.frame.as_ref(),
            [frame.camera_altitude as f32, curvature as f32, last_x, last_y],
        );
        let [sx, sy] = posts.spacing;
        calls.uniform_4(at.posts.as_ref(), [sx, sy, posts.offset[0], posts.offset[1]]);
        calls.uniform_4v(at.earth.as_ref(), &frame.earth_uniforms());
        calls.uniform_3(at.sun.as_ref(), sun.to_array());
        calls.uniform_4(at.awareness.as_ref(), awareness);
        calls.uniform_3(at.haze.as_ref(), palette::SKY_HORIZON);
        // Curtains are drawn as the sky pass draws missing data.
        calls.uniform_3(at.no_data.as_ref(), palette::NO_DATA_HATCH);
    }
}

/// `source` with `NO_DATA` defined after its `#version` line: the variant
/// that discards fragments of triangles touching a post without data.
fn with_no_data(source: &str) -> String {
    let (version, rest) = source.split_once('\n').unwrap_or((source, ""));
    format!("{version}\n#define NO_DATA\n{rest}")
}
