//! Building every present node's adaptive mesh, coarsest level first (a
//! node's mesh refines its parent's, and its morph targets lie on it).
//!
//! Per node of level `l`:
//! 1. the reference grid: the best data on the lattice of level
//!    `r = l - min(l, depth)` ([`super::reference`]);
//! 2. the RTIN error map of that grid, its hierarchy continuing the
//!    parent's ([`Diagonal::of_node`]);
//! 3. the mesh of error `level_error(l)`, split at least to squares of
//!    `tile_cells` node posts, and keeping every vertex of the parent's mesh
//!    inside the node (so the mesh refines the parent's: fully morphed, a
//!    node draws its parent's very surface);
//! 4. its exact vertical distance to the reference surface (posts, and cell
//!    centres where an edge crosses a cell's diagonal), plus the reference
//!    nodes' own delta when the reference is not level 0: the node's delta;
//! 5. per vertex, the parent mesh's height there (the morph target) and the
//!    data's normal there.

use rayon::prelude::*;

use super::reference::{reference_grid, ReferenceGrid};
use super::{MeshOptions, MeshesError};
use crate::mesh::rtin::round_up_to_f32;
use crate::mesh::{
    max_surface_distance, Diagonal, HeightGrid, Mesh, MeshError, MeshSampler, Metric, Rtin,
    RtinOptions,
};
use crate::node::{MeshVertex, NodeId, NodeLayout, NodeMesh, NodeSource};
use crate::pyramid::Progress;

/// One node's built mesh, and what its children need of it.
pub struct BuiltMesh {
    /// The mesh as stored.
    pub mesh: NodeMesh,
    /// Exact vertical distance from the mesh to the best data, metres.
    pub delta: f32,
    /// The error the mesh was simplified to (above the level's error only
    /// where the level's mesh would pass 65 536 vertices).
    pub error_m: f32,
    sampler: MeshSampler,
}

/// Every present node's mesh, level by level (finest first), `None` where
/// the node is absent.
pub struct BuiltMeshes {
    /// What they were built with.
    pub options: MeshOptions,
    /// Per level, per node of the level row by row.
    pub levels: Vec<Vec<Option<BuiltMesh>>>,
}

impl BuiltMeshes {
    /// The mesh of node `id`, if present.
    pub fn mesh(&self, layout: &NodeLayout, id: NodeId) -> Option<&BuiltMesh> {
        let [nx, _] = layout.nodes_at(id.level);
        let level = self.levels.get(id.level as usize)?;
        level.get((id.y * nx + id.x) as usize)?.as_ref()
    }

    /// Largest delta of each level, finest first.
    pub fn delta_per_level(&self) -> Vec<f32> {
        self.levels
            .iter()
            .map(|l| l.iter().flatten().map(|c| c.delta).fold(0.0, f32::max))
            .collect()
    }
}

/// Builds the mesh of every node `source` stores, using every core rayon offers.
pub fn build_meshes(
    source: &dyn NodeSource,
    options: MeshOptions,
    progress: &dyn Progress,
) -> Result<BuiltMeshes, MeshesError> {
    options.validate(source.layout())?;
    let layout = *source.layout();
    let mut levels: Vec<Vec<Option<BuiltMesh>>> = (0..layout.levels).map(|_| Vec::new()).collect();
    for level in (0..layout.levels).rev() {
        let [nx, ny] = layout.nodes_at(level);
        let ids: Vec<NodeId> =
            (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(level, x, y))).collect();
        progress.phase(&format!("level {level}: meshes"), ids.len() as u64);
        let parents =
            levels.get(level as usize + 1).map(|p| (p.as_slice(), layout.nodes_at(level + 1)[0]));
        let built: Vec<Result<Option<BuiltMesh>, MeshesError>> = ids
            .par_iter()
            .map(|&id| {
                let parent = parents.and_then(|(built, px)| {
                    let p = id.parent()?;
                    built.get((p.y * px + p.x) as usize)?.as_ref().map(|c| (p, c))
                });
                let mesh = if source.has_node(id) {
                    Some(build_node(source, id, parent, &options)?)
                } else {
                    None
                };
                progress.advance(1);
                Ok(mesh)
            })
            .collect();
        levels[level as usize] = built.into_iter().collect::<Result<_, _>>()?;
    }
    Ok(BuiltMeshes { options, levels })
}

