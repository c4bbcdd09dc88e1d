//! Valid life (Wu et al. section 5, issue 13): a selector that re-tests a
//! tile's split only when its life has run out selects exactly what a full
//! re-evaluation selects, on every frame:
//! - over random walks of the built-in terrain within the declared travel,
//!   with turns of any size, tau moving as a budget moves it, and jumps
//!   farther than declared (which must re-test everything);
//! - over the default flight through the whole pipeline (paging included),
//!   where it also reports how few tiles were re-tested.

use std::sync::Arc;

use proptest::prelude::*;
use ridgeline::camera::{Camera, Frustum};
use ridgeline::flight::default_flight;
use ridgeline::lod::life::LifeStats;
use ridgeline::lod::select::{SelectedTile, View};
use ridgeline::lod::TileKey;
use ridgeline::lod::{LevelRings, LodConfig, TileSelector};
use ridgeline::node::NodeSource;
use ridgeline::pipeline::{FramePipeline, PipelineConfig};
use ridgeline::scene::{
    clip_planes, ring_inputs, PreloadedTerrain, SceneConfig, TerrainData, TerrainSummary,
};
use ridgeline::tiles::ResidentNodes;
use testkit::flight::{along, fly, OnBackend, Settle};
use testkit::scene::{null_backend, terrain, VIEWPORT};
use testkit::{camera, over_tile};

/// One move of the walk: a step (as a share of the declared travel, and a
/// direction), a turn, and a change of tau.
#[derive(Clone, Debug)]
struct Move {
    share: f64,
    bearing: f64,
    climb: f64,
    heading: f64,
    pitch: f64,
    tau_factor: f64,
    jump: bool,
}

fn moves() -> impl Strategy<Value = Vec<Move>> {
    let one = (0.0..=1.0f64, 0.0..360.0f64, -1.0..1.0f64, 0.0..360.0f64, -30.0..5.0f64)
        .prop_flat_map(|(share, bearing, climb, heading, pitch)| {
            (prop_oneof![8 => Just(1.0), 1 => 0.8..1.25f64], prop::bool::weighted(0.04)).prop_map(
                move |(tau_factor, jump)| Move {
                    share,
                    bearing,
                    climb,
                    heading,
                    pitch,
                    tau_factor,
                    jump,
                },
            )
        });
    prop::collection::vec(one, 40)
}

/// The tiles `selector` picks for `camera` at `tau_px`.
fn select(
    selector: &mut TileSelector,
    terrain: &PreloadedTerrain,
    camera: &Camera,
    tau_px: f64,
) -> Vec<SelectedTile> {
    let layout = *terrain.layout();
    let lod = LodConfig { tau_px, ..*selector.config() };
    let (lo, hi) = terrain.height_range();
    let deltas = terrain.delta_per_level();
    let inputs = ring_inputs(&layout, lod.grid_size, &deltas, (hi - lo) as f64, camera);
    let rings = LevelRings::new(&lod, inputs);
    let (near, far) = clip_planes(camera, terrain);
    let frustum = Frustum::from_view_projection(camera.projection(near, far) * camera.view());
    let view = View {
        eye: camera.position,
        frustum: &frustum,
        rings: &rings,
        curvature: true,
        horizon: None,
        earth: None,
    };
    selector.select(&view, terrain).to_vec()
}

const TRAVEL_M: f64 = 400.0;

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn valid_life_selects_what_full_re_evaluation_selects(
        start in (0.0..70_000.0f64, 0.0..90_000.0f64, 200.0..6000.0f64),
        walk in moves(),
    ) {
        let terrain = terrain();
        let full_config = LodConfig::default();
        let mut full = TileSelector::new(full_config);
        let mut life = TileSelector::new(LodConfig { max_travel_m: Some(TRAVEL_M), ..full_config });
        let (mut x, mut y, mut z) = start;
        let mut tau = 1.0;
        let (mut tested, mut candidates) = (0u64, 0u64);
        for (frame, m) in walk.iter().enumerate() {
            let step = m.share * TRAVEL_M;
            let (horizontal, vertical) = match m.jump {
                true => (5.0 * TRAVEL_M, 0.0),
                false => (step * (1.0 - m.climb * m.climb).sqrt(), step * m.climb),
            };
            x += horizontal * m.bearing.to_radians().sin();
            y += horizontal * m.bearing.to_radians().cos();
            z = (z + vertical).max(100.0);
            tau = (tau * m.tau_factor).clamp(1.0, 16.0);
            let cam = camera(VIEWPORT, over_tile(x, y, z + 2500.0), m.heading, m.pitch);
            let expected = select(&mut full, terrain, &cam, tau);
            let got = select(&mut life, terrain, &cam, tau);
            prop_assert_eq!(&got, &expected, "frame {} at {:?}", frame, cam.position);
            let stats = life.life_stats().expect("a valid life");
            prop_assert!(stats.full || !(frame == 0 || m.jump), "a jump must re-test everything");
            tested += stats.re_evaluated as u64;
            candidates += stats.candidates as u64;
        }
        prop_assert!(tested < candidates, "no test was kept: {} of {}", tested, candidates);
    }
}

