//! No cracks, checked on the CPU: along a low flight with many LOD changes,
//! wherever two selected tiles share an edge, the heights the shader will draw
//! there (vertex data plus the per-vertex morph of src/lod/morph.rs) agree
//! where no skirt hangs, and differ by less than the skirt's depth where one
//! does (node meshes of two nodes choose their edge vertices each).
//!
//! With clusters on, the heights are read back from the cluster blocks and
//! each member's uniforms from its cluster's uniform array at the slot its
//! vertices carry (`clusters::mirror`): what the GPU is given.

use ridgeline::clusters::mirror::drawn_tiles;
use ridgeline::render::ClusterMorph;
use ridgeline::scene::{Scene, SceneConfig};
use testkit::scene::{edge_heights, terrain, VIEWPORT};
use testkit::{camera, over_tile};

#[test]
fn shared_edges_agree_along_a_low_flight() {
    low_flight_edges(terrain(), SceneConfig::default()).unwrap();
}

/// The same over node meshes: tiles of two nodes' meshes meet under a
/// skirt deep enough to hide the gap between their edges.
#[test]
fn shared_edges_of_node_meshes_are_covered() {
    low_flight_edges(testkit::scene::terrain_meshed(), SceneConfig::default()).unwrap();
}

fn clustered() -> SceneConfig {
    SceneConfig { clusters: true, ..SceneConfig::default() }
}

/// Drawn as clusters, over grids and over node meshes.
#[test]
fn shared_edges_agree_drawn_as_clusters() {
    low_flight_edges(terrain(), clustered()).unwrap();
    low_flight_edges(testkit::scene::terrain_meshed(), clustered()).unwrap();
}

/// Every member of a cluster morphing over its first member's range (one
/// morph per cluster): edges between clusters no longer agree, and the
/// check says so.
#[test]
fn the_check_finds_a_broken_cluster_morph() {
    let broken = SceneConfig { cluster_morph: ClusterMorph::FirstMember, ..clustered() };
    let problem = low_flight_edges(terrain(), broken).expect_err("a broken cluster morph cracks");
    println!("caught: {problem}");
}

fn low_flight_edges(
    terrain: &ridgeline::scene::PreloadedTerrain,
    config: SceneConfig,
) -> Result<(), String> {
    let mut scene = Scene::new(config, terrain).unwrap();
    let grid = config.lod.grid_size;
    let mut levels_seen = std::collections::BTreeSet::new();
    let mut shared_points = 0;
    let mut skirted = 0;
    for k in 0..30 {
        let t = k as f64 / 29.0;
        let cam = camera(
            VIEWPORT,
            over_tile(8_000.0 + 50_000.0 * t, 10_000.0 + 60_000.0 * t, 3_600.0 - 1_000.0 * t),
            40.0,
            -8.0,
        );
        scene.frame(&cam, terrain).unwrap();
        let (list, staging) = match scene.clusters() {
            Some(clusters) => {
                drawn_tiles(scene.draw_list(), clusters.staging(), clusters.index_staging())
            }
            None => (scene.draw_list().clone(), scene.uploads().0.to_vec()),
        };
        levels_seen.extend(list.tiles.iter().map(|t| t.key.level));
        for ((x, y), values) in edge_heights(&list, &staging, cam.position.z, grid) {
            if values.len() < 2 {
                continue;
            }
            shared_points += 1;
            let (lo, hi) = values
                .iter()
                .fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v.height), hi.max(v.height)));
            // Without a skirt the surfaces must meet; with one, the skirt
            // hung from the edge must reach below the other surface.
            let skirt = values.iter().map(|v| v.skirt_m).fold(0.0, f64::max);
            let allowed = if skirt > 0.0 { skirt } else { 0.01 };
            if skirt > 0.0 {
                skirted += 1;
            }
            if hi - lo >= allowed {
                return Err(format!(
                    "frame {k}: tiles disagree by {} m at post ({}, {}) (skirt {skirt} m)",
                    hi - lo,
                    x as f64 / 2.0,
                    y as f64 / 2.0
                ));
            }
        }
    }
    assert!(levels_seen.len() >= 3, "the flight crosses several levels: {levels_seen:?}");
    assert!(shared_points > 1000, "enough shared edge points were compared: {shared_points}");
    println!("{shared_points} shared edge points, {skirted} under a skirt");
    Ok(())
}
