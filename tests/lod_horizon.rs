//! Horizon culling never culls a visible tile: over random cameras above a
//! procedural earth, every tile the selector drops below the horizon (and
//! would draw without horizon culling) is checked post by post against a
//! brute-force model: the sight line from the eye to each of its posts, at
//! the post's exact height, sampled along its length, must dip below the
//! floor surface (the lowest height anywhere, lowered by the display's
//! curvature drop), which the drawn terrain never goes below.
//!
//! And on a cruise at 10 km the horizon does cull: a measured share.

use std::cell::RefCell;
use std::collections::HashMap;

use glam::DVec3;
use proptest::prelude::*;
use ridgeline::camera::{Camera, Frustum};
use ridgeline::lod::horizon::Horizon;
use ridgeline::lod::rings::RingInputs;
use ridgeline::lod::select::{TileBounds, View};
use ridgeline::lod::{LevelRings, LodConfig, TileKey, TileSelector};
use ridgeline::node::{NodeData, NodeId, NodeSource};
use ridgeline::procedural::{EarthParams, ProceduralEarth};

const GRID: u32 = 32;

/// A procedural earth 2516 km a side, 38.4 m posts, 32-cell nodes.
fn earth() -> ProceduralEarth {
    let params = EarthParams { node_size: 32, levels: 12, border: 1, spacing_m: 38.4, seed: 5 };
    ProceduralEarth::new(params).unwrap()
}

/// Tile bounds from each tile's node, read on demand (and kept).
struct Bounds<'a> {
    earth: &'a ProceduralEarth,
    nodes: RefCell<HashMap<NodeId, (f32, f32)>>,
}

impl TileBounds for Bounds<'_> {
    fn posts(&self) -> [u32; 2] {
        self.earth.layout().posts
    }

    fn spacing_m(&self) -> [f64; 2] {
        self.earth.layout().spacing_m
    }

    fn height_bounds(&self, tile: TileKey, grid_size: u32) -> (f32, f32) {
        let per_node = self.earth.layout().node_size / grid_size;
        let id = NodeId::new(tile.level, tile.x / per_node, tile.y / per_node);
        *self.nodes.borrow_mut().entry(id).or_insert_with(|| {
            let mut data = NodeData::default();
            self.earth.read_node(id, &mut data).unwrap();
            (data.min - data.delta, data.max + data.delta)
        })
    }

    fn has_finer_data(&self, tile: TileKey, _grid_size: u32) -> bool {
        tile.level > 0
    }
}

/// Tiles selected for `camera` without and with horizon culling, and the
/// horizon culled count.
fn select(
    earth: &ProceduralEarth,
    camera: &Camera,
) -> (Vec<TileKey>, Vec<TileKey>, usize, Horizon) {
    let config = LodConfig { max_tiles: 1 << 20, ..LodConfig::default() };
    let deltas: Vec<f64> =
        (0..earth.layout().levels).map(|l| earth.delta_bound(l) as f64).collect();
    let [low, high] = earth.height_bounds();
    let inputs = RingInputs {
        tile_size_m: GRID as f64 * 38.4,
        delta_per_level: &deltas,
        height_range_m: high - low,
        perspective_scale: camera.perspective_scale(),
    };
    let rings = LevelRings::new(&config, inputs);
    let frustum = Frustum::from_view_projection(camera.projection(1.0, 2e6) * camera.view());
    let horizon = Horizon::new(camera.position.z, low).unwrap();
    let bounds = Bounds { earth, nodes: RefCell::new(HashMap::new()) };
    let mut selector = TileSelector::new(config);
    let mut keys = |horizon: Option<Horizon>| {
        let view = View {
            eye: camera.position,
            frustum: &frustum,
            rings: &rings,
            curvature: true,
            horizon,
            earth: None,
        };
        let keys: Vec<TileKey> = selector.select(&view, &bounds).iter().map(|t| t.key).collect();
        (keys, selector.horizon_culled())
    };
    let (all, _) = keys(None);
    let (kept, culled) = keys(Some(horizon));
    (all, kept, culled, horizon)
}

/// Whether some post of `tile` is visible over the floor (brute force).
fn some_post_visible(
    earth: &ProceduralEarth,
    tile: TileKey,
    eye: DVec3,
    horizon: &Horizon,
) -> bool {
    let stride = 1i64 << tile.level;
    let first = [tile.x as i64 * GRID as i64 * stride, tile.y as i64 * GRID as i64 * stride];
    let last = earth.layout().posts[0] as i64 - 1;
    (0..=GRID as i64).any(|j| {
        (0..=GRID as i64).any(|i| {
            let (px, py) = ((first[0] + i * stride).min(last), (first[1] + j * stride).min(last));
            let h = earth.sample(px, py) as f64;
            let d = (DVec3::new(px as f64 * 38.4, py as f64 * 38.4, 0.0) - eye).truncate().length();
            !horizon.line_dips(d, h, 4000)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn horizon_culling_never_drops_a_visible_tile(
        altitude in 500.0f64..15_000.0,
        heading in 0.0f64..360.0,
        pitch in -15.0f64..5.0,
        east in 0.3f64..0.7,
        north in 0.3f64..0.7,
    ) {
        let earth = earth();
        let side = (earth.layout().posts[0] - 1) as f64 * 38.4;
        let ground = earth.exact_height(east * side, north * side).unwrap() as f64;
        let camera = testkit::camera([640, 360], DVec3::new(east * side, north * side, ground.max(0.0) + altitude), heading, pitch);
        let (all, kept, culled, horizon) = select(&earth, &camera);
        let dropped: Vec<TileKey> = all.iter().filter(|k| !kept.contains(k)).copied().collect();
        prop_assert!(kept.iter().all(|k| all.contains(k)), "the horizon only drops tiles");
        prop_assert!(dropped.is_empty() || culled > 0);
        for tile in dropped {
            prop_assert!(
                !some_post_visible(&earth, tile, camera.position, &horizon),
                "tile {tile:?} has a visible post"
            );
        }
    }
}

#[test]
fn a_cruise_at_ten_km_culls_a_share_of_tiles_below_the_horizon() {
    let earth = earth();
    let side = (earth.layout().posts[0] - 1) as f64 * 38.4;
    let camera =
        testkit::camera([640, 360], DVec3::new(side / 2.0, side / 2.0, 10_000.0), 45.0, -4.0);
    let (all, kept, culled, _) = select(&earth, &camera);
    println!("{} tiles without horizon culling, {} with; {culled} culled", all.len(), kept.len());
    assert!(culled > 0 && kept.len() < all.len());
}
