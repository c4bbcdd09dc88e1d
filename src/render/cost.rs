//! The cost model: how many GL calls of each kind a frame issues, computed
//! from the frame's data alone. The null backend reports these numbers; the
//! GL backend counts the calls it really makes (`gl::calls`), and a test flies
//! the default flight through both and requires the counts to be equal, so
//! every change to a GL pass must be mirrored here or that test fails.
//!
//! Each function below mirrors one GL pass call for call; its comments name
//! the calls, in the order the pass makes them.

use super::{DrawList, FrameUniforms, Slice};
use crate::symbology::SymbolMesh;
use std::ops::Range;

/// GL calls by kind, summed over frames (since creation or the last take).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CallStats {
    /// Frames drawn (a draw call of the backend trait with frame uniforms).
    pub frames: u64,
    /// glBufferSubData calls, and the bytes they carried.
    pub upload_calls: u64,
    /// Bytes carried by the upload calls.
    pub bytes_uploaded: u64,
    /// glDrawElements and glDrawArrays calls.
    pub draw_calls: u64,
    /// Triangles those draw calls drew (skirts included).
    pub triangles: u64,
    /// glUniform* calls.
    pub uniform_writes: u64,
    /// glVertexAttribPointer calls.
    pub attribute_pointer_changes: u64,
    /// glBindBuffer calls.
    pub buffer_binds: u64,
    /// glUseProgram calls.
    pub program_binds: u64,
    /// glBindVertexArray calls.
    pub vertex_array_binds: u64,
    /// glEnableVertexAttribArray and glDisableVertexAttribArray calls.
    pub attribute_array_toggles: u64,
    /// glClear calls.
    pub clears: u64,
    /// Fixed-function state: glViewport, glEnable, glDisable, glDepthFunc,
    /// glDepthMask, glCullFace, glFrontFace, glColorMask, glClearColor,
    /// glClearDepth.
    pub state_changes: u64,
}

impl CallStats {
    /// Every GL call counted (bytes and triangles are not calls).
    pub fn calls(&self) -> u64 {
        self.upload_calls
            + self.draw_calls
            + self.uniform_writes
            + self.attribute_pointer_changes
            + self.buffer_binds
            + self.program_binds
            + self.vertex_array_binds
            + self.attribute_array_toggles
            + self.clears
            + self.state_changes
    }

    /// Adds `other` into `self`.
    pub fn add(&mut self, other: &CallStats) {
        *self = CallStats {
            frames: self.frames + other.frames,
            upload_calls: self.upload_calls + other.upload_calls,
            bytes_uploaded: self.bytes_uploaded + other.bytes_uploaded,
            draw_calls: self.draw_calls + other.draw_calls,
            triangles: self.triangles + other.triangles,
            uniform_writes: self.uniform_writes + other.uniform_writes,
            attribute_pointer_changes: self.attribute_pointer_changes
                + other.attribute_pointer_changes,
            buffer_binds: self.buffer_binds + other.buffer_binds,
            program_binds: self.program_binds + other.program_binds,
            vertex_array_binds: self.vertex_array_binds + other.vertex_array_binds,
            attribute_array_toggles: self.attribute_array_toggles + other.attribute_array_toggles,
            clears: self.clears + other.clears,
            state_changes: self.state_changes + other.state_changes,
        };
    }
}

/// What the cost of a frame depends on besides its data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CostModel {
    /// The context has vertex array objects (ES 3, or ES 2 with the
    /// extension): passes bind their own.
    pub vertex_arrays: bool,
    /// The sky is drawn (no sentinel colour).
    pub sky: bool,
}

/// Uploading `ranges`: per range, a vertex-array unbind (with VAOs, so the
/// bind cannot change a VAO's state), glBindBuffer and glBufferSubData.
pub fn upload(model: &CostModel, ranges: &[Range<u32>]) -> CallStats {
    let n = ranges.len() as u64;
    CallStats {
        upload_calls: n,
        bytes_uploaded: ranges.iter().map(|r| (r.end - r.start) as u64).sum(),
        buffer_binds: n,
        vertex_array_binds: if model.vertex_arrays { n } else { 0 },
        ..CallStats::default()
    }
}

/// A frame of the display (`frame` its uniforms): clear, sky, terrain.
pub fn frame(model: &CostModel, list: &DrawList, frame: &FrameUniforms) -> CallStats {
    let mut stats = clear();
    if model.sky {
        stats.add(&sky(model));
    }
    stats.add(&terrain(model, list, frame));
    stats.frames = 1;
    stats
}

/// The clear: glViewport, glDisable(SCISSOR), glColorMask, glDepthMask,
/// glClearColor, glClearDepth, glClear.
pub fn clear() -> CallStats {
    CallStats { state_changes: 6, clears: 1, ..CallStats::default() }
}

