//! The loader's handling of failed and unwanted reads: an I/O error is read
//! again after a doubling delay and given up after a few attempts, a
//! checksum failure is not retried, and queued loads no view wants any more
//! are cancelled before they are read.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use glam::{DVec2, DVec3};
use ridgeline::clipmap::{
    Clipmap, ClipmapConfig, LoaderMode, ViewId, READ_ATTEMPTS, RETRY_FIRST_DELAY_FRAMES,
};
use ridgeline::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use ridgeline::procedural::ProceduralEarth;
use testkit::clipmap::*;

/// Fails the first `failures` reads of `target` with an I/O error (or a
/// checksum error when `corrupt`), and counts them.
struct Failing {
    earth: Arc<ProceduralEarth>,
    target: NodeId,
    failures: u32,
    corrupt: bool,
    reads: AtomicU32,
}

impl NodeSource for Failing {
    fn layout(&self) -> &NodeLayout {
        self.earth.layout()
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        if id == self.target {
            let read = self.reads.fetch_add(1, Ordering::SeqCst);
            if read < self.failures {
                let path = "failing.rlp".into();
                return Err(if self.corrupt {
                    NodeError::Corrupt { path, id, problem: "checksum mismatch".into() }
                } else {
                    let source = std::io::Error::new(std::io::ErrorKind::TimedOut, "injected");
                    NodeError::Io { path, source }
                });
            }
        }
        self.earth.read_node(id, out)
    }

    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        self.earth.exact_height(x_m, y_m)
    }
}

/// An inline clipmap whose level-0 node under the viewer fails `failures`
/// times; every wanted node is loaded in the frame it is first wanted.
fn failing(failures: u32, corrupt: bool, loader: LoaderMode) -> (Clipmap, Arc<Failing>, ViewId) {
    let earth = earth(41);
    let position = over_ground(&earth, 5e6, 5e6, 30.0);
    let target = earth.layout().locate(0, position.x, position.y).unwrap().id;
    let source = Arc::new(Failing { earth, target, failures, corrupt, reads: AtomicU32::new(0) });
    let config = ClipmapConfig { atlas_bytes: None, atlas_slots: 3000, budget: 1000, loader };
    let mut clipmap = Clipmap::new(source.clone(), config).unwrap();
    let view = clipmap.add_view(VIEW, position).unwrap();
    (clipmap, source, view)
}

/// The frames (1-based) of `frames` updates in which the target was read.
fn read_frames(clipmap: &mut Clipmap, source: &Failing, frames: u64) -> Vec<u64> {
    let mut at = Vec::new();
    for frame in 1..=frames {
        let before = source.reads.load(Ordering::SeqCst);
        clipmap.update().unwrap();
        if source.reads.load(Ordering::SeqCst) > before {
            at.push(frame);
        }
    }
    at
}

/// Frames of the first `attempts` reads: `first`, then 4, 8, 16 ... later.
/// (The view first wants the node in its second frame, once the ground
/// under it is known from the first.)
fn backoff_frames(first: u64, attempts: u32) -> Vec<u64> {
    let mut frames = vec![first];
    for k in 1..attempts {
        frames.push(frames[k as usize - 1] + (RETRY_FIRST_DELAY_FRAMES << (k - 1)));
    }
    frames
}

#[test]
fn an_io_error_is_retried_with_a_doubling_delay_until_the_read_succeeds() {
    let (mut clipmap, source, _) = failing(2, false, LoaderMode::Inline);
    let target = source.target;
    let frames = read_frames(&mut clipmap, &source, 40);
    assert_eq!(frames, backoff_frames(frames[0], 3), "first, 4 and 12 frames later");
    assert!(clipmap.atlas().slot_of(target).is_some(), "the third read landed");
    assert!(!clipmap.has_given_up(target));
    assert_eq!((clipmap.corrupt_nodes(), clipmap.unreadable_nodes()), (0, 0));
}

#[test]
fn an_io_error_that_persists_gives_the_node_up_after_the_attempts() {
    let (mut clipmap, source, view) = failing(u32::MAX, false, LoaderMode::Inline);
    let position = clipmap.view(view).position();
    let target = source.target;
    let frames = read_frames(&mut clipmap, &source, 200);
    let expected = backoff_frames(frames[0], READ_ATTEMPTS);
    assert_eq!(frames, expected, "first, +4, +12, +28, +60 frames, then never again");
    assert_eq!((clipmap.unreadable_nodes(), clipmap.corrupt_nodes()), (1, 0));
    assert!(clipmap.has_given_up(target) && clipmap.is_wanted(target));
    assert!(matches!(clipmap.last_load_error(), Some(NodeError::Io { .. })));
    let sample = clipmap.height_at(view, position.truncate()).unwrap();
    assert_eq!(sample.node, target.parent().unwrap(), "the parent answers for the lost node");
    check_height(&clipmap, view, position.truncate()).unwrap();
    check_entries(&clipmap, view).unwrap();
}

