//! One frame's draw data: the per-frame uniforms and, per tile, only what the
//! shader cannot share: the tile's transform, its morph range and skirt depth,
//! and where its block's vertices and indices are (Polok: transforms in
//! uniforms).
//!
//! Positions are placed on integer level-0 post numbers counted from an
//! anchor post next to the camera ([`PostFrame`]): the shader computes a
//! vertex as `(post number) * spacing - (camera minus anchor)` in f32, so a
//! post shared by two tiles gets the same bits from both (watertight edges),
//! and every number stays small however far the camera is from the origin.

use crate::camera::Camera;
use crate::earth::{EarthFrame, NodePlace, PlaceCache};
use crate::lod::{LevelRings, TileKey};
use crate::tiles::block::TileVertex;
use crate::tiles::block::{BLOCK_ALIGNMENT, INDEX_BYTES};
use crate::tiles::cache::EdgeErrors;
use crate::tiles::errors::MeshErrors;
use crate::tiles::seams::Seams;
use crate::tiles::{TileBlock, TileCoverage, TileDraw};
use glam::{DVec2, Mat4, Vec3};

#[cfg(feature = "test-support")]
use super::cluster::ClusterMorph;
use super::cluster::{Cluster, Member};

/// Uniforms shared by every tile of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameUniforms {
    /// Projection times the rotation-only view.
    pub view_projection: Mat4,
    /// Camera altitude above mean sea level, metres (terrain awareness and
    /// the vertical offset of every vertex).
    pub camera_altitude: f64,
    /// Unit vector toward the sun in the local frame.
    pub sun_direction: Vec3,
    /// Whether to lower vertices by the earth's curvature.
    pub curvature: bool,
    /// The lowest height terrain can have where the display draws none,
    /// metres: the sky pass draws the no-data hatching below this sphere's
    /// horizon. Sea level (0 m), the surface a pilot sees, unless the data
    /// cover the whole earth and go lower (a bathymetric grid imported with
    /// its sea floor): then a ray between the two horizons passes over all
    /// the terrain there is, and is sky ([`crate::scene::horizon_floor_m`]).
    pub horizon_floor_m: f32,
    /// Every morph's start over its end (`1 - morph_range`): a band's
    /// start from its end ([`crate::lod::morph::band_range`]).
    pub morph_start_share: f32,
    /// Terrain-awareness bands, metres relative to the aircraft: terrain above
    /// `warning_above_m` is red, above `-caution_below_m` amber.
    pub warning_above_m: f32,
    /// Depth, metres below the aircraft, above which terrain is amber (see `warning_above_m`).
    pub caution_below_m: f32,
    /// Viewport in pixels, width and height.
    pub viewport: [u32; 2],
    /// Distance at which fog has fully hidden the terrain, metres.
    pub fog_distance_m: f32,
    /// Where level-0 posts are relative to the camera.
    pub posts: PostFrame,
    /// The data's last level-0 post east and north (the layout's posts
    /// minus one): the terrain program clips every tile there, so a cell
    /// the data end inside ends with them (see `tiles::PostReader::value`).
    pub last_post: [i64; 2],
    /// The depth range cut in two where one 24-bit range cannot resolve it.
    pub slices: DepthSlices,
    /// Drawn on the ellipsoid (the camera's east-north-up axes, each
    /// node placed by [`EarthFrame::place`]); `None`: in the planar chart,
    /// lowered by `d^2 / 2R` where `curvature` is on.
    pub earth: Option<EarthFrame>,
}

impl FrameUniforms {
    /// `u_earth[2]` (zero: the chart), with [`Self::morph_start_share`]
    /// in the last float.
    pub fn earth_uniforms(&self) -> [f32; 8] {
        let mut uniforms = self.earth.map_or([0.0; 8], |e| e.uniforms());
        uniforms[7] = self.morph_start_share;
        uniforms
    }
}

/// A 24-bit depth buffer resolves `d^2 / (near 2^24)` metres at distance `d`:
/// with the near plane at a metre (flying low) that is 280 m at 68 km, and far
/// ridges fight over pixels. Then the terrain is drawn in two depth slices,
/// far first, the depth buffer cleared between: `[split, far]` and
/// `[near, split]` with `split = sqrt(near far)`, each resolving the other's
/// worst case far better (0.7 m at 68 km for a 1 m near plane and a 150 km
/// far one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthSlices {
    /// Projection times view for `[near, split]` (the whole range when there is no far slice).
    pub near: Mat4,
    /// Projection times view for `[split * SLICE_OVERLAP, far]`, if cut.
    pub far: Option<Mat4>,
    /// Distance between the slices, metres (the far plane when not cut).
    pub split_m: f32,
    /// View depth over distance, at least, for a point in view: the cosine
    /// of half the diagonal field of view.
    pub min_depth_share: f32,
    /// The largest height difference between the camera and any terrain
    /// the data holds, metres.
    pub max_drop_m: f32,
}

/// The far slice starts this share of the split in front of it, so the
/// slices overlap instead of leaving a hairline between their planes.
pub const SLICE_OVERLAP: f32 = 0.99;
/// Cut the range when one range resolves less than this at the far plane, metres.
const DEPTH_RESOLUTION_M: f64 = 1.0;

impl DepthSlices {
    /// The slices for `camera` between `near` and `far` metres, over data
    /// whose heights lie in `heights` (lowest, highest).
    pub fn new(camera: &Camera, near: f32, far: f32, heights: (f32, f32)) -> DepthSlices {
        let view = camera.view();
        let (n, f) = (near as f64, far as f64);
        let half_x = (camera.fov_x_deg.to_radians() / 2.0).tan();
        let half_y = (camera.fov_y() / 2.0).tan();
        let min_depth_share = (1.0 / (1.0 + half_x * half_x + half_y * half_y).sqrt()) as f32;
        let z = camera.position.z;
        let max_drop_m = (z - heights.0 as f64).abs().max((z - heights.1 as f64).abs()) as f32;
        if f * f / (n * (1u64 << 24) as f64) <= DEPTH_RESOLUTION_M {
            let near = camera.projection(near, far) * view;
            return DepthSlices { near, far: None, split_m: far, min_depth_share, max_drop_m };
        }
        let split = (n * f).sqrt() as f32;
        DepthSlices {
            near: camera.projection(near, split) * view,
            far: Some(camera.projection(split * SLICE_OVERLAP, far) * view),
            split_m: split,
            min_depth_share,
            max_drop_m,
        }
    }