/// The sky pass: glViewport, glDisable(DEPTH), glDepthMask, glDisable(CULL),
/// glDisable(BLEND), glUseProgram, five uniforms, the VAO bind, the corner
/// buffer bind, enable, pointer, glDrawArrays, disable, glDepthMask.
pub fn sky(model: &CostModel) -> CallStats {
    CallStats {
        state_changes: 6,
        program_binds: 1,
        uniform_writes: 5,
        vertex_array_binds: model.vertex_arrays as u64,
        buffer_binds: 1,
        attribute_array_toggles: 2,
        attribute_pointer_changes: 1,
        draw_calls: 1,
        triangles: 1,
        ..CallStats::default()
    }
}

/// The terrain pass: nine state calls, glUseProgram, seven frame uniforms, the
/// VAO bind, the tile buffer bound as index and as vertex buffer, three
/// attribute enables; then per depth slice one matrix uniform and the
/// slice's draws, those with no data last, after a switch to the program that
/// drops their triangles (glUseProgram, seven frame uniforms, the matrix) and
/// back to the plain one for the next slice; a depth clear between slices;
/// three attribute disables and the VAO unbind.
///
/// Per tile: one uniform array write (four vectors), three pointers at the
/// tile's block and a glDrawElements of its own indices. Per cluster
/// ([`DrawList::clustered`]): one uniform array write (its members'
/// vectors), a change of attribute base only when its base differs from
/// the last one set in the pass, and a glDrawElements per run of members in
/// the slice ([`DrawList::runs`]).
///
/// Clusters with vertex arrays: each window of the vertex buffer has its
/// own, its pointers and index buffer set when the pass was made (not in
/// any frame). The pass binds none of its own, no index buffer and no
/// attribute array: only the tile buffer (as vertex buffer, for the
/// embedding caller), a window's vertex array per change of base, and the
/// unbind at the end. Without vertex arrays a change of base is three
/// pointers.
pub fn terrain(model: &CostModel, list: &DrawList, frame: &FrameUniforms) -> CallStats {
    let windows = model.vertex_arrays && list.clustered();
    let mut stats = CallStats {
        state_changes: 9,
        program_binds: 1,
        uniform_writes: 7,
        vertex_array_binds: if windows { 1 } else { 2 * model.vertex_arrays as u64 },
        buffer_binds: if windows { 1 } else { 2 },
        attribute_array_toggles: if windows { 0 } else { 6 },
        ..CallStats::default()
    };
    let slices: &[Slice] =
        if frame.slices.far.is_some() { &[Slice::Far, Slice::Near] } else { &[Slice::Near] };
    let mut on_plain = true;
    let mut base = None;
    for &slice in slices {
        let switch = |stats: &mut CallStats| {
            stats.program_binds += 1;
            stats.uniform_writes += 8;
        };
        if on_plain {
            stats.uniform_writes += 1;
        } else {
            switch(&mut stats);
            on_plain = true;
        }
        if list.has_no_data_in(slice) {
            switch(&mut stats);
            on_plain = false;
        }
        if !list.clustered() {
            for tile in list.tiles_in(slice) {
                stats.uniform_writes += 1;
                stats.attribute_pointer_changes += 3;
                stats.draw_calls += 1;
                stats.triangles += tile.triangles();
            }
            continue;
        }
        for no_data in [false, true] {
            for cluster in list.clusters_with(slice, no_data, base) {
                stats.uniform_writes += 1;
                if base != Some(cluster.base) {
                    base = Some(cluster.base);
                    if windows {
                        stats.vertex_array_binds += 1;
                    } else {
                        stats.attribute_pointer_changes += 3;
                    }
                }
                for run in list.runs(cluster, slice) {
                    stats.draw_calls += 1;
                    stats.triangles += run.index_count as u64 / 3;
                }
            }
        }
    }
    stats.clears += slices.len() as u64 - 1;
    stats
}

/// The symbol pass (`gl::symbol_pass`) drawing `mesh`: nothing for an
/// empty mesh; else glViewport, glDisable(DEPTH), glDepthMask,
/// glDisable(CULL), glDisable(BLEND), glUseProgram, the viewport uniform,
/// the VAO bind, the buffer bind, one glBufferSubData of the vertices, two
/// attribute enables and pointers, glDrawArrays, two disables, the VAO
/// unbind, then glDepthMask, glEnable(DEPTH) and glEnable(CULL).
pub fn symbols(model: &CostModel, mesh: &SymbolMesh) -> CallStats {
    if mesh.is_empty() {
        return CallStats::default();
    }
    CallStats {
        state_changes: 8,
        program_binds: 1,
        uniform_writes: 1,
        vertex_array_binds: 2 * model.vertex_arrays as u64,
        buffer_binds: 1,
        upload_calls: 1,
        bytes_uploaded: mesh.bytes().len() as u64,
        attribute_array_toggles: 4,
        attribute_pointer_changes: 2,
        draw_calls: 1,
        triangles: mesh.vertices().len() as u64 / 3,
        ..CallStats::default()
    }
}

/// A withdrawn frame (stale data): the clear, and the failure flag by the
/// symbol pass.
pub fn withdrawn(model: &CostModel, flag: &SymbolMesh) -> CallStats {
    let mut stats = clear();
    stats.add(&symbols(model, flag));
    stats.frames = 1;
    stats
}
