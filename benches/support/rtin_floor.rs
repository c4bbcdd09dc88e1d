//! GL-free baselines for a tiled LOD's triangle count (issue 11), over one
//! square of level-0 posts around a flight (`2^k + 1` a side, as the RTIN
//! needs), for the views the LOD is measured at:
//!
//! - the RTIN floor: a view-dependent RTIN refinement of those posts at the
//!   LOD's tau ([`ridgeline::mesh::view_refine`]: split while the error
//!   exceeds `tau D / K`, `D` from the eye to the split's box), counting the
//!   triangles whose box meets the view frustum;
//! - full resolution in the frustum: two triangles per level-0 cell whose
//!   box meets the frustum, counted, not drawn.
//!
//! The frustum is the one the LOD culls its tiles with (the scene's
//! [`ridgeline::scene::clip_planes`]), and boxes reach down by the earth's
//! curvature drop at their far corner, as the selector's do. Box against
//! frustum is [`Frustum::intersects_box`]: conservative (a box straddling a
//! corner outside counts), the same test the LOD's tiles pass.

use std::ops::Range;

use glam::DVec3;
use ridgeline::camera::{curvature_drop, Camera, Frustum};
use ridgeline::gl::{TruthMesh, TruthRegion, CHUNK_CELLS};
use ridgeline::lod::TileKey;
use ridgeline::mesh::rtin::{SplitBounds, Triangle};
use ridgeline::mesh::{view_refine, HeightGrid, Rtin, RtinOptions, ViewParams};
use ridgeline::node::NodeSource;
use ridgeline::tiles::NO_DATA;

/// Rows of posts read from the source at once: a band of a 4097-post square
/// stays within what one truth mesh may hold.
const BAND_CELLS: u32 = 2048;

/// The square of level-0 posts and its RTIN error map (with split boxes).
pub struct FloorGrid {
    /// The data's level-0 post at the grid's post (0, 0).
    pub first: [i64; 2],
    /// Posts a side, `2^k + 1`.
    pub side: u32,
    /// Metres between posts east and north (the layout's level-0 spacing).
    pub spacing_m: [f64; 2],
    /// Posts without data (voids, or past the data), given the lowest height.
    pub filled: usize,
    heights: Vec<f32>,
    rtin: Rtin,
}

/// One view in the grid's frame.
pub struct FloorView {
    /// The eye, metres east and north of the grid's post (0, 0), and up.
    eye: DVec3,
    frustum: Frustum,
    curvature: bool,
    /// Ulrich's K, pixels.
    k: f64,
}

/// What one view costs at one tau.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct FloorCount {
    /// Triangles of the refinement whose box meets the frustum.
    pub in_frustum: u64,
    /// Every triangle of the refinement, all round.
    pub all_round: u64,
}

impl FloorGrid {
    /// Reads the `side^2` posts of `source`'s level 0 (best data where no
    /// level-0 node is stored, as the truth mesh does) centred on `region`'s
    /// centre, the first post rounded to a multiple of `align` (the coarse
    /// lattice the LOD's tiles and the base layer's nodes sit on), and builds
    /// the error map once. `side - 1` must be a power of two and a multiple
    /// of the truth mesh's chunk.
    pub fn load(source: &dyn NodeSource, region: TruthRegion, side: u32, align: i64) -> Self {
        let cells = side - 1;
        assert!(cells.is_power_of_two() && cells % CHUNK_CELLS == 0, "side {side}");
        let first = [0, 1].map(|a| {
            let centre = region.first[a] + region.posts[a] as i64 / 2;
            (centre - cells as i64 / 2 + align / 2).div_euclid(align) * align
        });
        let spacing_m = source.layout().spacing_m;
        let mut heights = vec![f32::NAN; side as usize * side as usize];
        let mut band = 0;
        while band < cells {
            let rows = BAND_CELLS.min(cells - band);
            let region =
                TruthRegion { first: [first[0], first[1] + band as i64], posts: [side, rows + 1] };
            let mesh = TruthMesh::load(source, region).expect("RTIN floor: level-0 posts");
            copy_posts(&mesh, band, side, &mut heights);
            band += rows;
        }
        let lowest = heights.iter().copied().filter(|h| !h.is_nan()).fold(f32::INFINITY, f32::min);
        let mut filled = 0;
        for h in &mut heights {
            if h.is_nan() {
                *h = lowest;
                filled += 1;
            }
        }
        let grid = HeightGrid::new(side, &heights).expect("RTIN floor grid");
        let rtin = Rtin::new(&grid, RtinOptions { bounds: true, ..RtinOptions::default() })
            .expect("RTIN error map");
        FloorGrid { first, side, spacing_m, filled, heights, rtin }
    }