    /// Whether a tile of `cells` cells is drawn in the near slice and in the
    /// far slice. Conservative: the near slice takes tiles whose nearest
    /// point could be in view at a depth below the split (view depth is at
    /// least `min_depth_share` of the distance; heights are left out, which
    /// only lowers the distance); the far slice takes every tile that could
    /// reach beyond the split, with any height the data holds.
    pub fn tile_slices(
        &self,
        tile: &TileUniforms,
        frame: &FrameUniforms,
        cells: f32,
    ) -> (bool, bool) {
        if self.far.is_none() {
            return (true, false);
        }
        let ([x0, y0], [x1, y1]) = tile.ground_rectangle(frame, cells);
        // Horizontal distance from the camera to the tile's rectangle, and to its far corner.
        let nearest = |lo: f32, hi: f32| {
            if lo > 0.0 {
                lo
            } else if hi < 0.0 {
                -hi
            } else {
                0.0
            }
        };
        let (dx, dy) = (nearest(x0.min(x1), x0.max(x1)), nearest(y0.min(y1), y0.max(y1)));
        let min_distance = (dx * dx + dy * dy).sqrt() as f64;
        let far_x = x0.abs().max(x1.abs()) as f64;
        let far_y = y0.abs().max(y1.abs()) as f64;
        let vertical = self.max_drop_m as f64;
        let max_distance = (far_x * far_x + far_y * far_y + vertical * vertical).sqrt();
        let split = self.split_m as f64;
        (
            min_distance * (self.min_depth_share as f64) < split,
            max_distance > split * SLICE_OVERLAP as f64,
        )
    }
}

/// The frame's post numbering: post `(i, j)` of the data (level 0) is
/// numbered `(i, j) - anchor`, and lies at `number * spacing - offset`
/// metres from the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PostFrame {
    /// The level-0 post at or south-west of the camera (not sent to the GPU).
    pub anchor: [i64; 2],
    /// Level-0 post spacing, metres east and north.
    pub spacing: [f32; 2],
    /// Camera position minus the anchor post, metres (in `[0, spacing)`).
    pub offset: [f32; 2],
}

impl PostFrame {
    /// The numbering for a camera at `eye` over posts `spacing_m` apart.
    pub fn new(eye: DVec2, spacing_m: [f64; 2]) -> PostFrame {
        let anchor = [0, 1].map(|k| (eye[k] / spacing_m[k]).floor());
        let offset = [0, 1].map(|k| (eye[k] - anchor[k] * spacing_m[k]) as f32);
        PostFrame { anchor: anchor.map(|a| a as i64), spacing: spacing_m.map(|s| s as f32), offset }
    }

    /// The number of level-0 post `post`, as the f32 the shader takes
    /// (exact below 2^24 posts from the camera).
    pub fn number(&self, post: [i64; 2]) -> [f32; 2] {
        [(post[0] - self.anchor[0]) as f32, (post[1] - self.anchor[1]) as f32]
    }
}

/// Per-tile uniforms, and where the tile's block is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileUniforms {
    /// The tile drawn.
    pub key: TileKey,
    /// The tile's south-west post, numbered from the frame's anchor.
    pub first_post: [f32; 2],
    /// Level-0 posts between the tile's posts (2^level).
    pub post_step: f32,
    /// Level-0 posts between its vertices' posts: a vertex's `post` times
    /// this is its place in level-0 posts from `first_post` (`post_step`
    /// for a regular grid, the node mesh's step for a mesh tile).
    pub vertex_step: f32,
    /// Morph start and end distances (equal and huge for no morph): its
    /// level's, toward the level above, which its band-0 vertices follow.
    pub morph: [f32; 2],
    /// The end of sub-level 1's morph, metres: a vertex of band `k >= 1`
    /// follows it halved `k - 1` times ([`crate::lod::morph::band_range`];
    /// 0 where no vertex has a band above 0).
    pub sub_morph_end: f32,
    /// How far the deepest of its skirts hangs below its edge, metres.
    pub skirt_depth: f32,
    /// Which edges hang a skirt: bit 0 south, 1 east, 2 north, 3 west (the
    /// order of [`crate::tiles::grid::edge_posts`]). See [`skirt_edges`].
    pub skirt_edges: u8,
    /// Per edge (in that order), the share of `skirt_depth` its skirt hangs,
    /// in [`SKIRT_SHARES`]ths, rounded up; 0 where it hangs none. See
    /// [`skirt_depths`].
    pub skirt_shares: [u8; 4],
    /// Metres of skirt per metre of a skirt vertex's distance from the
    /// camera that no skirt of the tile hangs deeper than (plus
    /// [`SKIRT_BASE_M`]); infinite for none. See [`skirt_slope`].
    pub skirt_slope: f32,
    /// Where the tile's block (its vertices) starts in the GPU buffer, bytes.
    pub byte_offset: u32,
    /// Where the tile's indices start in the same buffer, bytes.
    pub index_byte_offset: u32,
    /// The tile's indices, three per triangle, skirts included: one
    /// glDrawElements.
    pub index_count: u32,
    /// Some posts have no data: drawn by the program that drops the
    /// triangles touching them (after the tiles whose posts all have data, since that
    /// program cannot use early depth rejection).
    pub no_data: bool,
    /// Its node's placement on the ellipsoid (zero in the chart).
    pub place: NodePlace,
    /// On the ellipsoid, its [`Self::ground_rectangle`] computed once when
    /// the list was built (the draw order's sort and every depth slice's
    /// filter read it); `None`: computed where asked.
    pub ground: Option<[[f32; 2]; 2]>,
}

impl TileUniforms {
    /// The morph range vertex `vertex` follows, in a frame whose morphs
    /// start `start_share` of the way to their end
    /// ([`crate::lod::morph::band_range`]).
    pub fn vertex_morph(&self, vertex: &TileVertex, start_share: f32) -> [f32; 2] {
        crate::lod::morph::band_range(self.morph, self.sub_morph_end, start_share, vertex.band())
    }

    /// Camera-relative position of the tile's post `(i, j)`, metres, as
    /// `terrain.vert` computes it.
    pub fn post_position(&self, posts: &PostFrame, i: f32, j: f32) -> [f32; 2] {
        self.position(posts, self.post_step, i, j)
    }

    /// Camera-relative position of a vertex of the tile's block whose
    /// `post` is `(i, j)`, metres, as `terrain.vert` computes it (`u_tile.z`
    /// is the vertex step).
    pub fn vertex_position(&self, posts: &PostFrame, i: f32, j: f32) -> [f32; 2] {
        self.position(posts, self.vertex_step, i, j)
    }

    /// The lowest and highest camera-relative east and north of the
    /// tile's ground (height 0) over its `cells` cells: its chart
    /// rectangle, or on the ellipsoid the rectangle around its corners
    /// and edge midpoints (a tile's edges bow by far less than a cell).
    pub fn ground_rectangle(&self, frame: &FrameUniforms, cells: f32) -> ([f32; 2], [f32; 2]) {
        if let Some([lo, hi]) = self.ground {
            return (lo, hi);
        }
        let Some(earth) = frame.earth else {
            let [x0, y0] = self.post_position(&frame.posts, 0.0, 0.0);
            let [x1, y1] = self.post_position(&frame.posts, cells, cells);
            return ([x0.min(x1), y0.min(y1)], [x0.max(x1), y0.max(y1)]);
        };
        let uniforms = earth.uniforms();
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for i in 0..3 {
            for j in 0..3 {
                let [u, v] = [i, j].map(|k| k as f32 * cells / 2.0 * self.post_step);
                let post = [self.first_post[0] + u, self.first_post[1] + v];
                let p = self.place.vertex(&uniforms, post, 0.0);
                lo = [lo[0].min(p.x), lo[1].min(p.y)];
                hi = [hi[0].max(p.x), hi[1].max(p.y)];
            }
        }
        (lo, hi)
    }

