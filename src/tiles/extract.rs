//! A tile's mesh extracted from its node's error map when the tile is made
//! (issues 21 and 22): the right-triangulated irregular network of the best
//! data under the tile at the error its ring allows for this viewport and
//! tau, nested in the mesh its vertices morph toward.
//!
//! - **Error.** A split is made where the map's code is above the mesh's
//!   error, where a triangle is wider than the tile's square or than the
//!   curvature allows (the *forced* lattice), and where the meshes the
//!   tile must refine have a vertex.
//! - **Nesting.** The mesh keeps every vertex of the meshes of its node's
//!   resident ancestors at their own errors (the parent's mesh keeps its
//!   parent's, and so on), so it refines the parent's mesh and, fully
//!   morphed, draws the parent's very surface: no pop when the parent takes
//!   over. The maps share one hierarchy (a node's root diagonal continues
//!   its parent's), so the union of their vertex sets is closed and the
//!   mesh conforming.
//! - **Targets.** Each vertex's morph target is the target mesh's surface
//!   there: its own height where the target mesh has a vertex, else the
//!   mean of the targets at the ends of the hypotenuse it splits (the
//!   target surface is linear along it). The target mesh is the parent
//!   node's (a tile at its level's ring) or, for a leaf tile nearer than
//!   its level's ring, the same map at each sub-level's coarser one's
//!   error ([`crate::tiles::errors::MeshErrors::target_rule`]), its vertices of
//!   morph band 0 taking the parent's surface ([`Extraction::place_parent`]).
//! - **Fans.** A cell the mesh draws along the data's diagonal where the
//!   target folds along the other is split four ways ([`super::fan`]).

use std::collections::HashMap;

use super::by_distance::{reach_legs, split_leg, DistanceRule};
use super::fan::{fan_with, FanScratch};
use super::kept::{KeptBy, KeptTable};
use super::vertex::{slope, PostReader};
use crate::lod::TileKey;
use crate::mesh::code::{splits, threshold_code};
use crate::mesh::rtin::{Diagonal, Triangle};
use crate::node::{ErrorMap, MeshVertex, NodeData, NodeId, NodeLayout, NodeMesh};

/// One node's error map placed for a walk: which of its posts are
/// vertices of its mesh of one error, and the data at them.
pub struct PlacedMap<'a> {
    node: NodeId,
    data: &'a NodeData,
    /// Level-0 posts between the map's posts.
    step: u64,
    /// The node's south-west post, level 0.
    origin: [u64; 2],
    /// Splits are made where the code is above this.
    threshold: u8,
    /// No post's threshold is below this (`threshold` without a view; with
    /// one, its least error's): posts at or under it are never vertices,
    /// which spares most posts the distance and the cone.
    least: u8,
    /// Map posts between the corners of the squares every mesh of this
    /// map splits to (its tiles' squares, and the curvature's).
    forced: u32,
    /// The node's posts, for a dense map's heights and normals past the
    /// data's last post (extrapolated, as every tile's are).
    reader: PostReader<'a>,
    /// Dense maps: the last map post inside the data, east and north.
    inside: [u32; 2],
    /// Dense maps: posts a side of the node's stored heights, and its border.
    stored: (u32, u32),
    /// Metres between the map's posts, east and north.
    spacing_m: [f64; 2],
    /// Where the mesh's error grows with the distance (`None`: one error,
    /// `threshold`, everywhere): see [`super::by_distance`].
    view: Option<DistanceRule>,
    /// The smallest error the map serves, metres.
    floor_m: f64,
    /// The forced lattice's posts are vertices only where the view gives
    /// them an error: a target mesh past its last ring shows the level
    /// above's mesh, which has its own lattice ([`Self::force_where_viewed`]).
    forced_where_viewed: bool,
}

