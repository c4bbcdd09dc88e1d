//! A clipmap whose atlas is counted in bytes (a memory budget): over a
//! flight across the procedural earth its nodes never take more than the
//! budget beside the pinned root level, the nodes a view needs most (the
//! finest under the viewer) are resident while far ones are left out, and
//! what was left out is counted.

use glam::DVec3;
use ridgeline::clipmap::{Clipmap, ClipmapConfig, LoaderMode, ViewConfig};
use ridgeline::node::{NodeId, NodeSource};

use testkit::clipmap::*;

const ROOM: u64 = 400;
const VIEW_CONFIG: ViewConfig =
    ViewConfig { node_count: 12, view_distance: 3.0, load_distance: 4.5 };

fn budgeted(earth: &std::sync::Arc<ridgeline::procedural::ProceduralEarth>, nodes: u64) -> Clipmap {
    let bytes = nodes * earth.node_bytes();
    let config = ClipmapConfig {
        atlas_slots: 4000,
        atlas_bytes: Some(bytes),
        budget: 64,
        loader: LoaderMode::Inline,
    };
    Clipmap::new(earth.clone(), config).unwrap()
}

#[test]
fn a_byte_budget_keeps_the_nodes_under_the_viewer_and_leaves_out_far_ones() {
    let earth = earth(5);
    let layout = *earth.layout();
    // Room for ROOM nodes beside the root level: the view wants three times as many.
    let mut clipmap = budgeted(&earth, ROOM);
    let budget = clipmap.atlas().byte_budget().unwrap();
    let pinned = clipmap.atlas().pinned_bytes();
    let start = over_ground(&earth, 6e6, 6e6, 300.0);
    let view = clipmap.add_view(VIEW_CONFIG, start).unwrap();
    let (mut wanted, mut over) = (0, 0);
    for frame in 0..200 {
        let at = start + DVec3::new(40.0 * frame as f64, 25.0 * frame as f64, 0.0);
        clipmap.set_view_position(view, at).unwrap();
        let stats = clipmap.update().unwrap();
        (wanted, over) = (wanted.max(stats.wanted), over.max(stats.over_budget));
        let resident = clipmap.atlas().resident_bytes();
        assert!(
            resident <= budget + pinned,
            "frame {frame}: {resident} bytes resident, budget {budget} and pinned {pinned}"
        );
        if frame < 20 {
            continue; // settling: a few frames of loads
        }
        // The budget goes to the nodes whose absence would draw the largest
        // error, their size over their distance: every wanted node nearer
        // than 1.5 of its own sizes is resident (ROOM holds those within
        // about 2.3 sizes at every level). Coarsest first, the finest
        // levels would be left out instead.
        let ground = earth.exact_height(at.x, at.y).unwrap() as f64;
        let mut near = 0;
        for level in 0..layout.levels {
            let size = layout.node_size_m(level);
            let [nx, ny] = layout.nodes_at(level);
            let around = |p: f64, size: f64, n: u32| {
                let first = ((p - 2.0 * size) / size).floor().max(0.0) as u32;
                first..(((p + 2.0 * size) / size).ceil() as u32).min(n)
            };
            for y in around(at.y, size[1], ny) {
                let cy = (y as f64 * size[1], (y + 1) as f64 * size[1]);
                for x in around(at.x, size[0], nx) {
                    let cx = (x as f64 * size[0], (x + 1) as f64 * size[0]);
                    let gap = |p: f64, (lo, hi): (f64, f64)| (lo - p).max(p - hi).max(0.0);
                    let (gx, gy) = (gap(at.x, cx), gap(at.y, cy));
                    let distance = (gx * gx + gy * gy + (at.z - ground).powi(2)).sqrt();
                    let id = NodeId::new(level, x, y);
                    if distance > 1.5 * size[0] || !clipmap.is_wanted(id) {
                        continue;
                    }
                    near += 1;
                    assert!(
                        clipmap.atlas().slot_of(id).is_some(),
                        "frame {frame}: {id:?}, {distance:.0} m away, is not resident"
                    );
                }
            }
        }
        assert!(near >= 40, "frame {frame}: only {near} wanted nodes near the viewer");
    }
    println!("wanted up to {wanted} nodes, up to {over} left out, room for {ROOM}");
    assert!(
        wanted as u64 > ROOM && over > 0,
        "the budget never bound: {wanted} wanted, {over} left out"
    );
}

#[test]
fn without_a_budget_the_atlas_is_not_counted_in_bytes() {
    let earth = earth(5);
    let mut clipmap = clipmap(&earth, 2000, 64, LoaderMode::Inline);
    let view = clipmap.add_view(VIEW, over_ground(&earth, 6e6, 6e6, 300.0)).unwrap();
    clipmap.set_view_position(view, over_ground(&earth, 6e6, 6e6, 300.0)).unwrap();
    let stats = clipmap.update().unwrap();
    assert_eq!((clipmap.atlas().byte_room(), stats.over_budget), (None, 0));
}