    /// The height of grid post `(i, j)`.
    pub fn at(&self, i: u32, j: u32) -> f32 {
        self.heights[j as usize * self.side as usize + i as usize]
    }

    /// Where grid post `(i, j)` lies in the local frame, metres.
    pub fn post_m(&self, i: f64, j: f64) -> [f64; 2] {
        [
            (self.first[0] as f64 + i) * self.spacing_m[0],
            (self.first[1] as f64 + j) * self.spacing_m[1],
        ]
    }

    /// The grid's extent in the local frame, metres: south-west and north-east corners.
    pub fn extent_m(&self) -> ([f64; 2], [f64; 2]) {
        let last = (self.side - 1) as f64;
        (self.post_m(0.0, 0.0), self.post_m(last, last))
    }

    /// Triangles of the full-resolution grid, every cell.
    pub fn full_res_triangles(&self) -> u64 {
        2 * (self.side as u64 - 1).pow(2)
    }

    /// `camera` in the grid's frame, with the frustum of `near` and `far`.
    pub fn view(&self, camera: &Camera, (near, far): (f32, f32), curvature: bool) -> FloorView {
        let origin = self.post_m(0.0, 0.0);
        let p = camera.position;
        FloorView {
            eye: DVec3::new(p.x - origin[0], p.y - origin[1], p.z),
            frustum: Frustum::from_view_projection(camera.projection(near, far) * camera.view()),
            curvature,
            k: camera.perspective_scale(),
        }
    }

    /// The grid post nearest `camera`'s ground position, if inside the grid.
    pub fn post_under(&self, camera: &Camera) -> Option<[u32; 2]> {
        let origin = self.post_m(0.0, 0.0);
        let p = camera.position;
        let i = ((p.x - origin[0]) / self.spacing_m[0]).round();
        let j = ((p.y - origin[1]) / self.spacing_m[1]).round();
        let last = (self.side - 1) as f64;
        ((0.0..=last).contains(&i) && (0.0..=last).contains(&j)).then_some([i as u32, j as u32])
    }

    /// Full-resolution triangles in the frustum: two per cell whose box
    /// (its four posts' heights) meets it.
    pub fn full_res_in_frustum(&self, view: &FloorView) -> u64 {
        let side = self.side as usize;
        let mut cells = 0u64;
        for j in 0..side - 1 {
            let (south, north) =
                (&self.heights[j * side..][..side], &self.heights[(j + 1) * side..][..side]);
            for i in 0..side - 1 {
                let corners = [south[i], south[i + 1], north[i], north[i + 1]];
                let lo = corners.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = corners.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                let (i, j) = (i as u32, j as u32);
                cells += u64::from(self.visible(view, [i, j], [i + 1, j + 1], [lo, hi]));
            }
        }
        2 * cells
    }

    /// The view-dependent RTIN refinement at `tau` pixels: its triangles in
    /// the frustum (box: the triangle's corners across, the heights under
    /// its split down and up, or its corners' for a half cell) and all round.
    pub fn rtin_floor(&self, view: &FloorView, tau: f64) -> FloorCount {
        let params =
            ViewParams { eye: view.eye.to_array(), spacing: self.spacing_m, k: view.k, tau };
        let mut in_frustum = 0u64;
        let all_round = view_refine(&self.rtin, &params, &mut |t| {
            in_frustum += u64::from(self.triangle_visible(view, &t));
        })
        .expect("view refinement");
        FloorCount { in_frustum, all_round }
    }