impl<'a> PlacedMap<'a> {
    /// Node `node`'s map in `data`, for meshes of `error_m` whose triangles
    /// lie in squares of `forced` map posts.
    pub fn new(
        layout: &'a NodeLayout,
        node: NodeId,
        data: &'a NodeData,
        error_m: f64,
        forced: u32,
    ) -> PlacedMap<'a> {
        let map = &data.map;
        let step = 1u64 << map.post_level;
        let span = (layout.node_size as u64) << node.level;
        let key = TileKey::new(node.level, node.x, node.y);
        let scale = step as f64;
        let origin = [node.x as u64 * span, node.y as u64 * span];
        let inside = [0, 1].map(|k| {
            let last = (layout.posts[k] as u64).saturating_sub(1);
            (last.saturating_sub(origin[k]) / step).min(map.cells as u64) as u32
        });
        PlacedMap {
            node,
            data,
            step,
            origin,
            inside,
            stored: (layout.stored_side(), layout.border),
            threshold: threshold_code(error_m.max(map.floor_m as f64)),
            least: threshold_code(error_m.max(map.floor_m as f64)),
            forced: forced.clamp(1, map.cells),
            reader: PostReader::new(layout, key, layout.node_size, node, data),
            spacing_m: [layout.spacing_m[0] * scale, layout.spacing_m[1] * scale],
            view: None,
            floor_m: map.floor_m as f64,
            forced_where_viewed: false,
        }
    }

    /// The same map with its error growing with the distance as `view`
    /// says (the error it was placed with no longer counts).
    pub fn with_view(self, view: DistanceRule) -> Self {
        // Every error the rule gives is at least one of its rings' own.
        let least_m = view.rings.iter().map(|r| r.own_m).fold(f64::INFINITY, f64::min);
        let least = threshold_code(least_m.max(self.floor_m));
        PlacedMap { view: Some(view), least, ..self }
    }

    /// The node whose map this is.
    pub fn node(&self) -> NodeId {
        self.node
    }

    /// Map posts between the corners of the squares its meshes split to.
    pub fn forced(&self) -> u32 {
        self.forced
    }

    /// Splits its meshes to squares of `forced` map posts (a power of two).
    pub fn set_forced(&mut self, forced: u32) {
        self.forced = forced.clamp(1, self.data.map.cells);
    }

    /// Places the map as a tile's target mesh: the forced lattice only
    /// where the view gives an error (past its rings the target is the
    /// level above's mesh, exactly).
    pub fn as_target(&mut self) {
        self.forced_where_viewed = self.view.is_some();
    }

    /// The map's post at level-0 post `x`, if it is one of the node's.
    fn local(&self, x: [u64; 2]) -> Option<[u32; 2]> {
        let cells = self.data.map.cells as u64;
        let mut p = [0u32; 2];
        for k in 0..2 {
            let d = x[k].checked_sub(self.origin[k])?;
            if d % self.step != 0 || d / self.step > cells {
                return None;
            }
            p[k] = (d / self.step) as u32;
        }
        Some(p)
    }

    /// The level-0 post of map post `p`.
    fn level0(&self, p: [u32; 2]) -> [u64; 2] {
        [self.origin[0] + p[0] as u64 * self.step, self.origin[1] + p[1] as u64 * self.step]
    }

    /// Whether map post `p`, its code given by `code`, is a vertex of this
    /// map's mesh.
    fn is_vertex(&self, p: [u32; 2], code: impl Fn() -> u8) -> bool {
        let on_forced = p[0] % self.forced == 0 && p[1] % self.forced == 0;
        debug_assert!(self.view.is_some() || self.least == self.threshold);
        if self.view.is_none() {
            return on_forced || code() > self.threshold;
        }
        if on_forced && !self.forced_where_viewed {
            return true;
        }
        let code = code();
        // The view's error, worked out once and only where it can decide.
        // The curvature splits where the split's legs are longer than
        // [`sag_leg_m`] at the vertex's own error (the sag lattice of
        // [`forced_step`], vertex by vertex, so that neighbouring tiles of
        // other sub-levels split their shared edge alike); a split's
        // dependencies have longer legs and no larger errors, so they
        // split too and the mesh stays closed.
        let leg_m = split_leg(p) * self.spacing_m[0].max(self.spacing_m[1]);
        let may_sag = leg_m > sag_leg_m(0.0);
        if !on_forced && code <= self.least && !may_sag {
            return false;
        }
        let Some(error_m) = self.error_m_at(p) else { return false };
        // The forced lattice of a target, only where viewed.
        on_forced
            || (code > self.least && splits(code, error_m.max(self.floor_m)))
            || (may_sag && leg_m > sag_leg_m(error_m))
    }

    /// The error the view allows the mesh at map post `p`, metres (`None`:
    /// no vertex of its own there, or no view).
    fn error_m_at(&self, p: [u32; 2]) -> Option<f64> {
        let view = self.view.as_ref()?;
        let (at, reach, heights) = self.view_inputs(p);
        view.accepting(at, reach, heights).map(|(ring, error_m)| {
            // Along a level-0 node's own edge (not shared) the mesh keeps
            // its vertex's ring's near-end error: the neighbouring node's
            // map codes the edge's posts apart, so the two meshes meet at
            // cracks as deep as both errors, which its skirts fill and a
            // viewer sees (issue 25). Shared edges' posts are coded alike
            // on both sides: no crack. Level 0's: farther levels' cracks
            // span fewer pixels (capping levels 1 and 2 too cost 4 % more
            // triangles at 480x272 and tau 4, past issue 22's floor ratio;
            // larger share squares, `SHARE_LEVEL`, leave fewer such edges
            // instead). The vertex's own ring's, as every
            // tile's rule gives it: the tile's finest ring's, as it was,
            // differs between neighbours of other sub-levels.
            let reached = self.edges_reached(p);
            let near_boundary = self.node.level == 0 && reached & !self.data.map.shared_edges != 0;
            match near_boundary {
                true => error_m.min(view.rings[ring].largest_within(0.0)),
                false => error_m,
            }
        })
    }

    /// Where map post `p` lies in the chart (metres), how far its split's
    /// dependants reach (metres), and the heights the view judges it with.
    fn view_inputs(&self, p: [u32; 2]) -> ([f64; 2], f64, [f64; 2]) {
        // Metres in the chart: level-0 posts times their spacing.
        let level0 = [self.spacing_m[0], self.spacing_m[1]].map(|s| s / self.step as f64);
        let x = self.level0(p);
        let at = [x[0] as f64 * level0[0], x[1] as f64 * level0[1]];
        let reach = split_leg(p) * reach_legs() * self.spacing_m[0].max(self.spacing_m[1]);
        // A split whose reach meets a shared edge is judged against the
        // view with heights both nodes agree on: with each node's own, one
        // side kept an edge post the other left out of the cone, a crack
        // with no skirt under it (`tests/scene_cracks.rs`).
        let heights = match self.edges_reached(p) & self.data.map.shared_edges != 0 {
            // The view cone's vertical extent where two nodes must agree.
            true => crate::geo::TERRAIN_RANGE_M,
            false => [self.data.min as f64, self.data.max as f64],
        };
        (at, reach, heights)
    }

    /// The morph band of the vertex at level-0 post `x` (0 without a view,
    /// or off the map): see [`DistanceRule::band_at`], by the vertex's own
    /// place. Not by its dependants' reach, as its error is: a coarse
    /// split far out reaches near the camera, and in a finer band it would
    /// never morph onto the level above, which then took over with a pop.
    fn band_at(&self, x: [u64; 2]) -> u8 {
        let (Some(view), Some(p)) = (&self.view, self.local(x)) else { return 0 };
        let (at, _, heights) = self.view_inputs(p);
        view.band_at(at, 0.0, heights)
    }

    /// The node edges (bits of [`ErrorMap::shared_edges`]) map post `p`'s
    /// split reaches within its reach.
    fn edges_reached(&self, p: [u32; 2]) -> u8 {
        let legs = split_leg(p) * reach_legs();
        let cells = self.data.map.cells as f64;
        let near = |c: u32| c as f64 <= legs;
        let far = |c: u32| c as f64 >= cells - legs;
        let bit = |reached: bool, edge: u8| if reached { edge } else { 0 };
        bit(near(p[0]), ErrorMap::WEST)
            | bit(far(p[0]), ErrorMap::EAST)
            | bit(near(p[1]), ErrorMap::SOUTH)
            | bit(far(p[1]), ErrorMap::NORTH)
    }

    /// Whether level-0 post `x` is a vertex of this map's mesh.
    fn has_vertex(&self, x: [u64; 2]) -> bool {
        self.local(x).is_some_and(|p| self.is_vertex(p, || self.data.map.code(p[0], p[1])))
    }

    /// The height and data normal the map keeps at level-0 post `x`.
    fn data_at(&self, x: [u64; 2]) -> Option<(f32, [i8; 2])> {
        let p = self.local(x)?;
        let map = &self.data.map;
        if map.is_dense() {
            let (i, j) = (p[0] as i64, p[1] as i64);
            let h = |di: i64, dj: i64| self.dense_height(i + di, j + dj) as f64;
            let dx = slope(h(-1, 0), h(0, 0), h(1, 0), self.spacing_m[0]);
            let dy = slope(h(0, -1), h(0, 0), h(0, 1), self.spacing_m[1]);
            return Some((h(0, 0) as f32, quantise_normal(dx, dy)));
        }
        let k = map.find(p[0], p[1])?;
        Some((map.heights[k], map.normals[k]))
    }
}

