//! One node's error map, built from the pyramid alone: every node is built
//! on its own (no parent, no neighbour), so nodes build in parallel, in
//! any order, on any machine.
//!
//! Per node of level `l`:
//! 1. the reference grid: the best data on the lattice of level
//!    `r = max(l - depth, finest)` ([`super::reference`]), `finest` the
//!    finest level with a node stored under it;
//! 2. the RTIN error map of that grid, exact against its posts and the
//!    data's cell diagonals ([`Metric::Surface`]), its hierarchy continuing
//!    the parent's ([`Diagonal::of_node`]);
//! 3. a node no finer node lies under (a *leaf*: level 0, or a coarse
//!    base) keeps a code for every post of its own lattice (dense: it is
//!    drawn however near the camera comes, so any error may be asked of
//!    it); any other node keeps the posts whose code is above its level's
//!    floor ([`MeshOptions::floor_m`]) and those every mesh has, with their
//!    heights and the data's normals there (sparse).

use super::reference::{reference_grid, ReferenceGrid};
use super::{MeshOptions, MeshesError};
use crate::mesh::code::{error_code, threshold_code};
use crate::mesh::{Diagonal, HeightGrid, Metric, Rtin, RtinOptions};
use crate::node::{ErrorMap, NodeId, NodeLayout, NodeSource};
use crate::tiles::extract::forced_step;

/// Builds node `id`'s error map (the node must be stored).
pub fn build_map(
    source: &dyn NodeSource,
    id: NodeId,
    options: &MeshOptions,
) -> Result<ErrorMap, MeshesError> {
    let layout = *source.layout();
    let finest = finest_stored_level(source, id);
    let leaf = finest == id.level;
    let post_level = (id.level - id.level.min(options.depth)).max(finest);
    let reference = reference_grid(source, id, post_level)?;
    let grid = HeightGrid::with_voids(reference.side, &reference.heights)
        .map_err(|e| MeshesError::Mesh { id, source: e })?;
    // Half cells are drawn along the data's diagonal only on the data's own
    // lattice (see `RtinOptions::hierarchy_leaves`).
    let hierarchy_leaves = post_level > finest;
    let rtin_options = RtinOptions {
        metric: Metric::Surface,
        diagonal: Diagonal::of_node(id.x, id.y),
        hierarchy_leaves,
        ..RtinOptions::default()
    };
    let rtin = Rtin::new(&grid, rtin_options).map_err(|e| MeshesError::Mesh { id, source: e })?;
    let cells = reference.side - 1;
    let mut map = ErrorMap {
        post_level,
        cells,
        floor_m: 0.0,
        reference_delta: reference.delta,
        hierarchy_leaves,
        ..ErrorMap::default()
    };
    let side = reference.side;
    let code_at = |i: u32, j: u32| error_code(rtin.error_at(i, j) as f64);
    if leaf {
        map.codes = (0..side * side).map(|k| code_at(k % side, k / side)).collect();
    } else {
        map.floor_m = options.floor_m(&layout, id.level) as f32;
        let tile_posts = options.tile_cells << (id.level - post_level);
        let forced = forced_step(&layout, post_level, cells, tile_posts, map.floor_m as f64);
        keep_sparse(&mut map, &reference, &layout, forced, code_at);
    }
    map.count_codes();
    map.index_rows();
    map.debug_check();
    Ok(map)
}

/// Keeps the posts a sparse map needs: codes above the floor's, and the
/// corners of the squares every mesh of the node splits to.
fn keep_sparse(
    map: &mut ErrorMap,
    reference: &ReferenceGrid,
    layout: &NodeLayout,
    forced: u32,
    code_at: impl Fn(u32, u32) -> u8,
) {
    let side = reference.side;
    let floor_code = threshold_code(map.floor_m as f64);
    let scale = (1u64 << map.post_level) as f64;
    let spacing = [layout.spacing_m[0] * scale, layout.spacing_m[1] * scale];
    for j in 0..side {
        for i in 0..side {
            let code = code_at(i, j);
            let on_forced = i % forced == 0 && j % forced == 0;
            if code > floor_code || on_forced {
                map.keys.push(j * side + i);
                map.codes.push(code);
                map.heights.push(reference.heights[(j * side + i) as usize]);
                map.normals.push(reference.normal(i, j, spacing));
            }
        }
    }
}

/// The finest level with a node stored under node `id` (`id.level` for a
/// leaf: no child stored).
pub fn finest_stored_level(source: &dyn NodeSource, id: NodeId) -> u8 {
    let layout = source.layout();
    let mut finest = id.level;
    for down in 1..=id.level {
        let level = id.level - down;
        let n = 1u32 << down;
        let any = (0..n).any(|dy| {
            (0..n).any(|dx| {
                let child = NodeId::new(level, id.x * n + dx, id.y * n + dy);
                layout.contains(child) && source.has_node(child)
            })
        });
        if !any {
            break;
        }
        finest = level;
    }
    finest
}