/// Frames of `ridgeline fly`'s default run, and its image size.
const FLY_FRAMES: u32 = 120;
const FLY_SIZE: [u32; 2] = [1280, 720];

/// Each frame's drawn tiles and the valid life's counts, along the default
/// flight as `ridgeline fly` flies it, on the null backend.
fn fly_default(max_travel_m: Option<f64>, meshes: bool) -> Vec<(Vec<TileKey>, LifeStats)> {
    let pyramid = testkit::builtin_pyramid();
    let path = default_flight(&pyramid);
    let mut scene = SceneConfig::default();
    scene.lod.max_travel_m = max_travel_m;
    let config = PipelineConfig {
        scene,
        loader: ridgeline::clipmap::LoaderMode::Inline,
        load_budget: 4096,
        ..PipelineConfig::new(FLY_SIZE)
    };
    let (source, summary): (Arc<dyn NodeSource>, _) = if meshes {
        let terrain = testkit::builtin_terrain();
        let summary = testkit::summary_of(&terrain);
        (terrain, summary)
    } else {
        (pyramid.clone(), TerrainSummary::from_pyramid(pyramid.info()))
    };
    let mut pipeline = FramePipeline::new(&config, source, summary).expect("pipeline");
    let mut backend = null_backend(&pipeline);
    let mut flyer = OnBackend { pipeline: &mut pipeline, backend: &mut backend };
    fly(&mut flyer, along(&path, FLY_FRAMES, 60.0, FLY_SIZE), Settle::Never, |frame| {
        let keys = frame.flyer.pipeline.draw_list().tiles.iter().map(|t| t.key).collect();
        (keys, frame.stats.scene.split_tests)
    })
}

#[test]
fn the_default_flight_selects_the_same_and_re_tests_few_tiles() {
    for meshes in [true, false] {
        default_flight_matches(meshes);
    }
}

fn default_flight_matches(meshes: bool) {
    let pyramid = testkit::builtin_pyramid();
    let travel = default_flight(&pyramid).max_travel_per_frame(FLY_FRAMES);
    let full = fly_default(None, meshes);
    let life = fly_default(Some(travel), meshes);
    let mut fractions = Vec::new();
    for (frame, ((expected, _), (got, stats))) in full.iter().zip(&life).enumerate() {
        assert_eq!(got, expected, "frame {frame}: the valid life selected other tiles");
        assert!(
            !stats.full || frame == 0,
            "frame {frame}: a full re-evaluation within the declared travel"
        );
        fractions.push(stats.fraction());
    }
    let mean = fractions.iter().sum::<f64>() / fractions.len() as f64;
    let later = &fractions[1..];
    let max = later.iter().cloned().fold(0.0, f64::max);
    let candidates = life.iter().map(|(_, s)| s.candidates as f64).sum::<f64>() / life.len() as f64;
    let tested = life.iter().map(|(_, s)| s.re_evaluated as f64).sum::<f64>() / life.len() as f64;
    println!(
        "default flight ({}), {FLY_FRAMES} frames at {:?}, declared travel {travel:.1} m a frame: \
         {tested:.1} of {candidates:.1} split tests made a frame ({:.1} % mean, {:.1} % at most after the first frame)",
        if meshes { "node meshes" } else { "regular grids" },
        FLY_SIZE,
        100.0 * mean,
        100.0 * max
    );
    assert!(mean <= 0.10, "re-tested {:.1} % of candidates a frame", 100.0 * mean);
}
