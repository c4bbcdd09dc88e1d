//! Property tests: random camera walks of several views over the procedural
//! earth, loading inline. After every frame the atlas obeys its budget, LRU
//! and pinning rules, and every lookup inside the view distance answers from
//! a resident node that covers the point, within its error bound.

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use ridgeline::clipmap::{Clipmap, LoaderMode, ViewId};
use ridgeline::node::NodeSource;
use testkit::clipmap::*;

/// One view's move in one frame: a hop (metres east, north, up) or a jump
/// to a fresh place (fractions of the earth, height above ground).
#[derive(Clone, Debug)]
enum Move {
    Hop(f64, f64, f64),
    Jump(f64, f64, f64),
}

fn moves() -> impl Strategy<Value = Move> {
    prop_oneof![
        12 => (-400.0..400.0f64, -400.0..400.0f64, -150.0..150.0f64).prop_map(|(x, y, z)| Move::Hop(x, y, z)),
        1 => (0.0..1.0f64, 0.0..1.0f64, -20.0..6000.0f64).prop_map(|(x, y, z)| Move::Jump(x, y, z)),
    ]
}

fn apply(earth: &ridgeline::procedural::ProceduralEarth, at: DVec3, step: &Move) -> DVec3 {
    let [ex, ey] = earth.layout().extent_m();
    match *step {
        Move::Hop(dx, dy, dz) => at + DVec3::new(dx, dy, dz),
        Move::Jump(fx, fy, agl) => over_ground(earth, fx * ex, fy * ey, agl),
    }
}

/// Points around a viewer: under it, near it, at the edge of each layer's
/// view radius, and far away (all clamped into the data).
fn probe_points(clipmap: &Clipmap, view: ViewId, salt: u64) -> Vec<DVec2> {
    let layout = clipmap.layout();
    let quadtree = clipmap.view(view);
    let at = quadtree.position().truncate();
    let [ex, ey] = layout.extent_m();
    let mut points = vec![at];
    for lod in [0u8, 1, 3, 6, 10, layout.levels - 1] {
        let radius = quadtree.view_radius_m(layout, lod);
        let angle = (salt.wrapping_mul(lod as u64 + 7) % 628) as f64 / 100.0;
        points.push(at + DVec2::from_angle(angle) * radius * 0.97);
        points.push(at + DVec2::from_angle(angle + 2.0) * radius * 0.4);
    }
    points.into_iter().map(|p| DVec2::new(p.x.clamp(0.0, ex), p.y.clamp(0.0, ey))).collect()
}