    fn position(&self, posts: &PostFrame, step: f32, i: f32, j: f32) -> [f32; 2] {
        let at =
            |k: usize, n: f32| (self.first_post[k] + n * step) * posts.spacing[k] - posts.offset[k];
        [at(0, i), at(1, j)]
    }

    /// How far edge `edge`'s skirt hangs below it, metres (0 for none).
    pub fn edge_skirt_m(&self, edge: usize) -> f32 {
        self.skirt_depth * self.skirt_shares[edge] as f32 / SKIRT_SHARES as f32
    }

    /// The skirt shares as `terrain.vert` takes them: four bits per edge,
    /// south lowest (an integer below 2^16, exact in any float).
    pub fn packed_skirt_shares(&self) -> f32 {
        let word = self.skirt_shares.iter().rev().fold(0u32, |w, &s| (w << 4) | s as u32);
        (word | (slope_code(self.skirt_slope) << 16)) as f32
    }

    /// The shares [`Self::packed_skirt_shares`] packed.
    pub fn unpack_skirt_shares(packed: f32) -> [u8; 4] {
        let word = packed as u32;
        std::array::from_fn(|edge| ((word >> (4 * edge)) & 0xf) as u8)
    }

    /// The skirt slope [`Self::packed_skirt_shares`] packed (quantised up).
    pub fn unpack_skirt_slope(packed: f32) -> f32 {
        slope_of_code((packed as u32) >> 16)
    }

    /// Triangles the tile's draw call draws, skirts included.
    pub fn triangles(&self) -> u64 {
        self.index_count as u64 / 3
    }

    /// The bytes of the tile's block in the buffer: its vertices, its
    /// indices and the padding after them.
    pub fn block_range(&self) -> std::ops::Range<u32> {
        let end = self.index_byte_offset + self.index_count * INDEX_BYTES;
        self.byte_offset..end.next_multiple_of(BLOCK_ALIGNMENT)
    }

    /// The tile's block in `staging` (the copy the GPU buffer mirrors).
    pub fn block<'a>(&self, staging: &'a [u8]) -> TileBlock<'a> {
        TileBlock::new(staging, self.byte_offset, self.index_byte_offset, self.index_count)
    }
}

/// Everything drawn in one frame; buffers are kept and reused.
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    /// The uniforms every tile of the frame shares (none before a frame is built).
    pub uniforms: Option<FrameUniforms>,
    /// One entry per tile drawn this frame, nearest first.
    pub tiles: Vec<TileUniforms>,
    /// Cells per tile side.
    pub grid_size: u32,
    /// The frame's tiles, sorted by tile: what [`skirt_edges`] looks
    /// neighbours up in.
    pub drawn: Vec<DrawnTile>,
    /// Drawn as clusters (`clusters`, `members`), not one draw per tile:
    /// set by [`DrawList::cluster`] alone.
    pub(super) clustered: bool,
    /// The frame's clusters, in draw order (when clustered).
    pub clusters: Vec<Cluster>,
    /// Every cluster's members.
    pub members: Vec<Member>,
    /// Which morph range a cluster's members take (tests break it).
    #[cfg(feature = "test-support")]
    pub cluster_morph: ClusterMorph,
    /// A projected grid's node series, across frames.
    pub places: PlaceCache,
}

/// Where a frame's cluster draws go: the draw list's own vectors, lent to
/// the cluster cache by [`DrawList::cluster`].
pub struct ClusterDraws<'a> {
    /// The clusters, in draw order.
    pub clusters: &'a mut Vec<Cluster>,
    /// Every cluster's members.
    pub members: &'a mut Vec<Member>,
}

/// What [`skirt_edges`] needs of a neighbour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawnTile {
    /// The tile.
    pub key: TileKey,
    /// The level its heights came from.
    pub source_level: u8,
    /// Cut from its source node's mesh (else a regular grid of its posts).
    pub node_mesh: bool,
    /// How far its surface may lie from the data along each edge (NaN:
    /// its level's table, for a grid).
    pub errors: EdgeErrors,
    /// Its sub-level: tiles of one node share their edges only at the
    /// same one (the same error and morph target).
    pub sub_level: u8,
    /// Which of its edges on its node's boundary meet the neighbouring
    /// node's tile alike.
    pub seams: Seams,
}

impl DrawnTile {
    /// What a neighbour sees of `draw`.
    pub fn of(draw: &TileDraw) -> DrawnTile {
        DrawnTile {
            key: draw.key,
            source_level: draw.source_level,
            node_mesh: draw.node_mesh,
            errors: draw.errors,
            sub_level: draw.sub_level,
            seams: draw.seams,
        }
    }
}

/// One of a frame's depth slices ([`DepthSlices`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slice {
    /// `[near, split]`, or the whole range when it is not cut.
    Near,
    /// `[split, far]`, drawn first, when the range is cut.
    Far,
}

/// How tiles map to metres and how deep their skirts hang.
#[derive(Clone, Copy, Debug)]
pub struct TileGeometry<'a> {
    /// Cells per tile side.
    pub grid_size: u32,
    /// Cells per node side.
    pub node_size: u32,
    /// Level-0 post spacing, metres.
    pub spacing_m: [f64; 2],
    /// Largest geometric error per level, metres (of the node meshes where
    /// the source keeps them).
    pub delta_per_level: &'a [f64],
    /// Largest error per level of the regular grid of posts, metres: what
    /// a tile made as a grid errs by.
    pub grid_delta_per_level: &'a [f64],
    /// The errors the frame's tiles were extracted at, with the leaf
    /// tiles' sub-level rings (their morphs).
    pub mesh_errors: &'a MeshErrors,
}

impl DrawList {
    /// An empty draw list with room for `tiles` tiles.
    pub fn with_capacity(tiles: usize) -> Self {
        DrawList {
            uniforms: None,
            tiles: Vec::with_capacity(tiles),
            grid_size: 0,
            drawn: Vec::with_capacity(tiles),
            clustered: false,
            clusters: Vec::with_capacity(tiles),
            members: Vec::with_capacity(tiles),
            #[cfg(feature = "test-support")]
            cluster_morph: ClusterMorph::PerMember,
            places: PlaceCache::default(),
        }
    }

