//! Once warmed up, a clipmap frame allocates nothing: not in the four-step
//! update, not in the loader (buffers circulate), not in lookups. Counted by
//! a global allocator wrapper; this file holds one test so no other test's
//! allocations are counted.

use std::time::{Duration, Instant};

use glam::DVec3;
use ridgeline::clipmap::{Clipmap, LoaderMode, ViewConfig};
use ridgeline::procedural::ProceduralEarth;
use testkit::clipmap::*;

/// A flight: east at 250 m/s for `frames` frames of 1/60 s, with a map
/// view 6 km above; returns allocations counted after the first `warm`.
fn fly(earth: &ProceduralEarth, clipmap: &mut Clipmap, frames: u32, warm: u32, paced: bool) -> u64 {
    let start = over_ground(earth, 6e6, 6e6, 400.0);
    let view = ViewConfig { node_count: 12, view_distance: 3.0, load_distance: 4.5 };
    let pfd = clipmap.add_view(view, start).unwrap();
    let map = clipmap.add_view(VIEW, start + DVec3::Z * 6000.0).unwrap();
    let mut counted = 0;
    for frame in 0..frames {
        let at = start + DVec3::new(250.0 / 60.0 * frame as f64, 0.0, 0.0);
        let before = testkit::alloc::allocations();
        clipmap.set_view_position(pfd, at).unwrap();
        clipmap.set_view_position(map, at + DVec3::Z * 6000.0).unwrap();
        clipmap.update().unwrap();
        clipmap.height_at(pfd, at.truncate()).unwrap();
        let after = testkit::alloc::allocations();
        if frame >= warm {
            counted += after - before;
        }
        if paced {
            let until = Instant::now() + Duration::from_micros(500);
            while Instant::now() < until {} // no sleeping: a parked thread may allocate its waker
        }
    }
    counted
}

#[test]
fn steady_state_frames_do_not_allocate() {
    let earth = earth(21);
    let mut inline = clipmap(&earth, 2000, 8, LoaderMode::Inline);
    let allocations = fly(&earth, &mut inline, 400, 20, false);
    assert_eq!(allocations, 0, "inline: allocations after warm-up");
    let mut threaded = clipmap(&earth, 2000, 8, LoaderMode::Thread { queue: 8 });
    let allocations = fly(&earth, &mut threaded, 400, 20, true);
    assert_eq!(allocations, 0, "threaded: allocations after warm-up (both threads)");
}
