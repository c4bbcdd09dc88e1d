//! The clipmap with its loader thread: a still camera converges to the same
//! resident set as inline loading, a moving one keeps every invariant, and
//! failing or panicking sources degrade to fallbacks and errors, not hangs.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec2, DVec3};
use ridgeline::clipmap::{Clipmap, ClipmapError, LoaderMode, ViewId};
use ridgeline::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use ridgeline::procedural::ProceduralEarth;
use testkit::clipmap::*;

const THREAD: LoaderMode = LoaderMode::Thread { queue: 4 };

/// Updates until nothing is missing or in flight (or `limit` passes),
/// checking every frame.
fn settle(clipmap: &mut Clipmap, limit: Duration) -> u32 {
    let start = Instant::now();
    let mut frames = 0;
    loop {
        let before = snapshot(clipmap);
        let stats = clipmap.update().unwrap();
        check_frame(clipmap, &before, &stats).unwrap();
        frames += 1;
        if stats.missing == 0 && stats.in_flight == 0 {
            return frames;
        }
        assert!(start.elapsed() < limit, "not settled after {frames} frames: {stats:?}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn resident(clipmap: &Clipmap) -> Vec<NodeId> {
    let atlas = clipmap.atlas();
    let mut ids: Vec<NodeId> = (0..atlas.slot_count()).filter_map(|s| atlas.node_in(s)).collect();
    ids.sort();
    ids
}

#[test]
fn a_still_camera_converges_like_inline_loading() {
    let earth = earth(11);
    let position = over_ground(&earth, 2.2e7, 1.7e7, 80.0);
    let mut threaded = clipmap(&earth, 1500, 6, THREAD);
    let mut inline = clipmap(&earth, 1500, 6, LoaderMode::Inline);
    let (a, b) =
        (threaded.add_view(VIEW, position).unwrap(), inline.add_view(VIEW, position).unwrap());
    let frames = settle(&mut threaded, Duration::from_secs(30));
    settle(&mut inline, Duration::from_secs(30));
    assert_eq!(resident(&threaded), resident(&inline));
    assert!(resident(&threaded).len() > 100 && frames > 100 / 6);
    for point in [position.truncate(), position.truncate() + DVec2::new(150.0, -90.0)] {
        assert_eq!(threaded.height_at(a, point), inline.height_at(b, point));
        check_height(&threaded, a, point).unwrap();
    }
}

#[test]
fn a_moving_camera_with_the_thread_keeps_every_invariant() {
    let earth = earth(12);
    let mut clipmap = clipmap(&earth, 300, 4, THREAD);
    let mut primary = over_ground(&earth, 9e6, 9e6, 300.0);
    let mut map = primary + DVec3::new(0.0, 0.0, 8000.0);
    let (pfd, overview) =
        (clipmap.add_view(VIEW, primary).unwrap(), clipmap.add_view(VIEW, map).unwrap());
    let mut loaded = 0;
    for frame in 0..120 {
        primary += DVec3::new(250.0 / 60.0 * 20.0, 30.0, -1.0);
        map = primary + DVec3::new(0.0, 0.0, 8000.0);
        clipmap.set_view_position(pfd, primary).unwrap();
        clipmap.set_view_position(overview, map).unwrap();
        let before = snapshot(&clipmap);
        let stats = clipmap.update().unwrap();
        check_frame(&clipmap, &before, &stats).unwrap();
        loaded += stats.applied;
        for (view, at) in [(pfd, primary), (overview, map)] {
            check_entries(&clipmap, view).unwrap();
            check_height(&clipmap, view, at.truncate()).unwrap();
            check_lookup(&clipmap, view, at.truncate() + DVec2::new(frame as f64, 500.0)).unwrap();
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(loaded > 0);
}

/// Fails (or panics) on level-0 and level-1 nodes whose x is a multiple of 3.
struct Flaky {
    earth: Arc<ProceduralEarth>,
    panic: bool,
}

impl NodeSource for Flaky {
    fn layout(&self) -> &NodeLayout {
        self.earth.layout()
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        if id.level < 2 && id.x % 3 == 0 {
            assert!(!self.panic, "the flaky source panics on {id:?}");
            return Err(NodeError::Corrupt { path: "flaky".into(), id, problem: "refused".into() });
        }
        self.earth.read_node(id, out)
    }

    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        self.earth.exact_height(x_m, y_m)
    }
}

fn flaky_clipmap(panic: bool, loader: LoaderMode) -> (Clipmap, ViewId, DVec3) {
    let earth = earth(13);
    let position = over_ground(&earth, 4e6, 4e6, 20.0);
    let source = Arc::new(Flaky { earth, panic });
    let config = ridgeline::clipmap::ClipmapConfig {
        atlas_bytes: None,
        atlas_slots: 1500,
        budget: 50,
        loader,
    };
    let mut clipmap = Clipmap::new(source, config).unwrap();
    let view = clipmap.add_view(VIEW, position).unwrap();
    (clipmap, view, position)
}

#[test]
fn failed_loads_fall_back_and_are_not_retried() {
    for loader in [LoaderMode::Inline, THREAD] {
        let (mut clipmap, view, position) = flaky_clipmap(false, loader);
        let (mut failed, start) = (0, Instant::now());
        loop {
            let stats = clipmap.update().unwrap();
            failed += stats.failed;
            let idle = stats.in_flight + stats.requested + stats.applied + stats.failed == 0;
            if idle && clipmap.frame() > 3 {
                assert!(stats.missing > 0, "the refused nodes stay missing");
                break;
            }
            assert!(start.elapsed() < Duration::from_secs(30), "{loader:?} never settled");
            std::thread::sleep(Duration::from_millis(1));
        }
        assert!(failed > 0 && matches!(clipmap.last_load_error(), Some(NodeError::Corrupt { .. })));
        let more: u32 = (0..5).map(|_| clipmap.update().unwrap().failed).sum();
        assert_eq!(more, 0, "{loader:?}: failed nodes are not requested again");
        for dx in [-40.0, 0.0, 35.0, 77.0] {
            let point = position.truncate() + DVec2::new(dx, 10.0);
            check_height(&clipmap, view, point).unwrap();
            let node = clipmap.height_at(view, point).unwrap().node;
            assert!(node.level >= 2 || node.x % 3 != 0, "{point}: answered from refused {node:?}");
        }
    }
}

#[test]
fn a_panicking_source_stops_the_loader_with_an_error() {
    let (mut clipmap, view, position) = flaky_clipmap(true, THREAD);
    let start = Instant::now();
    let error = loop {
        match clipmap.update() {
            Ok(_) => assert!(start.elapsed() < Duration::from_secs(30), "the panic never surfaced"),
            Err(error) => break error,
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    assert!(matches!(error, ClipmapError::LoaderStopped), "{error}");
    check_height(&clipmap, view, position.truncate()).unwrap();
    drop(clipmap); // joins the dead thread without hanging
}