    /// Draws the list's tiles as clusters: `make` (the cluster cache)
    /// reads the list's tiles and writes the clusters' draws into the
    /// list's own vectors. The list is drawn as clusters from then until
    /// the next [`DrawList::build`], unless `make` fails.
    pub fn cluster<E>(
        &mut self,
        make: impl FnOnce(&DrawList, ClusterDraws<'_>) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut clusters = std::mem::take(&mut self.clusters);
        let mut members = std::mem::take(&mut self.members);
        let made = make(self, ClusterDraws { clusters: &mut clusters, members: &mut members });
        (self.clusters, self.members) = (clusters, members);
        self.clustered = made.is_ok();
        made
    }

    /// The same list drawn one draw per tile: its clusters left out.
    pub fn per_tile(&self) -> DrawList {
        DrawList { clustered: false, clusters: Vec::new(), members: Vec::new(), ..self.clone() }
    }

    /// Triangles of the list's tiles, skirts included, each tile once.
    pub fn triangles(&self) -> u64 {
        self.tiles.iter().map(TileUniforms::triangles).sum()
    }

    /// The tiles drawn in depth slice `slice` with or without posts of no data, in
    /// draw order. The GL terrain pass and the cost model both walk this.
    pub fn tiles_with(
        &self,
        slice: Slice,
        no_data: bool,
    ) -> impl Iterator<Item = &TileUniforms> + '_ {
        self.tiles_in(slice).filter(move |tile| tile.no_data == no_data)
    }

    /// The tiles drawn in depth slice `slice`, in list order (every tile in
    /// the near slice when the range is not cut, none in the far one).
    pub fn tiles_in(&self, slice: Slice) -> impl Iterator<Item = &TileUniforms> + '_ {
        let frame = self.uniforms;
        let cells = self.grid_size as f32;
        self.tiles.iter().filter(move |tile| {
            let Some(frame) = frame else { return false };
            let (near, far) = frame.slices.tile_slices(tile, &frame, cells);
            match slice {
                Slice::Near => near,
                Slice::Far => far,
            }
        })
    }

    /// Rebuilds the list for `frame` (its camera) from the tile cache's draws.
    pub fn build(
        &mut self,
        frame: FrameUniforms,
        draws: &[TileDraw],
        rings: &LevelRings,
        geometry: TileGeometry<'_>,
    ) {
        self.uniforms = Some(frame);
        self.grid_size = geometry.grid_size;
        self.tiles.clear();
        self.drawn.clear();
        self.clustered = false;
        self.clusters.clear();
        self.members.clear();
        self.drawn.extend(draws.iter().map(DrawnTile::of));
        self.drawn.sort_unstable_by_key(|d| d.key);
        self.places.next_frame(frame.earth.and_then(|e| e.projected_lattice()));
        for draw in draws {
            let tile = tile_uniforms(draw, &frame, rings, &geometry, &self.drawn, &mut self.places);
            self.tiles.push(tile);
        }
        self.sort_front_to_back(geometry.grid_size);
    }

    /// Orders the tiles (of `grid_size` cells) nearest first: terrain hidden
    /// behind a near ridge then fails the depth test before it is shaded
    /// (early z) instead of being shaded and overdrawn. On llvmpipe this
    /// took the default flight from about 125 to 70 ms a frame. In place, so
    /// no allocation.
    pub fn sort_front_to_back(&mut self, grid_size: u32) {
        let Some(frame) = self.uniforms else { return };
        let distance = |tile: &TileUniforms| {
            let (lo, hi) = tile.ground_rectangle(&frame, grid_size as f32);
            let [x, y] = [0, 1].map(|k| (lo[k] + hi[k]) / 2.0);
            x * x + y * y
        };
        self.tiles.sort_unstable_by(|a, b| distance(a).total_cmp(&distance(b)));
    }
}

/// The level-0 post at the centre of the node holding tile `key` (tiles
/// of `grid_size` cells in nodes of `node_size`): where every tile of the
/// node is placed from on the ellipsoid, so the posts they share get the
/// same bits from each.
pub fn node_centre(key: TileKey, grid_size: u32, node_size: u32) -> [i64; 2] {
    let node_tiles = (node_size / grid_size.max(1)).max(1) as i64;
    let span = node_tiles * grid_size as i64;
    let step = 1i64 << key.level;
    [key.x, key.y].map(|t| (t as i64 / node_tiles * span + span / 2) * step)
}

/// `draw`'s uniforms; `drawn` (the frame's tiles, sorted by key) decides
/// which edges hang a skirt and how deep.
fn tile_uniforms(
    draw: &TileDraw,
    frame: &FrameUniforms,
    rings: &LevelRings,
    geometry: &TileGeometry<'_>,
    drawn: &[DrawnTile],
    places: &mut PlaceCache,
) -> TileUniforms {
    let key = draw.key;
    let step = 1i64 << key.level;
    let span = geometry.grid_size as i64 * step;
    let first_post = frame.posts.number([key.x as i64 * span, key.y as i64 * span]);
    // Every vertex follows its own band's morph: the level's (band 0) or
    // its sub-level's, whatever the tile's sub-level (`tiles::by_distance`).
    let (start, end) = rings.morph(key.level);
    let morph = if start.is_finite() { [start as f32, end as f32] } else { [f32::MAX, f32::MAX] };
    let sub_morph_end = match draw.sub_level {
        0 => 0.0,
        _ => geometry.mesh_errors.sub_level_morph(key.level, 1).1 as f32,
    };
    let ranges = |level: u8, sub_level: u8| match sub_level {
        0 => rings.morph(level),
        k => geometry.mesh_errors.sub_level_morph(level, k),
    };
    let reach = MorphReach { frame, ranges: &ranges, grid_size: geometry.grid_size };
    let depths = skirt_depths(draw, drawn, geometry, &reach);
    let (skirt_depth, skirt_shares) = skirt_shares(depths);
    let hangs = (0..4).filter(|&e| skirt_shares[e] > 0).fold(0, |bits, e| bits | 1 << e);
    let skirt_slope = skirt_slope(draw, drawn, hangs, geometry);
    let mut tile = TileUniforms {
        key,
        first_post,
        post_step: step as f32,
        vertex_step: draw.vertex_step,
        morph,
        sub_morph_end,
        skirt_depth,
        skirt_edges: (0..4).filter(|&e| skirt_shares[e] > 0).fold(0, |bits, e| bits | 1 << e),
        skirt_shares,
        skirt_slope,
        byte_offset: draw.byte_offset,
        index_byte_offset: draw.index_byte_offset,
        index_count: draw.index_count,
        no_data: draw.coverage != TileCoverage::Full,
        place: frame.earth.map_or(NodePlace::default(), |earth| {
            earth.place_with(node_centre(key, geometry.grid_size, geometry.node_size), places)
        }),
        ground: None,
    };
    if frame.earth.is_some() {
        let (lo, hi) = tile.ground_rectangle(frame, geometry.grid_size as f32);
        tile.ground = Some([lo, hi]);
    }
    tile
}

