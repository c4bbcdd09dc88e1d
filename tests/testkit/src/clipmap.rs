//! Helpers shared by the clipmap tests: a small-node procedural earth and
//! checks of a frame's effect on the atlas and of lookups, each returning
//! what went wrong.

use std::sync::Arc;

use glam::{DVec2, DVec3};
use ridgeline::clipmap::{
    Clipmap, ClipmapConfig, Entry, LoaderMode, SlotState, ClipmapStats, ViewConfig, ViewId,
};
use ridgeline::node::{NodeId, NodeSource};
use ridgeline::procedural::{EarthParams, ProceduralEarth};

/// Nodes of 16 cells, 2^24 samples a side, 21 levels.
pub fn earth(seed: u64) -> Arc<ProceduralEarth> {
    Arc::new(ProceduralEarth::new(EarthParams::earth(16, seed)).unwrap())
}

pub const VIEW: ViewConfig = ViewConfig { node_count: 8, view_distance: 2.0, load_distance: 2.5 };

pub fn clipmap(
    earth: &Arc<ProceduralEarth>,
    slots: u32,
    budget: u32,
    loader: LoaderMode,
) -> Clipmap {
    let config = ClipmapConfig { atlas_bytes: None, atlas_slots: slots, budget, loader };
    Clipmap::new(earth.clone(), config).unwrap()
}

/// A viewer `agl` metres above the terrain at `(x, y)`.
pub fn over_ground(earth: &ProceduralEarth, x: f64, y: f64, agl: f64) -> DVec3 {
    let [ex, ey] = earth.layout().extent_m();
    let ground = earth.exact_height(x.clamp(0.0, ex), y.clamp(0.0, ey)).unwrap() as f64;
    DVec3::new(x, y, ground + agl)
}

/// The atlas before a frame: per slot, its node, state and last use.
pub type Snapshot = Vec<(Option<NodeId>, SlotState, u64)>;

pub fn snapshot(clipmap: &Clipmap) -> Snapshot {
    let atlas = clipmap.atlas();
    (0..atlas.slot_count())
        .map(|s| (atlas.node_in(s), atlas.state(s), atlas.last_used(s)))
        .collect()
}

/// What one update may have done to the atlas: at most `budget` nodes
/// arrived, all wanted; only unused nodes lost their slots, empty slots went
/// first and the least recently used went before the others; the invariants
/// hold and the root level stays pinned.
pub fn check_frame(
    clipmap: &Clipmap,
    before: &Snapshot,
    stats: &ClipmapStats,
) -> Result<(), String> {
    let atlas = clipmap.atlas();
    atlas.check()?;
    let after = snapshot(clipmap);
    let arrived: Vec<usize> = (0..after.len()).filter(|&s| after[s].0 != before[s].0).collect();
    if arrived.len() as u32 > clipmap.config().budget || stats.applied != arrived.len() as u32 {
        return Err(format!(
            "{} nodes arrived, stats say {}, budget {}",
            arrived.len(),
            stats.applied,
            clipmap.config().budget
        ));
    }
    let evicted: Vec<usize> = arrived.iter().copied().filter(|&s| before[s].0.is_some()).collect();
    if !evicted.is_empty() && after.iter().any(|s| s.1 == SlotState::Empty) {
        return Err("a node was evicted while a slot stayed empty".into());
    }
    for &slot in &arrived {
        let id = after[slot].0.unwrap();
        if !clipmap.is_wanted(id) {
            return Err(format!("{id:?} arrived in slot {slot} but nobody wants it"));
        }
    }
    for &slot in &evicted {
        let (old, state, last_used) = before[slot];
        if state == SlotState::Pinned || clipmap.is_wanted(old.unwrap()) {
            return Err(format!(
                "evicted {old:?} from slot {slot}: {state:?}, wanted {}",
                clipmap.is_wanted(old.unwrap())
            ));
        }
        // Every unused node that kept its slot was used no earlier.
        let older = (0..after.len()).find(|&s| {
            after[s].1 == SlotState::Unused && after[s].0 == before[s].0 && before[s].2 < last_used
        });
        if let Some(s) = older {
            return Err(format!(
                "slot {slot} (last used {last_used}) reused before slot {s} (last used {})",
                before[s].2
            ));
        }
    }
    check_root(clipmap)
}

pub fn check_root(clipmap: &Clipmap) -> Result<(), String> {
    let layout = clipmap.layout();
    let top = layout.levels - 1;
    let [rx, ry] = layout.nodes_at(top);
    for (x, y) in (0..ry).flat_map(|y| (0..rx).map(move |x| (x, y))) {
        let slot = clipmap.atlas().slot_of(NodeId::new(top, x, y)).ok_or("a root node is gone")?;
        if clipmap.atlas().state(slot) != SlotState::Pinned {
            return Err("a root node is not pinned".into());
        }
    }
    Ok(())
}