/// Map posts between the corners of the squares every mesh of a node's
/// map splits to (a power of two): the tiles' squares (`tile_posts` map
/// posts), the node's quadrants (so a parent's mesh always has its
/// children's corners), and the widest triangle the curvature allows at
/// `error_m` ([`sag_extent`]).
pub fn forced_step(
    layout: &NodeLayout,
    post_level: u8,
    cells: u32,
    tile_posts: u32,
    error_m: f64,
) -> u32 {
    let sag = sag_extent(layout, post_level, error_m);
    tile_posts.min(cells / 2).min(sag).max(1)
}

/// The longest leg, metres, of a right triangle whose chord stays within
/// the curved earth's drop by a quarter of `error_m` (at least
/// 5 cm): see [`sag_extent`].
pub fn sag_leg_m(error_m: f64) -> f64 {
    let allowed = (error_m / 4.0).max(EXACT_SAG_M);
    (4.0 * crate::camera::EARTH_RADIUS_M * allowed).sqrt()
}

/// How far, metres, a mesh's triangles may sag below the curved earth
/// beyond what the data's own cells do, at least (exact meshes): 5 cm.
const EXACT_SAG_M: f64 = 0.05;

/// The widest triangle (a power of two of lattice cells, at least one)
/// whose chord stays within the curved earth's drop by a quarter of
/// `error_m` (at least `EXACT_SAG_M`). The display lowers each vertex by
/// its drop, `d^2 / 2R`, and draws straight between: a right triangle of
/// legs `a` sags by up to `a^2 / 4R` (its circumradius squared over 2R).
/// That is under a millimetre over 90 m posts, but over ETOPO5's 9 km
/// posts a level-0 mesh merging eight cells sagged 100 m, 3.6 px at tau 1.
pub fn sag_extent(layout: &NodeLayout, post_level: u8, error_m: f64) -> u32 {
    let leg_m = sag_leg_m(error_m);
    let cell_m = layout.spacing_m[0].max(layout.spacing_m[1]) * (1u64 << post_level) as f64;
    let cells = (leg_m / cell_m).floor().clamp(1.0, u32::MAX as f64) as u32;
    1 << cells.ilog2()
}