/// The deepest of `depths` (metres per edge, 0 for none) and each edge's
/// share of it in [`SKIRT_SHARES`]ths, rounded up so no skirt hangs short.
fn skirt_shares(depths: [f64; 4]) -> (f32, [u8; 4]) {
    let deepest = depths.iter().copied().fold(0.0f64, f64::max) as f32;
    let shares = depths.map(|d| {
        if d > 0.0 && deepest > 0.0 {
            ((d as f32 / deepest * SKIRT_SHARES as f32).ceil() as u8).clamp(1, SKIRT_SHARES)
        } else {
            0
        }
    });
    (deepest, shares)
}

/// What a skirt vertex hangs no deeper than beyond its tile's skirt slope
/// times its distance, metres: rounding ([`SKIRT_MARGIN_M`]) and the least
/// sag a mesh allows (5 cm a side) ([`skirt_slope`]). `terrain.vert` has it.
pub const SKIRT_BASE_M: f64 = 0.5;

/// The 8-bit code of a skirt slope above the shares' 16 bits: 0 for none,
/// else `128 + 8 log2(slope)` rounded up (the slope sent is never less).
fn slope_code(slope: f32) -> u32 {
    if !(slope.is_finite() && slope > 0.0) {
        return 0;
    }
    (128.0 + 8.0 * (slope as f64).log2()).ceil().clamp(1.0, 255.0) as u32
}

/// The slope of [`slope_code`] `code` (infinite for 0).
fn slope_of_code(code: u32) -> f32 {
    match code & 0xff {
        0 => f32::INFINITY,
        c => ((c as f64 - 128.0) / 8.0).exp2() as f32,
    }
}

/// How steeply a tile's skirts may deepen with the distance (metres a
/// metre, on top of [`SKIRT_BASE_M`]), or infinite where they hang their
/// edge's depth all along. A tile extracted from its own level's map
/// errs at a point `D` metres away by at most `tau D / K` (its errors grow
/// with the distance, `tiles::by_distance`, and morphing keeps that), so a
/// crack between two such tiles is at most twice that: an edge's depth,
/// set by its far end, need not hang at its near end, where it would stand
/// as a wall seen from past the data's edge (issue 25). Level-0 tiles only
/// (their cells sag within the base), and only where every tile across a
/// skirted edge is such a tile too.
pub fn skirt_slope(
    draw: &TileDraw,
    drawn: &[DrawnTile],
    hangs: u8,
    geometry: &TileGeometry<'_>,
) -> f32 {
    let bounded = |tile: &DrawnTile| {
        let exact = tile.key.level == 0 && tile.source_level == 0 && tile.node_mesh;
        exact && tile.errors.morphed_m.iter().all(|e| e.is_finite())
    };
    let per_m = geometry.mesh_errors.per_m();
    if !(bounded(&DrawnTile::of(draw)) && per_m.is_finite() && per_m > 0.0) {
        return f32::INFINITY;
    }
    // An edge with nothing drawn across (culled, or hidden by the horizon)
    // hangs for a neighbour of the same kind: its crack is as bounded.
    for edge in (0..4).filter(|e| hangs & (1 << e) != 0) {
        let mut all = true;
        for_each_across(draw.key, edge, drawn, |other| all &= bounded(other));
        if !all {
            return f32::INFINITY;
        }
    }
    // Each side errs by `tau D / K` at most, and its straight edges sag
    // below the curved earth by a quarter of its least error at most
    // (`tiles::extract::sag_extent`).
    (2.5 * per_m) as f32
}

/// A skirt's depth is sent as a share of its tile's deepest, in this many
/// steps (four bits per edge).
pub const SKIRT_SHARES: u8 = 15;

/// Every edge hangs a skirt.
pub const ALL_EDGES: u8 = 0b1111;

/// The edges of `draw` that need a skirt, given the frame's tiles `drawn`
/// (sorted by key, with their source levels). Skirts hide the cracks where
/// two surfaces meet that do not share their edge posts: a neighbour of
/// another level, or one whose heights came from another level's node (best
/// available). A neighbour of the same level with heights from the same
/// level shares every edge post bit for bit, and morphs them alike, so that
/// edge is watertight without one. Leaving those skirts out is what keeps
/// them from showing where nothing hides them: beneath the last strip of
/// data, seen from beyond the data's edge. Edges whose neighbour is not in
/// the frame (culled, past the data, or split finer) keep their skirt.
///
/// Tiles cut from node meshes share their edge vertices with tiles cut
/// from the same node's mesh (`node_tiles` tiles of a level a node side),
/// made with the same ring generations; across nodes, where their maps code
/// the edge alike ([`Seams::meets`]); elsewhere each mesh chose its own
/// edge vertices.
pub fn skirt_edges(draw: &TileDraw, drawn: &[DrawnTile], node_tiles: u32) -> u8 {
    let TileKey { level, x, y } = draw.key;
    let neighbours = [
        y.checked_sub(1).map(|y| (x, y)),
        x.checked_add(1).map(|x| (x, y)),
        y.checked_add(1).map(|y| (x, y)),
        x.checked_sub(1).map(|x| (x, y)),
    ];
    let mut edges = 0;
    for (bit, neighbour) in neighbours.into_iter().enumerate() {
        let watertight = neighbour.is_some_and(|(x, y)| {
            let key = TileKey::new(level, x, y);
            let Ok(at) = drawn.binary_search_by_key(&key, |d| d.key) else { return false };
            let other = drawn[at];
            // Node meshes share their edge vertices only inside one node
            // mesh at one error (sub-level), and with no regular grid.
            other.source_level == draw.source_level
                && other.node_mesh == draw.node_mesh
                && (other.sub_level == draw.sub_level || draw.seams.banded)
                && draw.seams.alike(&other.seams)
                && (!draw.node_mesh
                    || same_node(draw, key, node_tiles)
                    || draw.seams.meets(&other.seams, bit))
        });
        if !watertight {
            edges |= 1 << bit;
        }
    }
    edges
}

/// Whether tile `key` (of `draw`'s level) lies in the same node of
/// `draw`'s source level as `draw`.
fn same_node(draw: &TileDraw, key: TileKey, node_tiles: u32) -> bool {
    let shift = draw.source_level.saturating_sub(key.level).min(31);
    let per_node = node_tiles << shift;
    draw.key.x / per_node == key.x / per_node && draw.key.y / per_node == key.y / per_node
}

/// How far a drawn tile's surface may lie from the data, metres, fully
/// morphed: its own extraction's error where known (it includes the mesh it
/// morphs toward), else its levels' tables.
pub fn drawn_error_m(tile: &DrawnTile, geometry: &TileGeometry<'_>) -> f64 {
    surface_error_m(tile, 1.0, geometry, None)
}

/// The delta of `level` for a tile made as it was: from `meshes` for a
/// tile cut from a node mesh, from `grids` for one made as a grid of posts
/// (levels past the tables take the coarsest; an empty table gives 0).
pub fn made_delta(meshes: &[f64], grids: &[f64], node_mesh: bool, level: u8) -> f64 {
    let table = if node_mesh { meshes } else { grids };
    table.get(level as usize).or(table.last()).copied().unwrap_or(0.0)
}