#[test]
fn a_checksum_failure_is_not_retried() {
    let (mut clipmap, source, _) = failing(u32::MAX, true, LoaderMode::Inline);
    assert_eq!(read_frames(&mut clipmap, &source, 80).len(), 1, "read once");
    assert_eq!((clipmap.corrupt_nodes(), clipmap.unreadable_nodes()), (1, 0));
    assert!(clipmap.has_given_up(source.target));
}

#[test]
fn the_thread_retries_too() {
    let (mut clipmap, source, _) = failing(2, false, LoaderMode::Thread { queue: 8 });
    let start = Instant::now();
    while clipmap.atlas().slot_of(source.target).is_none() {
        clipmap.update().unwrap();
        assert!(start.elapsed() < Duration::from_secs(30), "never loaded");
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(source.reads.load(Ordering::SeqCst), 3);
    assert!(!clipmap.has_given_up(source.target));
}

/// Reads block while the gate is shut; every read is logged.
struct Gated {
    earth: Arc<ProceduralEarth>,
    open: Mutex<bool>,
    opened: Condvar,
    log: Mutex<Vec<NodeId>>,
}

impl Gated {
    fn set(&self, open: bool) {
        *self.open.lock().unwrap() = open;
        self.opened.notify_all();
    }
}

impl NodeSource for Gated {
    fn layout(&self) -> &NodeLayout {
        self.earth.layout()
    }

    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        let mut open = self.open.lock().unwrap();
        while !*open {
            open = self.opened.wait(open).unwrap();
        }
        drop(open);
        self.log.lock().unwrap().push(id);
        self.earth.read_node(id, out)
    }

    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        self.earth.exact_height(x_m, y_m)
    }
}

/// Updates until nothing is missing or in flight; returns the cancelled
/// loads counted on the way.
fn settle(clipmap: &mut Clipmap) -> u32 {
    let (mut cancelled, start) = (0, Instant::now());
    loop {
        let stats = clipmap.update().unwrap();
        cancelled += stats.cancelled;
        if stats.missing == 0 && stats.in_flight == 0 {
            return cancelled;
        }
        assert!(start.elapsed() < Duration::from_secs(30), "not settled: {stats:?}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
fn queued_loads_no_view_wants_are_cancelled_unread() {
    let earth = earth(42);
    let source = Arc::new(Gated {
        earth: earth.clone(),
        open: Mutex::new(true),
        opened: Condvar::new(),
        log: Mutex::new(Vec::new()),
    });
    let config = ClipmapConfig {
        atlas_bytes: None,
        atlas_slots: 1500,
        budget: 50,
        loader: LoaderMode::Thread { queue: 6 },
    };
    let mut clipmap = Clipmap::new(source.clone(), config).unwrap();
    let a = over_ground(&earth, 4e6, 4e6, 50.0);
    let view = clipmap.add_view(VIEW, a).unwrap();
    assert_eq!(settle(&mut clipmap), 0, "nothing to cancel while the view wants it all");

    // Shut the gate, move 3 km: the new nodes are queued, the first read blocks.
    source.set(false);
    clipmap.set_view_position(view, a + DVec3::new(3000.0, 0.0, 0.0)).unwrap();
    let requested = clipmap.update().unwrap().requested;
    assert!(requested >= 4, "{requested} requests queued");
    source.log.lock().unwrap().clear();

    // Fly far away before they are read: none of them is wanted any more.
    let b = over_ground(&earth, 3e7, 3e7, 50.0);
    clipmap.set_view_position(view, b).unwrap();
    let first = clipmap.update().unwrap();
    source.set(true);
    let cancelled = first.cancelled + settle(&mut clipmap);
    let log = source.log.lock().unwrap().clone();
    let stale_reads = log.iter().filter(|&&id| !clipmap.is_wanted(id)).count() as u32;
    assert!(
        stale_reads <= 1,
        "{stale_reads} unwanted nodes were read (only the blocked one may be)"
    );
    assert_eq!(stale_reads + cancelled, requested, "every queued request was read or cancelled");
    check_entries(&clipmap, view).unwrap();
    check_height(&clipmap, view, b.truncate() + DVec2::new(20.0, -15.0)).unwrap();
}
