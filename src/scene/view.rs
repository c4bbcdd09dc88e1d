//! The view of one frame: everything the frame's stages measure from the
//! camera (clip planes, frustum, horizons, Ulrich's K, the rings' inputs),
//! made once per frame by [`View::new`] and only read after that. Paging,
//! selection, the tau policy, the frame's uniforms and the census all take
//! it, so none of them computes view geometry of its own.

use std::cell::Cell;

use crate::camera::{Camera, CameraError, Frustum, EARTH_RADIUS_M};
use crate::earth::{EarthFrame, EllipsoidHorizon};
use crate::lod::census::CensusView;
use crate::lod::horizon::Horizon;
use crate::lod::rings::RingInputs;
use crate::lod::select::{self, EarthView};
use crate::lod::LevelRings;
use crate::node::NodeLayout;
use crate::render::draw_list::{DepthSlices, PostFrame};
use crate::render::{palette, FrameUniforms};

use super::{horizon_floor_m, SceneConfig, TerrainData};

thread_local! {
    /// Clip planes computed on this thread: what [`clip_planes_computed`] reads.
    static CLIP_PLANES: Cell<u64> = const { Cell::new(0) };
}

/// How many times this thread computed [`clip_planes`]: the view geometry
/// every other part of a [`View`] (frustum, horizons) is made beside, in
/// [`View::new`] alone. `tests/scene_view.rs` counts one per frame, budget
/// retries, coarsening and clusters included.
pub fn clip_planes_computed() -> u64 {
    CLIP_PLANES.with(Cell::get)
}

/// What a frame's stages measure from its camera.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// The camera, valid ([`Camera::validate`]).
    pub camera: Camera,
    /// The widest near plane and the far plane, metres ([`clip_planes`]):
    /// culling uses them; drawing pushes the near plane out.
    pub near_m: f32,
    /// The far plane, metres.
    pub far_m: f32,
    /// The culling frustum, from `near_m` and `far_m`.
    pub frustum: Frustum,
    /// The chart's horizon tiles are culled below ([`View::new`]).
    pub horizon: Option<Horizon>,
    /// The ellipsoid's eye and horizon, when the display draws there.
    pub earth: Option<EarthView>,
    /// Ulrich's K for the camera's viewport and field of view.
    pub k: f64,
    /// A level-0 tile's side, metres (what the rings scale by).
    pub tile_size_m: f64,
    /// Highest minus lowest height of the data, metres.
    pub height_range_m: f64,
}

impl View {
    /// The view of `camera` over `terrain` for a scene configured by
    /// `config`; refused when the camera is not valid. Tiles are culled
    /// below the chart's horizon (over the data's lowest height) when the
    /// curvature is drawn, horizon culling is on, every post of the data has
    /// data and the camera is over the data's rectangle (see
    /// [`crate::lod::horizon`]); on the ellipsoid,
    /// under the same conditions, below its horizon.
    pub fn new(
        camera: &Camera,
        terrain: &dyn TerrainData,
        config: &SceneConfig,
    ) -> Result<View, CameraError> {
        camera.validate()?;
        let layout = terrain.layout();
        let (lo, hi) = terrain.height_range();
        let (near_m, far_m) = clip_planes(camera, terrain);
        let frustum =
            Frustum::from_view_projection(camera.projection(near_m, far_m) * camera.view());
        let culling = config.horizon_culling
            && config.curvature
            && terrain.gapless()
            && over_data(camera, layout);
        let horizon = culling.then(|| Horizon::new(camera.position.z, lo as f64)).flatten();
        let earth = config.earth.and_then(|placement| {
            let frame = EarthFrame::new(&placement, camera.position, [0, 0])?;
            let horizon = horizon.is_some().then(|| EllipsoidHorizon::new(frame.eye(), lo as f64));
            Some(EarthView { frame, horizon: horizon.flatten() })
        });
        Ok(View {
            camera: *camera,
            near_m,
            far_m,
            frustum,
            horizon,
            earth,
            k: camera.perspective_scale(),
            tile_size_m: config.lod.grid_size as f64 * layout.spacing_m[0].max(layout.spacing_m[1]),
            height_range_m: (hi - lo) as f64,
        })
    }