/// How deep each edge of `draw` hangs its skirt this frame, metres (south,
/// east, north, west; 0 for none). A skirt fills the crack between the
/// tile's edge and the surface drawn across it (a neighbour of its level,
/// the level above or the two of the level below along the edge), and a
/// crack is at most the two sides' errors there. A small memory budget
/// draws neighbours from sources levels apart and from grids of posts,
/// which err by the grid's deltas ([`made_delta`]): a depth from the tile's
/// own source alone, or from the meshes' errors alone, left pinholes at
/// 16 MB. Each side's error here is each side's own source's delta, plus the way
/// its morph has gone toward its parent level's surface at the far end of
/// the edge ([`MorphReach`]), plus the sag of its straight edges below the
/// curved earth, plus rounding ([`SKIRT_MARGIN_M`]). Two exact level-0
/// tiles near the camera (unmorphed) can open no crack wider than rounding:
/// they hung 97 m at tau 4 when every tile was taken as fully morphed, and
/// near a data edge those skirts stood as walls under the cut face seen
/// from beyond it (issue 25). An edge [`skirt_edges`] finds watertight
/// hangs none; one with no tile found across it hangs as if the level above
/// were there, fully morphed (hanging none there left single pixels of sky
/// in the default flight: `tests/render_horizon.rs`). Where the data end the
/// skirt is dropped with the posts across it (`tiles::vertex`).
pub fn skirt_depths(
    draw: &TileDraw,
    drawn: &[DrawnTile],
    geometry: &TileGeometry<'_>,
    reach: &MorphReach<'_>,
) -> [f64; 4] {
    let node_tiles = (geometry.node_size / geometry.grid_size).max(1);
    let hangs = skirt_edges(draw, drawn, node_tiles);
    let own = DrawnTile::of(draw);
    std::array::from_fn(|edge| {
        if hangs & (1 << edge) == 0 {
            return 0.0;
        }
        // Each side's error along the edge: the tiles across face it with
        // their opposite edge.
        let crack_side = |tile: &DrawnTile, side: usize| {
            let morph = reach.along(draw.key, edge, tile.key.level, tile.sub_level);
            surface_error_m(tile, morph, geometry, Some(side)) + sag_m(tile, geometry)
        };
        let mut across: Option<f64> = None;
        for_each_across(draw.key, edge, drawn, |other| {
            let side = crack_side(other, (edge + 2) % 4);
            across = Some(across.map_or(side, |a| a.max(side)));
        });
        // Nothing found across (culled, past the data, or drawn at a level
        // the rings do not pair with this one): the coarser level's full
        // error, as if its tile were there.
        let unseen = || {
            let coarser = DrawnTile { key: draw.key.parent(), ..own };
            let morphed = surface_error_m(&coarser, 1.0, geometry, Some(edge));
            crack_side(&coarser, edge).max(morphed)
        };
        crack_side(&own, edge) + across.unwrap_or_else(unseen) + SKIRT_MARGIN_M
    })
}

/// Rounding a skirt covers beyond the two sides' errors, metres: f32
/// positions and heights, and the rasteriser at a vertex of one side that
/// the other side's straight edge passes (a T-junction).
pub const SKIRT_MARGIN_M: f64 = 0.1;

/// How far `tile`'s surface may lie from the data where its morph factor
/// is at most `morph`, along `edge` (south, east, north, west; `None`:
/// anywhere): its source's delta, moved toward the delta of the level above
/// its own (whose surface it morphs to) by that factor. A tile extracted
/// from an error map knows its errors unmorphed and fully morphed, edge by
/// edge (they grow with the distance).
pub fn surface_error_m(
    tile: &DrawnTile,
    morph: f64,
    geometry: &TileGeometry<'_>,
    edge: Option<usize>,
) -> f64 {
    let (meshes, grids) = (geometry.delta_per_level, geometry.grid_delta_per_level);
    let at = |level: u8| made_delta(meshes, grids, tile.node_mesh, level);
    let errors = &tile.errors;
    let pick = |per_edge: &[f32; 4]| match edge {
        Some(edge) => per_edge[edge & 3] as f64,
        None => per_edge.iter().copied().fold(f32::NAN, f32::max) as f64,
    };
    let (own, toward) = if errors.morphed_m.iter().all(|e| e.is_finite()) {
        (pick(&errors.own_m), pick(&errors.morphed_m))
    } else {
        (at(tile.source_level), at(tile.key.level.saturating_add(1)))
    };
    own + morph.clamp(0.0, 1.0) * (toward - own).max(0.0)
}

/// How far `tile`'s straight edges may sag below the curved earth between
/// two of its vertices, metres (the shader drops each vertex by `d^2 / 2R`
/// and draws straight between them; a right triangle of legs `a` sags up
/// to `a^2 / 4R`): a node mesh's triangles are capped at a quarter of its
/// error or 5 cm (`meshes::build::sag_extent`) but never span less than a
/// cell of its reference lattice (up to 5 levels finer than its source: a
/// leaf node of a coarse base is exact on its own 9 km posts, 3.4 m); a
/// grid's cell spans `2^level` posts.
fn sag_m(tile: &DrawnTile, geometry: &TileGeometry<'_>) -> f64 {
    let spacing = geometry.spacing_m[0].max(geometry.spacing_m[1]);
    let cell_sag = |level: u8| {
        let cell = spacing * (1u64 << level.min(40)) as f64;
        cell * cell / (4.0 * crate::camera::EARTH_RADIUS_M)
    };
    if tile.node_mesh {
        let delta = made_delta(geometry.delta_per_level, &[], true, tile.source_level);
        (delta / 4.0).max(0.05).max(cell_sag(tile.source_level.saturating_sub(5)))
    } else {
        cell_sag(tile.source_level)
    }
}

/// Where the frame's morph has taken tiles along an edge: the shader's
/// morph factor grows with a vertex's distance from the camera, so along an
/// edge it is at most its value at the edge's far end, with the data's
/// largest height difference to the camera.
pub struct MorphReach<'a> {
    /// The frame: the camera's post numbering and the heights' reach.
    pub frame: &'a FrameUniforms,
    /// Each level's and sub-level's morph start and end distance, metres
    /// (infinite for none): [`LevelRings::morph`], `sub_level_morph`.
    pub ranges: &'a dyn Fn(u8, u8) -> (f64, f64),
    /// Cells per tile side.
    pub grid_size: u32,
}