fn check_views(clipmap: &Clipmap, views: &[ViewId], salt: u64) -> Result<(), String> {
    for &view in views {
        check_entries(clipmap, view)?;
        for point in probe_points(clipmap, view, salt) {
            check_height(clipmap, view, point)?;
            check_lookup(clipmap, view, point)?;
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_walks_keep_the_clipmap_sound(
        slots in prop_oneof![30u32..400, 400u32..1200],
        budget in prop_oneof![1u32..6, 40u32..120],
        starts in proptest::collection::vec((0.0..1.0f64, 0.0..1.0f64, -20.0..3000.0f64), 1..=3),
        walk in proptest::collection::vec(proptest::collection::vec(moves(), 3), 5..40),
        seed in 0u64..4,
    ) {
        let earth = earth(seed);
        let mut clipmap = clipmap(&earth, slots, budget, LoaderMode::Inline);
        let [ex, ey] = earth.layout().extent_m();
        let mut positions: Vec<DVec3> =
            starts.iter().map(|&(fx, fy, agl)| over_ground(&earth, fx * ex, fy * ey, agl)).collect();
        let views: Vec<ViewId> = positions.iter().map(|&p| clipmap.add_view(VIEW, p).unwrap()).collect();
        check_views(&clipmap, &views, 1).map_err(TestCaseError::fail)?;
        for (frame, steps) in walk.iter().enumerate() {
            for ((view, position), step) in views.iter().zip(positions.iter_mut()).zip(steps) {
                *position = apply(&earth, *position, step);
                clipmap.set_view_position(*view, *position).unwrap();
            }
            let before = snapshot(&clipmap);
            let stats = clipmap.update().unwrap();
            prop_assert!(stats.applied <= budget, "{stats:?}");
            prop_assert!(clipmap.atlas().resident_count() <= slots);
            check_frame(&clipmap, &before, &stats).map_err(TestCaseError::fail)?;
            check_views(&clipmap, &views, frame as u64).map_err(TestCaseError::fail)?;
        }
    }
}

/// A still camera converges: every wanted node becomes resident, and then
/// every point inside a layer's load radius answers at that level or finer.
#[test]
fn a_still_camera_converges_to_the_wanted_levels() {
    let earth = earth(3);
    let mut clipmap = clipmap(&earth, 1500, 8, LoaderMode::Inline);
    let position = over_ground(&earth, 1.23e7, 3.45e6, 120.0);
    let view = clipmap.add_view(VIEW, position).unwrap();
    let mut last = None;
    for _ in 0..200 {
        let stats = clipmap.update().unwrap();
        last = Some(stats);
        if stats.missing == 0 {
            break;
        }
    }
    let stats = last.unwrap();
    assert_eq!(stats.missing, 0, "{stats:?}");
    assert!(stats.wanted > 40, "{stats:?}");
    let layout = *clipmap.layout();
    let quadtree = clipmap.view(view);
    let ground = clipmap.height_at(view, position.truncate()).unwrap().height_m as f64;
    let dz = position.z - ground;
    for lod in 0..layout.levels {
        let radius = quadtree.load_radius_m(&layout, lod);
        if dz.abs() >= radius {
            continue;
        }
        let reach = (radius * radius - dz * dz).sqrt() * 0.99;
        for angle in [0.0, 1.0, 2.5, 4.0, 5.5] {
            let point = position.truncate() + DVec2::from_angle(angle) * reach;
            if layout.locate(0, point.x, point.y).is_none() {
                continue; // beyond the edge of the data
            }
            let got = check_height(&clipmap, view, point).unwrap();
            assert!(got <= lod, "at {reach:.0} m the answer is level {got}, want <= {lod}");
        }
    }
    // Nothing left to do: another frame changes nothing.
    let before = snapshot(&clipmap);
    let again = clipmap.update().unwrap();
    assert_eq!((again.applied, again.missing), (0, 0));
    let strip =
        |s: Snapshot| s.into_iter().map(|(node, state, _)| (node, state)).collect::<Vec<_>>();
    assert_eq!(strip(before), strip(snapshot(&clipmap)));
}

/// Too few slots for what the views want: requests stop at what the atlas
/// can take, nothing wanted is evicted, and lookups still answer.
#[test]
fn a_small_atlas_falls_back_without_thrashing() {
    let earth = earth(5);
    let mut clipmap = clipmap(&earth, 24, 4, LoaderMode::Inline);
    let a = clipmap.add_view(VIEW, over_ground(&earth, 2e6, 2e6, 50.0)).unwrap();
    let b = clipmap.add_view(VIEW, over_ground(&earth, 3e7, 1e7, 50.0)).unwrap();
    for frame in 0..40 {
        let before = snapshot(&clipmap);
        let stats = clipmap.update().unwrap();
        check_frame(&clipmap, &before, &stats).unwrap();
        assert_eq!(stats.evicted, 0, "frame {frame}: every slot holds a wanted node");
        check_views(&clipmap, &[a, b], frame).unwrap();
    }
    assert_eq!(clipmap.atlas().resident_count(), 24);
    assert!(clipmap.update().unwrap().missing > 0);
}

/// Walking away leaves the old nodes cached: coming back finds them
/// resident without loading, and reuse takes the least recently used.
#[test]
fn unused_nodes_stay_cached_and_are_reused_oldest_first() {
    let earth = earth(6);
    let mut clipmap = clipmap(&earth, 1500, 16, LoaderMode::Inline);
    let home = over_ground(&earth, 5e6, 5e6, 30.0);
    let view = clipmap.add_view(VIEW, home).unwrap();
    for _ in 0..100 {
        if clipmap.update().unwrap().missing == 0 {
            break;
        }
    }
    let home_nodes: Vec<_> =
        (0..1500).filter_map(|s| clipmap.atlas().node_in(s)).filter(|&id| id.level < 3).collect();
    assert!(!home_nodes.is_empty());
    // A short hop: home's finest nodes become unused but stay resident.
    clipmap.set_view_position(view, home + DVec3::new(3000.0, 0.0, 0.0)).unwrap();
    for _ in 0..3 {
        let before = snapshot(&clipmap);
        let stats = clipmap.update().unwrap();
        check_frame(&clipmap, &before, &stats).unwrap();
    }
    let cached = home_nodes.iter().filter(|&&id| clipmap.atlas().slot_of(id).is_some()).count();
    assert!(cached > 0, "some of home's nodes are still cached");
    let lru: Vec<u32> = clipmap.atlas().lru().collect();
    assert!(lru
        .windows(2)
        .all(|w| clipmap.atlas().last_used(w[0]) <= clipmap.atlas().last_used(w[1])));
    clipmap.set_view_position(view, home).unwrap();
    let stats = clipmap.update().unwrap();
    assert!(
        stats.wanted - stats.missing >= cached as u32,
        "cached nodes count as resident at once: {stats:?}"
    );
}

#[test]
fn refuses_bad_configurations_and_positions() {
    use ridgeline::clipmap::{ClipmapConfig, ClipmapError, LookupError, ViewConfig};
    let earth = earth(0);
    let make = |slots, budget, loader| {
        Clipmap::new(
            earth.clone(),
            ClipmapConfig { atlas_bytes: None, atlas_slots: slots, budget, loader },
        )
    };
    assert!(matches!(make(1, 1, LoaderMode::Inline), Err(ClipmapError::TooFewSlots { .. })));
    assert!(matches!(make(8, 0, LoaderMode::Inline), Err(ClipmapError::ZeroBudget)));
    assert!(matches!(make(8, 1, LoaderMode::Thread { queue: 0 }), Err(ClipmapError::ZeroQueue)));
    let mut clipmap = make(8, 1, LoaderMode::Inline).unwrap();
    let bad_views = [
        ViewConfig { node_count: 3, ..VIEW },
        ViewConfig { load_distance: 2.6, ..VIEW },
        ViewConfig { view_distance: 3.0, ..VIEW },
        ViewConfig { view_distance: f64::NAN, ..VIEW },
    ];
    for config in bad_views {
        assert!(clipmap.add_view(config, DVec3::ZERO).is_err(), "{config:?}");
    }
    assert!(matches!(
        clipmap.add_view(VIEW, DVec3::new(f64::NAN, 0.0, 0.0)),
        Err(ClipmapError::Position(_))
    ));
    let view = clipmap.add_view(VIEW, DVec3::new(1e200, -1e200, 1e9)).unwrap();
    clipmap.update().unwrap();
    assert_eq!(
        clipmap.height_at(view, DVec2::new(-1.0, 0.0)),
        Err(LookupError::OutsideData(-1.0, 0.0))
    );
    assert!(matches!(
        clipmap.height_at(view, DVec2::new(10.0, 10.0)),
        Err(LookupError::OutsideView(..))
    ));
    assert!(clipmap.set_view_position(view, DVec3::new(0.0, f64::INFINITY, 0.0)).is_err());
    clipmap.set_view_position(view, DVec3::new(10.0, 10.0, 0.0)).unwrap();
    clipmap.update().unwrap();
    check_height(&clipmap, view, DVec2::new(10.0, 10.0)).unwrap();
}
