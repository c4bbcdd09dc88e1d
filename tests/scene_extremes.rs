//! Terrain at the extremes: a flat sea at 0 m, cliffs of 2000 m from one post
//! to the next, heights from the Dead Sea shore (-430 m) to Everest
//! (8848 m), and a single-sample spike. Each goes through the real pipeline
//! (pyramid file, scene, null backend); every frame must give finite tiles
//! whose shared edges agree, and skirts at least as deep as the errors they
//! cover.

use ridgeline::dem::ElevationGrid;
use ridgeline::geo::GeoRef;
use ridgeline::node::NodeSource;
use ridgeline::pyramid::{self, BuildOptions, Pyramid, Silent};
use ridgeline::scene::{SceneConfig, TerrainSummary};
use std::sync::Arc;
use testkit::scene::{fly, null_backend, pipeline_over, worst_edge_disagreement, VIEWPORT};

const SIDE: u32 = 513;
const SPACING: f64 = 30.0;

fn grid(name: &str, height: impl Fn(u32, u32) -> f32) -> (String, ElevationGrid) {
    let heights =
        (0..SIDE).flat_map(|j| (0..SIDE).map(move |i| (i, j))).map(|(i, j)| height(i, j)).collect();
    let grid = ElevationGrid {
        width: SIDE,
        height: SIDE,
        heights,
        georef: GeoRef::local([SPACING, SPACING]),
        voids_filled: 0,
    };
    (name.to_string(), grid)
}

/// The pyramid of `grid`, built and opened (the file is removed; the open
/// map keeps it readable).
fn terrain_of(name: &str, grid: &ElevationGrid) -> Arc<Pyramid> {
    let dir = testkit::target_tmp().join(format!("extreme-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let built = pyramid::build(grid, &BuildOptions::default(), &Silent).unwrap();
    pyramid::write_atomic(&built, &dir.join(pyramid::FILE_NAME), &Silent).unwrap();
    let pyramid = Arc::new(Pyramid::open(&dir).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
    pyramid
}

#[test]
fn extreme_terrain_draws_without_cracks() {
    let cases = [
        grid("flat-sea", |_, _| 0.0),
        grid("cliffs", |i, _| if (i / 16) % 2 == 0 { 0.0 } else { 2000.0 }),
        grid("dead-sea-to-everest", |i, j| {
            -430.0 + (8848.0 + 430.0) * (i + j) as f32 / (2 * (SIDE - 1)) as f32
        }),
        grid("spike", |i, j| if (i, j) == (300, 300) { 8848.0 } else { 100.0 }),
    ];
    let extent = (SIDE - 1) as f64 * SPACING;
    for (name, grid) in &cases {
        let terrain = terrain_of(name, grid);
        let summary = TerrainSummary::from_pyramid(terrain.info());
        let (_, top) = summary.height_range;
        let deltas = summary.delta_per_level.clone();
        let config = SceneConfig::default();
        let source: Arc<dyn NodeSource> = terrain;
        let mut pipeline = pipeline_over(source, summary, config);
        let mut backend = null_backend(&pipeline);
        let (mut worst, mut draw_calls): (f64, u64) = (0.0, 0);
        for k in 0..12 {
            let t = k as f64 / 11.0;
            let cam = testkit::camera(
                VIEWPORT,
                glam::DVec3::new(
                    0.1 * extent + 0.7 * extent * t,
                    0.2 * extent + 0.5 * extent * t,
                    top as f64 + 300.0,
                ),
                45.0,
                -12.0,
            );
            let stats = fly(&mut pipeline, &mut backend, &cam)
                .unwrap_or_else(|e| panic!("{name}, frame {k}: {e}"));
            draw_calls += stats.calls.draw_calls;
            let (list, staging) = (pipeline.draw_list(), pipeline.staging());
            for tile in &list.tiles {
                // How deep each edge hangs is checked where it matters: no
                // shared edge opens wider than its skirts (below).
                assert!(
                    (0..4).all(|e| (0.0..1e6).contains(&tile.edge_skirt_m(e))),
                    "{name}: skirts {:?} of {}",
                    tile.skirt_shares,
                    tile.skirt_depth
                );
                assert!(tile
                    .first_post
                    .iter()
                    .chain([&tile.post_step])
                    .chain(&tile.morph)
                    .all(|v| v.is_finite()));
            }
            worst = worst.max(worst_edge_disagreement(
                list,
                staging,
                cam.position.z,
                config.lod.grid_size,
            ));
        }
        println!(
            "{name}: deltas {deltas:?}, worst shared-edge disagreement {worst:.4} m, {draw_calls} draw calls"
        );
        assert!(draw_calls > 12, "{name}: something was drawn");
        assert!(worst < 0.01, "{name}: tiles disagree by {worst} m along a shared edge");
    }
}