impl PlacedMap<'_> {
    /// A dense map's height at its post `(i, j)` (one post past the node
    /// allowed): read from the node's stored posts inside the data, as the
    /// tiles read them past it.
    fn dense_height(&self, i: i64, j: i64) -> f32 {
        let (side, border) = (self.stored.0 as i64, self.stored.1 as i64);
        let within = |p: i64, last: u32| p >= -border && p <= last as i64;
        if within(i, self.inside[0]) && within(j, self.inside[1]) {
            let at = (j + border) * side + i + border;
            if let Some(&h) = self.data.heights.get(at as usize) {
                return h;
            }
        }
        self.reader.post(i, j)
    }
}

/// Unit normal of slopes `dx`, `dy` (rise per metre), x and y scaled to
/// -127..127; flat where a slope is not a number.
pub fn quantise_normal(dx: f64, dy: f64) -> [i8; 2] {
    if dx.is_nan() || dy.is_nan() {
        return [0, 0];
    }
    let inv = 1.0 / (dx * dx + dy * dy + 1.0).sqrt();
    let q = |x: f64| (x * 127.0).round().clamp(-127.0, 127.0) as i8;
    [q(-dx * inv), q(-dy * inv)]
}

/// The mesh a tile's vertices morph toward.
#[derive(Clone, Copy)]
pub enum TargetMesh<'m, 'a> {
    /// None: the tile is drawn unmorphed (drawn from an ancestor's data, or
    /// its parent is not resident).
    None,
    /// The parent node's mesh: the first of the ancestors.
    Parent,
    /// The same map at a coarser error (a sub-level up).
    Coarser(&'m PlacedMap<'a>),
}

impl TargetMesh<'_, '_> {
    /// Whether there is a mesh to morph toward.
    pub fn morphs(&self) -> bool {
        !matches!(self, TargetMesh::None)
    }
}