    /// What the rings depend on, with the per-level `deltas`.
    pub fn ring_inputs<'a>(&self, deltas: &'a [f64]) -> RingInputs<'a> {
        RingInputs {
            tile_size_m: self.tile_size_m,
            delta_per_level: deltas,
            height_range_m: self.height_range_m,
            perspective_scale: self.k,
        }
    }

    /// What the selector culls and measures with, for `rings`.
    pub fn selection<'a>(&'a self, rings: &'a LevelRings, curvature: bool) -> select::View<'a> {
        select::View {
            eye: self.camera.position,
            frustum: &self.frustum,
            rings,
            curvature,
            horizon: self.horizon,
            earth: self.earth,
        }
    }

    /// What the census counts with.
    pub fn census(&self, curvature: bool, grid_size: u32, root: u8) -> CensusView<'_> {
        CensusView {
            eye: self.camera.position,
            frustum: &self.frustum,
            curvature,
            horizon: self.horizon,
            grid_size,
            root,
        }
    }

    /// The uniforms every pass of the frame shares: projection, bands,
    /// sun, curvature. The near plane is `near_m` (at least the view's):
    /// [`super::Scene::frame`] puts it 80 % of the way to the nearest tile
    /// it selected, since a 24-bit depth buffer resolves `d^2 / (near
    /// 2^24)` metres at distance `d` (560 m at 68 km with a 0.5 m near
    /// plane: far ridges then fought over pixels; 1.5 m with the near plane
    /// at 180 m).
    pub fn uniforms(
        &self,
        config: &SceneConfig,
        terrain: &dyn TerrainData,
        near_m: f32,
    ) -> FrameUniforms {
        let (camera, far) = (&self.camera, self.far_m);
        let near = self.near_m.max(near_m.min(far / 10.0));
        let layout = terrain.layout();
        let posts = PostFrame::new(camera.position.truncate(), layout.spacing_m);
        FrameUniforms {
            view_projection: camera.projection(near, far) * camera.view(),
            camera_altitude: camera.position.z,
            sun_direction: palette::sun_direction(),
            curvature: config.curvature,
            horizon_floor_m: horizon_floor_m(config.earth.as_ref(), terrain.height_range().0),
            morph_start_share: 1.0 - config.lod.morph_range as f32,
            warning_above_m: config.warning_above_m,
            caution_below_m: config.caution_below_m,
            viewport: camera.viewport,
            fog_distance_m: far,
            posts,
            last_post: layout.posts.map(|p| p as i64 - 1),
            slices: DepthSlices::new(camera, near, far, terrain.height_range()),
            earth: config
                .earth
                .and_then(|placement| EarthFrame::new(&placement, camera.position, posts.anchor)),
        }
    }
}

/// Whether `camera` is over the rectangle of `layout`'s posts.
fn over_data(camera: &Camera, layout: &NodeLayout) -> bool {
    let inside = |at: f64, posts: u32, spacing: f64| {
        at >= 0.0 && at <= posts.saturating_sub(1) as f64 * spacing
    };
    let p = camera.position;
    inside(p.x, layout.posts[0], layout.spacing_m[0])
        && inside(p.y, layout.posts[1], layout.spacing_m[1])
}

/// Near and far planes: near shrinks as the aircraft nears the terrain (never
/// below half a metre), far reaches the farthest corner of the data or the
/// horizon, whichever is nearer.
pub fn clip_planes(camera: &Camera, terrain: &dyn TerrainData) -> (f32, f32) {
    CLIP_PLANES.with(|n| n.set(n.get() + 1));
    let layout = terrain.layout();
    let (lo, hi) = terrain.height_range();
    let above = (camera.position.z - hi as f64).max(camera.position.z - lo as f64).abs();
    let clearance = (camera.position.z - hi as f64).max(1.0);
    let near = (clearance * 0.25).clamp(0.5, 50.0);
    let extent = glam::DVec2::new(
        layout.posts[0] as f64 * layout.spacing_m[0],
        layout.posts[1] as f64 * layout.spacing_m[1],
    );
    let eye = camera.position.truncate();
    let corners = [
        glam::DVec2::ZERO,
        glam::DVec2::new(extent.x, 0.0),
        glam::DVec2::new(0.0, extent.y),
        extent,
    ];
    let data_far = corners.iter().map(|c| c.distance(eye)).fold(0.0, f64::max) + above;
    let horizon = (2.0 * EARTH_RADIUS_M * above.max(1.0)).sqrt() + 200_000.0;
    (near as f32, data_far.min(horizon).max(near * 10.0) as f32)
}