    /// The refinement's limit as tau goes to 0 whatever the error: every
    /// split whose box meets the frustum. Its triangles in the frustum are the
    /// half cells of the cells [`Self::full_res_in_frustum`] counts (less the
    /// few whose three posts' box misses where the cell's four posts' meets).
    pub fn split_all_in_frustum(&self, view: &FloorView) -> u64 {
        let mut split = |_: &Triangle, [i, j]: [u32; 2]| {
            let b = self.split_bounds(i, j);
            self.visible(
                view,
                [b.min[0].into(), b.min[1].into()],
                [b.max[0].into(), b.max[1].into()],
                b.z,
            )
        };
        let mut in_frustum = 0u64;
        self.rtin
            .walk(&mut split, &mut |t| in_frustum += u64::from(self.triangle_visible(view, &t)));
        in_frustum
    }

    /// The share of a LOD tile's footprint that lies over the grid.
    pub fn tile_share(&self, key: TileKey, grid_size: u32) -> f64 {
        let span = (grid_size as i64) << key.level;
        let overlap = |a: usize, index: u32| {
            let tile = index as i64 * span..(index as i64 + 1) * span;
            let grid = self.first[a]..self.first[a] + self.side as i64 - 1;
            overlap(tile, grid) as f64 / span as f64
        };
        overlap(0, key.x) * overlap(1, key.y)
    }

    fn split_bounds(&self, i: u32, j: u32) -> SplitBounds {
        self.rtin.bounds_at(i, j).expect("built with bounds")
    }

    fn triangle_visible(&self, view: &FloorView, t: &Triangle) -> bool {
        let corners = t.ccw();
        let min = [0, 1].map(|a| corners.iter().map(|c| c[a]).min().unwrap_or(0));
        let max = [0, 1].map(|a| corners.iter().map(|c| c[a]).max().unwrap_or(0));
        let z = if t.is_leaf() {
            let h = corners.map(|[i, j]| self.at(i, j));
            [h[0].min(h[1]).min(h[2]), h[0].max(h[1]).max(h[2])]
        } else {
            let [i, j] = t.midpoint();
            self.split_bounds(i, j).z
        };
        self.visible(view, min, max, z)
    }

    /// The box between grid posts `min` and `max`, heights `z`, meets the frustum.
    fn visible(&self, view: &FloorView, min: [u32; 2], max: [u32; 2], z: [f32; 2]) -> bool {
        let [sx, sy] = self.spacing_m;
        let e = view.eye;
        let mut lo =
            DVec3::new(min[0] as f64 * sx - e.x, min[1] as f64 * sy - e.y, z[0] as f64 - e.z);
        let hi = DVec3::new(max[0] as f64 * sx - e.x, max[1] as f64 * sy - e.y, z[1] as f64 - e.z);
        if view.curvature {
            let far =
                DVec3::new(lo.x.abs().max(hi.x.abs()), lo.y.abs().max(hi.y.abs()), 0.0).length();
            lo.z -= curvature_drop(far);
        }
        view.frustum.intersects_box(lo.as_vec3(), hi.as_vec3())
    }
}

/// Length of the overlap of two ranges.
fn overlap(a: Range<i64>, b: Range<i64>) -> i64 {
    (a.end.min(b.end) - a.start.max(b.start)).max(0)
}

/// Copies the posts of `mesh` (whole chunks, `side` posts east) into rows
/// `band..` of the grid; NaN where the data have none.
fn copy_posts(mesh: &TruthMesh, band: u32, side: u32, heights: &mut [f32]) {
    let g = CHUNK_CELLS as usize + 1;
    for chunk in &mesh.chunks {
        for (k, vertex) in chunk.vertices[..g * g].iter().enumerate() {
            let i = chunk.first_post[0] as usize + k % g;
            let j = (band + chunk.first_post[1]) as usize + k / g;
            if i < side as usize && j < side as usize {
                heights[j * side as usize + i] =
                    if vertex.height == NO_DATA { f32::NAN } else { vertex.height };
            }
        }
    }
}