/// What a tile's mesh is extracted with.
pub struct Extraction<'m, 'a> {
    /// The tile's node's map at the tile's error.
    pub own: &'m PlacedMap<'a>,
    /// The node's resident ancestors' maps at their errors, nearest first:
    /// the mesh keeps their vertices.
    pub ancestors: &'m [PlacedMap<'a>],
    /// What the vertices morph toward.
    pub target: TargetMesh<'m, 'a>,
    /// The tile's square in the map's posts: south-west post and width.
    pub origin: [u32; 2],
    /// The square's width, map posts.
    pub width: u32,
    /// Vertices of morph band 0 (`PlacedMap::band_at`: where the level's
    /// own ring takes over) morph onto the parent's surface, whatever the
    /// target mesh (a leaf tile's target of its sub-levels, whose vertices
    /// far out but reaching near keep the sub-levels' errors): the level
    /// above then takes over without a pop.
    pub place_parent: bool,
}

impl Extraction<'_, '_> {
    /// This extraction morphing onto the parent's mesh.
    fn onto_parent(&self) -> Extraction<'_, '_> {
        Extraction {
            own: self.own,
            ancestors: self.ancestors,
            target: TargetMesh::Parent,
            origin: self.origin,
            width: self.width,
            place_parent: false,
        }
    }

    /// Which of the extraction's meshes have a vertex at level-0 post `x`.
    fn kept_by(&self, x: [u64; 2]) -> KeptBy {
        // The coarser sub-level's vertices are the tile's too: past its
        // band's morph the own map keeps none of its own
        // (`super::by_distance`).
        let ancestor = self.ancestors.iter().any(|a| a.has_vertex(x));
        // The coarser sub-level's map is the own one at another error: its
        // code is read once for both (a sparse map's is a search).
        let Some(p) = self.own.local(x) else {
            return KeptBy::new(if ancestor { KeptBy::ANCESTOR } else { 0 });
        };
        let map = &self.own.data.map;
        let read = std::cell::OnceCell::new();
        let code = || *read.get_or_init(|| map.code(p[0], p[1]));
        let coarser = match self.target {
            TargetMesh::Coarser(c) if std::ptr::eq(c.data, self.own.data) => c.is_vertex(p, code),
            TargetMesh::Coarser(c) => c.has_vertex(x),
            _ => false,
        };
        let own = !coarser && !ancestor && self.own.is_vertex(p, code);
        let bit = |kept: bool, bit: u8| if kept { bit } else { 0 };
        KeptBy::new(
            bit(own, KeptBy::OWN) | bit(coarser, KeptBy::COARSER) | bit(ancestor, KeptBy::ANCESTOR),
        )
    }

    /// Whether level-0 post `x` is a vertex of the tile's mesh.
    fn own_has(&self, x: [u64; 2]) -> bool {
        self.kept_by(x).by_tile()
    }

    /// Whether level-0 post `x` is a vertex of the mesh the tile morphs
    /// toward (none: no target, the tile does not morph).
    fn target_has(&self, x: [u64; 2]) -> bool {
        match self.target {
            TargetMesh::None => false,
            TargetMesh::Parent => self.ancestors.iter().any(|a| a.has_vertex(x)),
            TargetMesh::Coarser(_) => self.kept_by(x).by_target(),
        }
    }

    /// The morph band of the tile's vertex at level-0 post `x`: its own
    /// map's rule's (0 where the tile does not morph).
    fn band_at(&self, x: [u64; 2]) -> u8 {
        match self.morphs() {
            true => self.own.band_at(x),
            false => 0,
        }
    }

    /// Whether the tile morphs at all.
    fn morphs(&self) -> bool {
        !matches!(self.target, TargetMesh::None)
    }

    /// The height and normal of the mesh at its vertex `x`: from the first
    /// map of the tile's chain that keeps the post.
    fn own_data(&self, x: [u64; 2]) -> Option<(f32, [i8; 2])> {
        std::iter::once(self.own).chain(self.ancestors).find_map(|m| m.data_at(x))
    }

    /// The same for the target mesh: its own chain's first map keeping it.
    fn target_data(&self, x: [u64; 2]) -> Option<(f32, [i8; 2])> {
        let coarser = match self.target {
            TargetMesh::Coarser(c) => Some(c),
            _ => None,
        };
        coarser.into_iter().chain(self.ancestors).find_map(|m| m.data_at(x))
    }

    /// The same for the parent's mesh: the first ancestor keeping it.
    fn parent_data(&self, x: [u64; 2]) -> Option<(f32, [i8; 2])> {
        self.ancestors.iter().find_map(|m| m.data_at(x))
    }