/// Whether `point` lies in the footprint of `id` (edges included).
pub fn covers(clipmap: &Clipmap, id: NodeId, point: DVec2) -> bool {
    let size = clipmap.layout().node_size_m(id.level);
    let inside = |p: f64, k: u32, side: f64| {
        p >= k as f64 * side - 1e-6 && p <= (k + 1) as f64 * side + 1e-6
    };
    inside(point.x, id.x, size[0]) && inside(point.y, id.y, size[1])
}

/// `height_at` answers at `point` from a resident node covering it, the
/// finest resident one from the finest layer whose window holds the point,
/// within its error bound of the exact height; the returned level is the
/// answering node's.
pub fn check_height(clipmap: &Clipmap, view: ViewId, point: DVec2) -> Result<u8, String> {
    let sample = clipmap.height_at(view, point).map_err(|e| format!("height_at {point}: {e}"))?;
    let node = sample.node;
    let slot =
        clipmap.atlas().slot_of(node).ok_or(format!("{node:?} answered but is not resident"))?;
    if clipmap.atlas().state(slot) == SlotState::Empty || !covers(clipmap, node, point) {
        return Err(format!("{node:?} in slot {slot} does not cover {point}"));
    }
    let layout = clipmap.layout();
    let quadtree = clipmap.view(view);
    let first_layer = (0..layout.levels)
        .find(|&l| {
            let id = layout.locate(l, point.x, point.y).unwrap().id;
            quadtree.in_window(l, id.x as i64, id.y as i64)
        })
        .unwrap();
    for level in first_layer..node.level {
        let id = layout.locate(level, point.x, point.y).unwrap().id;
        if clipmap.atlas().slot_of(id).is_some() {
            return Err(format!("answered from {node:?} though {id:?} is resident"));
        }
    }
    let exact = clipmap.exact_height(point).map_err(|e| e.to_string())?;
    if (sample.height_m - exact).abs() > sample.error_bound_m + 0.01 {
        return Err(format!(
            "{point}: {} from {node:?} vs exact {exact}, bound {}",
            sample.height_m, sample.error_bound_m
        ));
    }
    Ok(node.level)
}

/// The Kühnert lookup at the distance-dependent layer answers from a
/// resident node at that level or coarser covering the point.
pub fn check_lookup(clipmap: &Clipmap, view: ViewId, point: DVec2) -> Result<(), String> {
    let level = clipmap.quadtree_level(view, point);
    let found =
        clipmap.lookup(view, point, level).map_err(|e| format!("lookup {point} at {level}: {e}"))?;
    if clipmap.atlas().node_in(found.slot) != Some(found.node) || found.node.level < level {
        return Err(format!("lookup at {level} gave {found:?}"));
    }
    if !covers(clipmap, found.node, point) || !(0.0..=1.0).contains(&found.atlas_coords.x) {
        return Err(format!("lookup gave {found:?} for {point}"));
    }
    Ok(())
}

/// Every entry of every layer of the view names the finest resident node
/// at its node's level or above (recomputed here from scratch), or nothing
/// outside the pyramid.
pub fn check_entries(clipmap: &Clipmap, view: ViewId) -> Result<(), String> {
    let layout = clipmap.layout();
    let quadtree = clipmap.view(view);
    let n = quadtree.config().node_count as i64;
    for level in 0..layout.levels {
        let [ox, oy] = quadtree.origin(level);
        let [nx, ny] = layout.nodes_at(level);
        for (x, y) in (oy..oy + n).flat_map(|y| (ox..ox + n).map(move |x| (x, y))) {
            let inside = (0..nx as i64).contains(&x) && (0..ny as i64).contains(&y);
            let expected = if inside {
                let mut id = NodeId::new(level, x as u32, y as u32);
                loop {
                    if let Some(slot) = clipmap.atlas().slot_of(id) {
                        break Entry { slot, atlas_level: id.level };
                    }
                    id = id
                        .parent()
                        .filter(|p| p.level < layout.levels)
                        .ok_or("no resident ancestor")?;
                }
            } else {
                Entry::NONE
            };
            let got = quadtree.entry(level, x, y).ok_or("a window node has no entry")?;
            if got != expected {
                return Err(format!(
                    "layer {level} node ({x}, {y}): entry {got:?}, expected {expected:?}"
                ));
            }
        }
    }
    Ok(())
}