/// The mesh of node `id`, refining `parent`'s mesh (none at the root level).
pub fn build_node(
    source: &dyn NodeSource,
    id: NodeId,
    parent: Option<(NodeId, &BuiltMesh)>,
    options: &MeshOptions,
) -> Result<BuiltMesh, MeshesError> {
    // A node none of whose children is stored is drawn however near the
    // camera comes: exact, on its own posts (the best data there).
    // The reference lattice is never finer than the best data under the
    // node: over a coarse layer (the base) it is that layer's own lattice,
    // whose cells are then drawn along the data's diagonal as the child
    // nodes draw them, so the meshes still nest.
    let finest = finest_stored_level(source, id);
    let leaf = finest == id.level;
    let post_level = (id.level - id.level.min(options.depth)).max(finest);
    let reference = reference_grid(source, id, post_level)?;
    let grid = HeightGrid::with_voids(reference.side, &reference.heights)
        .map_err(|e| MeshesError::Mesh { id, source: e })?;
    let diagonal = Diagonal::of_node(id.x, id.y);
    // Half cells are redrawn along the data's diagonal only on the data's
    // own lattice (see `RtinOptions::hierarchy_leaves`).
    let hierarchy_leaves = post_level > finest;
    let rtin_options = RtinOptions {
        metric: Metric::Surface,
        diagonal,
        hierarchy_leaves,
        ..RtinOptions::default()
    };
    let rtin = Rtin::new(&grid, rtin_options).map_err(|e| MeshesError::Mesh { id, source: e })?;
    let shift = id.level - post_level;
    let extent = options.tile_cells << shift;
    let node_size = source.layout().node_size as i64;
    let placement =
        parent.map(|(pid, p)| (Placement { id, parent: pid, node_size, post_level }, p));
    let keep = |m: [u32; 2]| placement.as_ref().is_some_and(|(at, p)| parent_has(at, p, m));
    let mut error = if leaf { 0.0 } else { options.level_error(id.level) as f64 };
    let mesh = loop {
        match rtin.extract_with(error, extent, keep) {
            Ok(mesh) => break mesh,
            Err(MeshError::TooManyVertices { .. }) if error < 1e6 => error = (2.0 * error).max(1.0),
            Err(e) => return Err(MeshesError::Mesh { id, source: e }),
        }
    };
    let heights = mesh.vertex_heights(&grid);
    let surface = max_surface_distance(&mesh, &heights, &grid);
    let delta = round_up_to_f32(surface + reference.delta as f64);
    let sampler = MeshSampler::of_rtin(&mesh, &heights, &rtin);
    let vertices = vertices(source, &reference, &mesh, &heights, placement.as_ref());
    let node_mesh = NodeMesh { post_level, vertices, indices: mesh.indices };
    node_mesh.debug_check();
    Ok(BuiltMesh { mesh: node_mesh, delta, error_m: error as f32, sampler })
}

/// The finest level with a stored node under node `id` (`id.level` for a
/// leaf: no child stored).
fn finest_stored_level(source: &dyn NodeSource, id: NodeId) -> u8 {
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

/// Whether the parent's mesh has a vertex at the child's reference post `m`.
fn parent_has(at: &Placement, parent: &BuiltMesh, m: [u32; 2]) -> bool {
    let [x, y] = at.parent_post(parent.mesh.post_level, m);
    x >= 0.0
        && y >= 0.0
        && x.fract() == 0.0
        && y.fract() == 0.0
        && parent.sampler.has_vertex(x as u32, y as u32)
}

/// Where a node's reference posts lie in its parent's mesh.
struct Placement {
    id: NodeId,
    parent: NodeId,
    node_size: i64,
    post_level: u8,
}

impl Placement {
    /// The parent mesh's post coordinates (posts of `2^parent_level`) of the
    /// child's reference post `m`.
    fn parent_post(&self, parent_level: u8, m: [u32; 2]) -> [f64; 2] {
        let (id, pid, n) = (self.id, self.parent, self.node_size);
        let origin = |x: u32, level: u8| (x as i64 * n) << level;
        let at = |k: usize, child: u32, parent: u32| {
            let p0 = origin(child, id.level) + ((m[k] as i64) << self.post_level);
            (p0 - origin(parent, pid.level)) as f64 / (1i64 << parent_level) as f64
        };
        [at(0, id.x, pid.x), at(1, id.y, pid.y)]
    }
}

/// The stored vertices: heights, morph targets, and the data's normal at
/// each vertex's post (on the reference lattice, so the same post has the
/// same normal in every node and at every level drawn from that lattice).
fn vertices(
    source: &dyn NodeSource,
    reference: &ReferenceGrid,
    mesh: &Mesh,
    heights: &[f32],
    parent: Option<&(Placement, &BuiltMesh)>,
) -> Vec<MeshVertex> {
    let layout = *source.layout();
    let scale = (1u64 << reference.post_level) as f64;
    let spacing = [layout.spacing_m[0] * scale, layout.spacing_m[1] * scale];
    mesh.vertices
        .iter()
        .zip(heights)
        .map(|(&post, &height)| {
            let m = [post[0] as u32, post[1] as u32];
            let [x, y] = reference.normal(m[0], m[1], spacing);
            let on_parent = parent.and_then(|(at, p)| {
                let [px, py] = at.parent_post(p.mesh.post_level, m);
                p.sampler.height_on_mesh(px, py).filter(|h| h.is_finite())
            });
            MeshVertex {
                post,
                height,
                target: if height.is_nan() {
                    f32::NAN
                } else {
                    on_parent.map_or(height, |h| h as f32)
                },
                normal: [x, y, x, y],
            }
        })
        .collect()
}