    /// The map whose drawing rule (half cells along the data's diagonal or
    /// as the hierarchy makes them) the target mesh follows.
    fn target_map(&self) -> Option<&PlacedMap<'_>> {
        match self.target {
            TargetMesh::None => None,
            TargetMesh::Parent => self.ancestors.first(),
            TargetMesh::Coarser(c) => Some(c),
        }
    }
}

/// Why a tile's mesh could not be extracted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ExtractError {
    /// More vertices than 16-bit indices address: extract at a larger error.
    #[error("the tile's mesh needs more than 65536 vertices")]
    TooManyVertices,
    /// A vertex's post is kept by no map of the chain (a damaged map).
    #[error("post {0:?} is a vertex but no map keeps its height")]
    Unkept([u64; 2]),
}

/// Target height and normal carried down the walk.
#[derive(Clone, Copy)]
struct Target {
    height: f32,
    normal: [f32; 2],
}

/// Scratch for extracting tiles' meshes, reused (no allocation once the
/// largest tile has been extracted).
#[derive(Default)]
pub struct Extractor {
    /// Map post key (`j * side + i`) to vertex number.
    numbers: HashMap<u32, u16, crate::hash::BuildIdHasher>,
    /// Per vertex: the target mesh's surface, and the parent's (band-0
    /// vertices of a tile with [`Extraction::place_parent`] take it), both
    /// carried down the walk.
    targets: Vec<Target>,
    parents: Vec<Target>,
    /// Which meshes keep the posts of the tile's square.
    kept: KeptTable,
    leaves: Vec<Triangle>,
    fans: FanScratch,
    /// The extracted mesh (posts in half steps of the map's lattice, from
    /// the node's south-west post), then fanned.
    pub mesh: NodeMesh,
}

impl Extractor {
    /// Extracts the tile's mesh into [`Self::mesh`].
    pub fn extract(&mut self, job: &Extraction<'_, '_>) -> Result<(), ExtractError> {
        self.numbers.clear();
        self.targets.clear();
        self.parents.clear();
        self.kept.reset(job.origin, job.width);
        self.leaves.clear();
        self.mesh.vertices.clear();
        self.mesh.indices.clear();
        self.mesh.bands.clear();
        let map = &job.own.data.map;
        self.mesh.post_level = map.post_level;
        let cells = map.cells;
        let node = job.own.node;
        let roots = Triangle::roots_along(cells, Diagonal::of_node(node.x, node.y));
        // Every split below a corner needs its ends: the node's corners
        // are made whether or not they touch the square.
        for corner in [[0, 0], [cells, 0], [0, cells], [cells, cells]] {
            self.corner_vertex(job, corner)?;
        }
        for root in roots {
            self.walk(job, root, job.morphs(), job.place_parent)?;
        }
        self.emit(job)?;
        // A fanned cell's centre takes its south-west corner's band, and
        // that band's target surface.
        let onto_parent = job.onto_parent();
        let parent_at = |x: f64, y: f64| {
            let p = [x / 2.0, y / 2.0];
            let corner = job.own.level0([p[0].floor() as u32, p[1].floor() as u32]);
            match job.place_parent && job.band_at(corner) == 0 {
                true => target_at(&onto_parent, p),
                false => target_at(job, p),
            }
        };
        if job.morphs() {
            let mesh = &mut self.mesh;
            fan_with(
                &mut self.fans,
                &mut mesh.vertices,
                &mut mesh.indices,
                &mut mesh.bands,
                parent_at,
            );
        }
        if self.mesh.vertices.len() > 1 << 16 {
            return Err(ExtractError::TooManyVertices);
        }
        Ok(())
    }

    /// Creates the vertex at a corner of the node (a vertex of every mesh).
    fn corner_vertex(&mut self, job: &Extraction<'_, '_>, p: [u32; 2]) -> Result<(), ExtractError> {
        let x = job.own.level0(p);
        let (height, normal) = job.own_data(x).ok_or(ExtractError::Unkept(x))?;
        let own = Target { height, normal: normal.map(f32::from) };
        let target = match job.target_data(x) {
            Some((h, n)) if job.morphs() => Target { height: h, normal: n.map(f32::from) },
            _ => own,
        };
        let parent = match job.parent_data(x) {
            Some((h, n)) if job.place_parent => Target { height: h, normal: n.map(f32::from) },
            _ => target,
        };
        self.push_vertex(job, p, height, normal, [target, parent])
    }

