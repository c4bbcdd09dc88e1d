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
//!    data's normal there;
//! 6. cells drawn across a fold of the parent's split into fans, so that
//!    fully morphed the mesh is the parent's surface ([`super::fan`]).

use rayon::prelude::*;

use super::fan::fan_unnested_cells;
use super::reference::{reference_grid, ReferenceGrid};
use super::{MeshOptions, MeshesError};
use crate::mesh::rtin::round_up_to_f32;
use crate::mesh::{
    max_surface_distance, Diagonal, HeightGrid, Mesh, MeshError, MeshSampler, Metric, Rtin,
    RtinOptions, MAX_VERTICES,
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
    /// What its children's morph targets are read from; dropped once they
    /// are built.
    surface: Option<MeshSurface>,
}

/// A built mesh's drawn surface: its height, and its normal as the GPU
/// interpolates it across each triangle, anywhere in the node.
struct MeshSurface {
    height: MeshSampler,
    normal: [MeshSampler; 2],
}

impl MeshSurface {
    /// Height and normal (x, y, scaled to -127..127) at `(x, y)` in the
    /// mesh's reference posts; `None` outside the node.
    fn at(&self, x: f64, y: f64) -> Option<(f64, [f64; 2])> {
        let height = self.height.height_on_mesh(x, y)?;
        let normal = self.normal.each_ref().map(|n| n.height_on_mesh(x, y).unwrap_or(0.0));
        Some((height, normal))
    }
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
        // The parents' surfaces are read by their children only.
        if let Some(parents) = levels.get_mut(level as usize + 1) {
            parents.iter_mut().flatten().for_each(|p| p.surface = None);
        }
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
    // A mesh too large for 16-bit indices, fans included, is simplified further.
    let (mesh, node_mesh) = loop {
        let extent = extent.min(sag_extent(source.layout(), post_level, error));
        let mesh = match rtin.extract_with(error, extent, keep) {
            Ok(mesh) => mesh,
            Err(MeshError::TooManyVertices { .. }) if error < 1e6 => {
                error = (2.0 * error).max(1.0);
                continue;
            }
            Err(e) => return Err(MeshesError::Mesh { id, source: e }),
        };
        let heights = mesh.vertex_heights(&grid);
        let node_mesh = stored_mesh(source, &reference, &mesh, &heights, placement.as_ref());
        if node_mesh.vertices.len() <= MAX_VERTICES || error >= 1e6 {
            break ((mesh, heights), node_mesh);
        }
        error = (2.0 * error).max(1.0);
    };
    let (mesh, heights) = mesh;
    if node_mesh.vertices.len() > MAX_VERTICES {
        let count = node_mesh.vertices.len();
        return Err(MeshesError::Mesh { id, source: MeshError::TooManyVertices { count } });
    }
    // Fans draw the mesh's own surface: its distance to the data is the mesh's.
    let surface = max_surface_distance(&mesh, &heights, &grid);
    let delta = round_up_to_f32(surface + reference.delta as f64);
    let normal = [0, 1].map(|k| {
        let values: Vec<f32> =
            node_mesh.vertices[..mesh.vertices.len()].iter().map(|v| v.normal[k] as f32).collect();
        MeshSampler::of_rtin(&mesh, &values, &rtin)
    });
    let surface = MeshSurface { height: MeshSampler::of_rtin(&mesh, &heights, &rtin), normal };
    node_mesh.debug_check();
    Ok(BuiltMesh { mesh: node_mesh, delta, error_m: error as f32, surface: Some(surface) })
}

/// How far, metres, a node mesh's triangles may sag below the curved earth
/// beyond what the data's own cells do, at least (exact meshes): 5 cm.
const EXACT_SAG_M: f64 = 0.05;

/// The widest triangle (a power of two of lattice cells, at least one)
/// whose chord stays within the curved earth's drop by a quarter of
/// `error` (at least [`EXACT_SAG_M`]). The display lowers each vertex by
/// its drop, `d^2 / 2R`, and draws straight between: a right triangle of
/// legs `a` sags by up to `a^2 / 4R` (its circumradius squared over 2R).
/// That is under a millimetre over 90 m posts, but over ETOPO5's 9 km
/// posts a level-0 mesh merging eight cells sagged 100 m, 3.6 px at tau 1.
fn sag_extent(layout: &NodeLayout, post_level: u8, error: f64) -> u32 {
    let allowed = (error / 4.0).max(EXACT_SAG_M);
    let leg_m = (4.0 * crate::camera::EARTH_RADIUS_M * allowed).sqrt();
    let cell_m = layout.spacing_m[0].max(layout.spacing_m[1]) * (1u64 << post_level) as f64;
    let cells = (leg_m / cell_m).floor().clamp(1.0, u32::MAX as f64) as u32;
    1 << cells.ilog2()
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
    let [x, y] = at.parent_post(parent.mesh.post_level, m.map(f64::from));
    x >= 0.0
        && y >= 0.0
        && x.fract() == 0.0
        && y.fract() == 0.0
        && parent.surface.as_ref().is_some_and(|s| s.height.has_vertex(x as u32, y as u32))
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
    fn parent_post(&self, parent_level: u8, m: [f64; 2]) -> [f64; 2] {
        let (id, pid, n) = (self.id, self.parent, self.node_size);
        let origin = |x: u32, level: u8| (x as i64 * n) << level;
        let at = |k: usize, child: u32, parent: u32| {
            // Whole level-0 posts, then the fraction: exact for half posts.
            let p0 = origin(child, id.level) - origin(parent, pid.level);
            (p0 as f64 + m[k] * (1i64 << self.post_level) as f64) / (1i64 << parent_level) as f64
        };
        [at(0, id.x, pid.x), at(1, id.y, pid.y)]
    }
}

/// The stored mesh: its vertices (posts in half steps), with cells across
/// a fold of the parent's drawn as fans ([`fan_unnested_cells`]).
fn stored_mesh(
    source: &dyn NodeSource,
    reference: &ReferenceGrid,
    mesh: &Mesh,
    heights: &[f32],
    parent: Option<&(Placement, &BuiltMesh)>,
) -> NodeMesh {
    let mut vertices = vertices(source, reference, mesh, heights, parent);
    let mut indices = mesh.indices.clone();
    if let Some((at, p)) = parent {
        let parent_at = |x: f64, y: f64| {
            let [px, py] = at.parent_post(p.mesh.post_level, [x / 2.0, y / 2.0]);
            p.surface.as_ref()?.at(px, py)
        };
        fan_unnested_cells(&mut vertices, &mut indices, parent_at);
    }
    NodeMesh { post_level: reference.post_level, vertices, indices }
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
                let [px, py] = at.parent_post(p.mesh.post_level, m.map(f64::from));
                p.surface.as_ref()?.at(px, py).filter(|(h, _)| h.is_finite())
            });
            // Where the parent has no surface the vertex does not morph.
            let (target, [nx, ny]) = match on_parent {
                Some((h, n)) if !height.is_nan() => (h as f32, n.map(to_i8)),
                _ if height.is_nan() => (f32::NAN, [x, y]),
                _ => (height, [x, y]),
            };
            MeshVertex { post: post.map(|c| 2 * c), height, target, normal: [x, y, nx, ny] }
        })
        .collect()
}

/// A normal component interpolated between stored ones, stored again.
fn to_i8(n: f64) -> i8 {
    n.round().clamp(-127.0, 127.0) as i8
}