impl MorphReach<'_> {
    /// The largest morph factor a tile of `level` and `sub_level` reaches
    /// along edge `edge` of tile `key`: 0 where the edge ends nearer than
    /// its morph start, 1 past its end.
    pub fn along(&self, key: TileKey, edge: usize, level: u8, sub_level: u8) -> f64 {
        let (start, end) = (self.ranges)(level, sub_level);
        if !start.is_finite() {
            return 0.0;
        }
        let posts = &self.frame.posts;
        let g = self.grid_size as i64;
        let step = 1i64 << key.level;
        let corner = |i: i64, j: i64| {
            let post = [(key.x as i64 * g + i) * step, (key.y as i64 * g + j) * step];
            let [x, y] = posts.number(post);
            let at = |k: usize, n: f32| (n * posts.spacing[k] - posts.offset[k]) as f64;
            at(0, x).hypot(at(1, y))
        };
        let ends = [[(0, 0), (g, 0)], [(g, 0), (g, g)], [(g, g), (0, g)], [(0, g), (0, 0)]][edge];
        let far = ends.iter().map(|&(i, j)| corner(i, j)).fold(0.0, f64::max);
        let distance = far.hypot(self.frame.slices.max_drop_m as f64);
        ((distance - start) / (end - start)).clamp(0.0, 1.0)
    }
}

/// Calls `f` with each tile of `drawn` (sorted by key) along `key`'s edges:
/// of its level, the level above, or the level below (the neighbours a
/// tile can have).
pub fn for_each_neighbour(key: TileKey, drawn: &[DrawnTile], mut f: impl FnMut(&DrawnTile)) {
    for edge in 0..4 {
        for_each_across(key, edge, drawn, &mut f);
    }
}

/// Calls `f` with each tile of `drawn` (sorted by key) across edge `edge`
/// of `key` (0 south, 1 east, 2 north, 3 west): of its level, the level
/// above, or the two of the level below along the edge.
pub fn for_each_across(
    key: TileKey,
    edge: usize,
    drawn: &[DrawnTile],
    mut f: impl FnMut(&DrawnTile),
) {
    let (dx, dy) = OUTWARD[edge];
    let (x, y) = (key.x as i64, key.y as i64);
    let mut look = |level: i64, x: i64, y: i64| {
        // Keys off the lattice (below 0, past u32) name no tile.
        let (Ok(level), Ok(x), Ok(y)) = (u8::try_from(level), u32::try_from(x), u32::try_from(y))
        else {
            return;
        };
        let key = TileKey::new(level, x, y);
        if let Ok(at) = drawn.binary_search_by_key(&key, |d| d.key) {
            f(&drawn[at]);
        }
    };
    let level = key.level as i64;
    let (nx, ny) = (x + dx, y + dy);
    look(level, nx, ny);
    look(level + 1, nx.div_euclid(2), ny.div_euclid(2));
    // The two finer tiles along the shared edge.
    let (cx, cy) = (2 * nx + (dx < 0) as i64, 2 * ny + (dy < 0) as i64);
    let (ax, ay) = if dx == 0 { (1, 0) } else { (0, 1) };
    look(level - 1, cx, cy);
    look(level - 1, cx + ax, cy + ay);
}