    /// Splits `t` where the tile's mesh does, and on down; `target_split`
    /// and `parent_split`: whether the target's and the parent's meshes
    /// split every triangle above `t` (below a leaf of theirs, their
    /// surface is linear: a vertex takes the mean of its hypotenuse's).
    fn walk(
        &mut self,
        job: &Extraction<'_, '_>,
        t: Triangle,
        target_split: bool,
        parent_split: bool,
    ) -> Result<(), ExtractError> {
        let corners = t.ccw();
        let (lo, hi) = bounds(&corners);
        if !touches_square(lo, hi, job) {
            return Ok(());
        }
        let m = t.midpoint();
        let x = job.own.level0(m);
        let kept = self.kept.get(m, || job.kept_by(x));
        let split = !t.is_leaf() && (t.extent() > job.width || kept.by_tile());
        if !split {
            if centred_in_square(&corners, job) {
                self.leaves.push(t);
            }
            return Ok(());
        }
        let target_here = target_split && kept.by_target();
        let parent_here = parent_split && kept.by_parent();
        if !self.numbers.contains_key(&key(job, m)) {
            self.midpoint_vertex(job, &t, [target_here, parent_here])?;
        }
        for child in t.children() {
            self.walk(job, child, target_here, parent_here)?;
        }
        Ok(())
    }

    /// Creates the vertex splitting `t`. Its target, and its parent's
    /// surface: the mesh's own height where that mesh has a vertex there
    /// (`vertex`, target then parent), else the mean at the hypotenuse's
    /// ends.
    fn midpoint_vertex(
        &mut self,
        job: &Extraction<'_, '_>,
        t: &Triangle,
        vertex: [bool; 2],
    ) -> Result<(), ExtractError> {
        let m = t.midpoint();
        let x = job.own.level0(m);
        let (height, normal) = job.own_data(x).ok_or(ExtractError::Unkept(x))?;
        let own = Target { height, normal: normal.map(f32::from) };
        // The ends were made before the split (the node's corners, or the
        // splits above): the walk descends from the roots.
        let ends = [t.a, t.b].map(|p| self.numbers.get(&key(job, p)).copied());
        let [Some(a), Some(b)] = ends.map(|n| n.map(usize::from)) else {
            return Err(ExtractError::Unkept(job.own.level0(t.a)));
        };
        let mean = |s: &[Target]| Target {
            height: (s[a].height + s[b].height) / 2.0,
            normal: [0, 1].map(|k| (s[a].normal[k] + s[b].normal[k]) / 2.0),
        };
        let at = |data: Option<(f32, [i8; 2])>| {
            let (h, n) = data.ok_or(ExtractError::Unkept(x))?;
            Ok::<_, ExtractError>(Target { height: h, normal: n.map(f32::from) })
        };
        let target = match (vertex[0], job.morphs()) {
            (true, _) => at(job.target_data(x))?,
            (false, true) => mean(&self.targets),
            (false, false) => own,
        };
        let parent = match (vertex[1], job.place_parent) {
            (true, _) => at(job.parent_data(x))?,
            (false, true) => mean(&self.parents),
            (false, false) => target,
        };
        self.push_vertex(job, m, height, normal, [target, parent])
    }

    /// Adds the vertex at map post `p` with its height and normal, and its
    /// target and parent surfaces (see [`Self::midpoint_vertex`]).
    fn push_vertex(
        &mut self,
        job: &Extraction<'_, '_>,
        p: [u32; 2],
        height: f32,
        normal: [i8; 2],
        [target, parent]: [Target; 2],
    ) -> Result<(), ExtractError> {
        let number = self.mesh.vertices.len();
        if number >= 1 << 16 {
            return Err(ExtractError::TooManyVertices);
        }
        self.numbers.insert(key(job, p), number as u16);
        self.targets.push(target);
        self.parents.push(parent);
        // A vertex of band 0 morphs onto the parent's surface.
        let band = job.band_at(job.own.level0(p));
        self.mesh.bands.push(band);
        let target = match (band, job.place_parent) {
            (0, true) => parent,
            _ => target,
        };
        let nt = target.normal.map(|n| n.round().clamp(-127.0, 127.0) as i8);
        self.mesh.vertices.push(MeshVertex {
            post: [2 * p[0] as u16, 2 * p[1] as u16],
            height,
            target: target.height,
            normal: [normal[0], normal[1], nt[0], nt[1]],
        });
        Ok(())
    }

    /// The leaves as drawn: half cells across the data's diagonal with all
    /// four corners are redrawn along it (the truth's triangles).
    fn emit(&mut self, job: &Extraction<'_, '_>) -> Result<(), ExtractError> {
        let leaves = std::mem::take(&mut self.leaves);
        let hierarchy = job.own.data.map.hierarchy_leaves;
        for t in &leaves {
            let corners = if hierarchy {
                t.ccw()
            } else {
                t.drawn(|p| p[0] <= job.own.data.map.cells && job.own_has(job.own.level0(p)))
            };
            for c in corners {
                let number = match self.numbers.get(&key(job, c)) {
                    Some(&n) => n,
                    None => return Err(ExtractError::Unkept(job.own.level0(c))),
                };
                self.mesh.indices.push(number);
            }
        }
        self.leaves = leaves;
        Ok(())
    }
}

fn key(job: &Extraction<'_, '_>, p: [u32; 2]) -> u32 {
    p[1] * (job.own.data.map.cells + 1) + p[0]
}

fn bounds(corners: &[[u32; 2]; 3]) -> ([u32; 2], [u32; 2]) {
    let lo = [0, 1].map(|k| corners.iter().map(|c| c[k]).min().unwrap_or(0));
    let hi = [0, 1].map(|k| corners.iter().map(|c| c[k]).max().unwrap_or(0));
    (lo, hi)
}

/// Whether the box `[lo, hi]` meets the tile's closed square.
fn touches_square(lo: [u32; 2], hi: [u32; 2], job: &Extraction<'_, '_>) -> bool {
    (0..2).all(|k| hi[k] >= job.origin[k] && lo[k] <= job.origin[k] + job.width)
}

/// Whether a triangle's centroid lies strictly inside the tile's square
/// (triangles no wider than the square lie in one square of the lattice).
fn centred_in_square(corners: &[[u32; 2]; 3], job: &Extraction<'_, '_>) -> bool {
    (0..2).all(|k| {
        let c3 = corners.iter().map(|c| c[k] as u64).sum::<u64>();
        let o3 = 3 * job.origin[k] as u64;
        c3 > o3 && c3 < o3 + 3 * job.width as u64
    })
}

/// The target mesh's height and normal at map position `p` (map posts,
/// possibly halves): descends the hierarchy while the target splits, then
/// interpolates the target leaf as it is drawn.
fn target_at(job: &Extraction<'_, '_>, p: [f64; 2]) -> Option<(f64, [f64; 2])> {
    let cells = job.own.data.map.cells;
    let node = job.own.node;
    let [first, second] = Triangle::roots_along(cells, Diagonal::of_node(node.x, node.y));
    let mut t = if inside(&first, p) { first } else { second };
    while !t.is_leaf() && job.target_has(job.own.level0(t.midpoint())) {
        let [c0, c1] = t.children();
        t = if inside(&c0, p) { c0 } else { c1 };
    }
    let target_map = job.target_map()?;
    let corners = if target_map.data.map.hierarchy_leaves {
        t.ccw()
    } else {
        let drawn = t.drawn(|q| q[0] <= cells && job.target_has(job.own.level0(q)));
        // A redrawn pair hands the place to the half holding it.
        if drawn != t.ccw() {
            let (sx, sy) = (t.a[0].min(t.b[0]), t.a[1].min(t.b[1]));
            let (sw, ne) = ([sx, sy], [sx + 1, sy + 1]);
            if p[0] - sx as f64 >= p[1] - sy as f64 {
                [sw, [sx + 1, sy], ne]
            } else {
                [sw, ne, [sx, sy + 1]]
            }
        } else {
            drawn
        }
    };
    let data = corners.map(|c| job.target_data(job.own.level0(c)));
    let mut height = 0.0;
    let mut normal = [0.0; 2];
    let w = barycentric(corners, p);
    for k in 0..3 {
        let (h, n) = data[k]?;
        height += w[k] * h as f64;
        normal = [0, 1].map(|d| normal[d] + w[k] * n[d] as f64);
    }
    Some((height, normal))
}

fn inside(t: &Triangle, p: [f64; 2]) -> bool {
    barycentric(t.ccw(), p).iter().all(|&w| w >= -1e-9)
}

fn barycentric(corners: [[u32; 2]; 3], p: [f64; 2]) -> [f64; 3] {
    let v = corners.map(|c| [c[0] as f64, c[1] as f64]);
    let area = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let total = area(v[0], v[1], v[2]);
    [area(v[1], v[2], p) / total, area(v[2], v[0], p) / total, area(v[0], v[1], p) / total]
}