/// The step to the tile across each edge, in skirt-bit order (south, east,
/// north, west).
const OUTWARD: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(x: u32, first_post: [f32; 2]) -> TileUniforms {
        let key = TileKey::new(0, x, 0);
        TileUniforms {
            key,
            first_post,
            post_step: 1.0,
            vertex_step: 1.0,
            morph: [0.0, 1.0],
            sub_morph_end: 0.0,
            skirt_depth: 1.0,
            skirt_edges: ALL_EDGES,
            skirt_shares: [15; 4],
            skirt_slope: f32::INFINITY,
            byte_offset: 0,
            index_byte_offset: 0,
            index_count: 0,
            no_data: false,
            place: NodePlace::default(),
            ground: None,
        }
    }

    fn frame(posts: PostFrame) -> FrameUniforms {
        FrameUniforms {
            view_projection: Mat4::IDENTITY,
            camera_altitude: 0.0,
            sun_direction: Vec3::Z,
            curvature: false,
            horizon_floor_m: 0.0,
            morph_start_share: 0.7,
            warning_above_m: 0.0,
            caution_below_m: 0.0,
            viewport: [1, 1],
            fog_distance_m: 1.0,
            posts,
            last_post: [i64::MAX / 2; 2],
            slices: DepthSlices {
                near: Mat4::IDENTITY,
                far: None,
                split_m: 1.0,
                min_depth_share: 1.0,
                max_drop_m: 0.0,
            },
            earth: None,
        }
    }

    #[test]
    fn low_views_cut_the_depth_range_and_tiles_go_where_they_reach() {
        use glam::DVec3;
        let camera = Camera {
            position: DVec3::new(0.0, 0.0, 1020.0),
            heading_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [1280, 720],
        };
        // Terrain from 0 to 20 m: the camera is 1000 m or more above it.
        let heights = (0.0, 20.0);
        assert!(
            DepthSlices::new(&camera, 2000.0, 150_000.0, heights).far.is_none(),
            "a 2 km near plane resolves 150 km alone"
        );
        let slices = DepthSlices::new(&camera, 1.0, 150_000.0, heights);
        assert!(slices.far.is_some());
        assert!((slices.split_m - 387.3).abs() < 0.1, "split {}", slices.split_m);
        let posts = PostFrame { anchor: [0, 0], spacing: [10.0, 10.0], offset: [5.0, 5.0] };
        // 4-cell tiles (40 m): under the camera, 2 km ahead, 100 km ahead.
        let under = TileUniforms { first_post: [-2.0, -2.0], ..tile(0, [0.0, 0.0]) };
        let ahead = TileUniforms { first_post: [0.0, 200.0], ..tile(1, [0.0, 0.0]) };
        let far = TileUniforms { first_post: [0.0, 10_000.0], ..tile(2, [0.0, 0.0]) };
        let posts = FrameUniforms { slices, ..frame(posts) };
        assert_eq!(
            slices.tile_slices(&under, &posts, 4.0),
            (true, true),
            "1 km above it, it may reach past the split"
        );
        assert_eq!(slices.tile_slices(&ahead, &posts, 4.0), (false, true));
        assert_eq!(slices.tile_slices(&far, &posts, 4.0), (false, true));
    }

    #[test]
    fn tiles_are_drawn_nearest_first() {
        // Posts 10 m apart, the camera 5 m east of the anchor; tiles of 4
        // cells with centres 1015, -25 (the camera's tile), 215 and 5015 m east.
        let posts = PostFrame { anchor: [0, 0], spacing: [10.0, 10.0], offset: [5.0, 0.0] };
        let tiles = vec![
            tile(0, [100.0, -2.0]),
            tile(1, [-4.0, -2.0]),
            tile(2, [20.0, -2.0]),
            tile(3, [500.0, -2.0]),
        ];
        let mut list = DrawList { uniforms: Some(frame(posts)), tiles, ..DrawList::default() };
        list.sort_front_to_back(4);
        let order: Vec<u32> = list.tiles.iter().map(|t| t.key.x).collect();
        assert_eq!(order, [1, 2, 0, 3]);
    }

    #[test]
    fn a_post_numbered_from_the_anchor_lands_where_f64_puts_it() {
        let spacing = [71.38, 92.62];
        let eye = DVec2::new(1.0e7 + 12.3, -3.0e6 - 45.6);
        let posts = PostFrame::new(eye, spacing);
        assert!(posts.offset.iter().zip(spacing).all(|(o, s)| (0.0..s as f32).contains(o)));
        let post = [posts.anchor[0] + 700, posts.anchor[1] - 300];
        let tile = TileUniforms { first_post: posts.number(post), ..tile(0, [0.0, 0.0]) };
        let [x, y] = tile.post_position(&posts, 0.0, 0.0);
        let exact = [post[0] as f64 * spacing[0] - eye.x, post[1] as f64 * spacing[1] - eye.y];
        assert!(
            (x as f64 - exact[0]).abs() < 0.01 && (y as f64 - exact[1]).abs() < 0.01,
            "{x} {y} vs {exact:?}"
        );
    }

    fn drawn(level: u8, x: u32, y: u32, source_level: u8) -> DrawnTile {
        DrawnTile {
            key: TileKey::new(level, x, y),
            source_level,
            node_mesh: true,
            errors: EdgeErrors::UNKNOWN,
            sub_level: 0,
            seams: Seams::default(),
        }
    }

    /// Each edge's skirt reaches as deep as the errors of the tile and of
    /// the tiles across that edge (its level, the level above, the two of
    /// the level below along it) with their morph this frame: unmorphed
    /// exact tiles hang only the margin, a tile made as a grid errs by the
    /// grid's deltas, an edge with nothing drawn across it hangs as if the
    /// level above were there.
    #[test]
    fn skirts_reach_below_what_each_edge_faces_this_frame() {
        let draw = TileDraw {
            key: TileKey::new(2, 4, 4),
            byte_offset: 0,
            index_byte_offset: 0,
            index_count: 0,
            vertex_step: 4.0,
            node_mesh: true,
            source_level: 2,
            coverage: crate::tiles::TileCoverage::Full,
            sub_level: 0,
            errors: EdgeErrors::UNKNOWN,
            seams: Seams::default(),
        };
        let deltas = [0.0, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
        let grid_deltas = deltas.map(|d| 10.0 * d);
        let geometry = TileGeometry {
            grid_size: 32,
            node_size: 64,
            spacing_m: [90.0, 90.0],
            delta_per_level: &deltas,
            grid_delta_per_level: &grid_deltas,
            mesh_errors: &MeshErrors::default(),
        };
        // Morph ranges so far out that nothing morphs, then so near that
        // everything has.
        let posts = PostFrame { anchor: [0, 0], spacing: [90.0, 90.0], offset: [0.0, 0.0] };
        let frame = FrameUniforms { posts, ..frame(posts) };
        // South: the same level, another source; east: two finer tiles;
        // north: nothing; west: the level above.
        let mut tiles =
            vec![drawn(2, 4, 3, 3), drawn(1, 10, 8, 1), drawn(1, 10, 9, 1), drawn(3, 1, 2, 3)];
        tiles.sort_unstable_by_key(|d| d.key);
        let depths = |start: f64, tiles: &[DrawnTile]| {
            let ranges = move |_: u8, _: u8| (start, 2.0 * start);
            let reach = MorphReach { frame: &frame, ranges: &ranges, grid_size: 32 };
            skirt_depths(&draw, tiles, &geometry, &reach)
        };
        let close = |a: [f64; 4], b: [f64; 4]| a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-9);
        // Each side: its delta (morphed: toward the level above's), plus a
        // quarter of its mesh's delta (at least 5 cm) of sag. The tile:
        // 2 + 0.5; source level 3: 4 + 1; level 1: 1 + 0.25.
        let unmorphed = depths(1e9, &tiles);
        assert!(close(unmorphed, [7.6, 3.85, 10.6, 7.6]), "{unmorphed:?}");
        // North, nothing drawn: as if the level above were, fully morphed
        // (8). Fully morphed: the tile 4 + 0.5, the level-3 tile 8 + 1,
        // level 1 2 + 0.25.
        let morphed = depths(1.0, &tiles);
        assert!(close(morphed, [9.6, 6.85, 13.1, 13.6]), "{morphed:?}");
        // A grid neighbour of source level 3 errs by the grid's 40 m.
        let grid = [DrawnTile { node_mesh: false, ..drawn(2, 4, 3, 3) }];
        let cell = 8.0 * 90.0;
        let sag = cell * cell / (4.0 * crate::camera::EARTH_RADIUS_M);
        assert!((depths(1e9, &grid)[0] - (2.5 + 40.0 + sag + SKIRT_MARGIN_M)).abs() < 1e-9);
        // Shares round up, so no edge hangs short of its depth.
        let (deepest, shares) = skirt_shares([3.0, 0.0, 1.0, 2.9]);
        assert_eq!((deepest, shares), (3.0, [15, 0, 5, 15]));
        let tile = TileUniforms { skirt_depth: deepest, skirt_shares: shares, ..tile(0, [0.0; 2]) };
        assert_eq!(TileUniforms::unpack_skirt_shares(tile.packed_skirt_shares()), shares);
        assert!(tile.edge_skirt_m(2) >= 1.0 && tile.edge_skirt_m(3) >= 2.9);
    }

    #[test]
    fn tiles_of_two_nodes_meet_without_a_skirt_where_their_seams_do() {
        // Two tiles a node side: (0, 3, 5)'s east edge is its node's.
        let seams = |shared| Seams { shared, views: 7, ancestors: 0b10, banded: false };
        let draw = TileDraw {
            key: TileKey::new(0, 3, 5),
            byte_offset: 0,
            index_byte_offset: 0,
            index_count: 0,
            vertex_step: 1.0,
            node_mesh: true,
            source_level: 0,
            coverage: crate::tiles::TileCoverage::Full,
            sub_level: 0,
            errors: EdgeErrors::UNKNOWN,
            seams: seams(0b0010),
        };
        let across = |seams| vec![DrawnTile { seams, ..drawn(0, 4, 5, 0) }];
        let east = 0b0010;
        assert_eq!(skirt_edges(&draw, &across(seams(0b1000)), 2) & east, 0);
        // The neighbour's west edge not shared, another generation, other
        // ancestors: the skirt hangs.
        assert_ne!(skirt_edges(&draw, &across(seams(0b0010)), 2) & east, 0);
        let later = Seams { views: 8, ..seams(0b1000) };
        assert_ne!(skirt_edges(&draw, &across(later), 2) & east, 0);
        let fewer = Seams { ancestors: 0, ..seams(0b1000) };
        assert_ne!(skirt_edges(&draw, &across(fewer), 2) & east, 0);
        // Inside one node the generations must agree as well.
        let west = [DrawnTile { seams: later, ..drawn(0, 2, 5, 0) }];
        assert_ne!(skirt_edges(&draw, &west, 2) & 0b1000, 0);
    }
}
