//! The clipped quadtree of one view (Kühnert 4.5.1, 4.5.3): `levels`
//! layers of `node_count x node_count` entries, each layer a window of nodes
//! of its level centred under the viewer and aligned to that level's node
//! size, addressed toroidally (eq. 4.10) so an entry keeps its place while the
//! window rolls. Each entry names the atlas slot and level of the best
//! resident node covering the entry's node: the node itself, else the finest
//! resident ancestor.

use glam::{DVec2, DVec3};

use super::atlas::NodeAtlas;
use super::ViewConfig;
use crate::node::{NodeId, NodeLayout};

/// One quadtree entry: Kühnert's atlas index (`slot`) and atlas LOD (`atlas_level`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Entry {
    /// The atlas slot of the best resident node for this entry.
    pub slot: u32,
    /// The level of the node in `slot` (coarser than the entry's own level when it fell back).
    pub atlas_level: u8,
}

impl Entry {
    /// The entry of a window node outside the pyramid.
    pub const NONE: Entry = Entry { slot: u32::MAX, atlas_level: u8::MAX };
}

/// Node coordinates beyond which a window may not move (keeps `i64`
/// arithmetic far from overflow for absurd positions).
const COORD_LIMIT: f64 = (1u64 << 52) as f64;

/// One view's lookup structure.
#[derive(Clone, Debug)]
pub struct ClippedQuadtree {
    config: ViewConfig,
    position: DVec3,
    /// Terrain height under the viewer when the frame began (Kühnert 4.5.2).
    ground_m: f64,
    /// Per layer, node coordinates of the window's south-west node.
    origins: Vec<[i64; 2]>,
    /// Per layer, the origin the entries were last refreshed for.
    refreshed: Vec<[i64; 2]>,
    /// `levels * node_count^2` entries, layer-major, toroidal inside a layer.
    entries: Vec<Entry>,
}

impl ClippedQuadtree {
    pub(crate) fn new(config: ViewConfig, layout: &NodeLayout, position: DVec3) -> Self {
        let n = config.node_count as usize;
        let layers = layout.levels as usize;
        let mut tree = ClippedQuadtree {
            config,
            position,
            ground_m: 0.0,
            origins: vec![[0, 0]; layers],
            refreshed: vec![[0, 0]; layers],
            entries: vec![Entry::NONE; layers * n * n],
        };
        tree.recenter(layout);
        tree
    }

    /// The view's window size and distances.
    pub fn config(&self) -> ViewConfig {
        self.config
    }

    /// The viewer position of the last recentre, in metres.
    pub fn position(&self) -> DVec3 {
        self.position
    }

    pub(crate) fn set_position(&mut self, position: DVec3) {
        self.position = position;
    }

    /// The terrain height under the viewer used for this frame's distances.
    pub fn ground_m(&self) -> f64 {
        self.ground_m
    }

    pub(crate) fn set_ground(&mut self, ground_m: f64) {
        self.ground_m = ground_m;
    }

    /// Node coordinates of the south-west node of layer `level`'s window.
    pub fn origin(&self, level: u8) -> [i64; 2] {
        self.origins[level as usize]
    }

    /// Whether node `(x, y)` of level `level` lies in that layer's window.
    pub fn in_window(&self, level: u8, x: i64, y: i64) -> bool {
        let [ox, oy] = self.origins[level as usize];
        let n = self.config.node_count as i64;
        (ox..ox + n).contains(&x) && (oy..oy + n).contains(&y)
    }

    /// The entry for node `(x, y)` of layer `level`, `None` outside the window.
    pub fn entry(&self, level: u8, x: i64, y: i64) -> Option<Entry> {
        self.in_window(level, x, y).then(|| self.entries[self.entry_index(level, x, y)])
    }

    /// Toroidal address (eq. 4.10): the window position modulo `node_count`.
    fn entry_index(&self, level: u8, x: i64, y: i64) -> usize {
        let n = self.config.node_count as i64;
        let (tx, ty) = (x.rem_euclid(n) as usize, y.rem_euclid(n) as usize);
        (level as usize * n as usize + ty) * n as usize + tx
    }

    /// Radius in metres within which layer `level` wants its nodes loaded.
    pub fn load_radius_m(&self, layout: &NodeLayout, level: u8) -> f64 {
        self.config.load_distance * min_side(layout.node_size_m(level))
    }

    /// Radius in metres within which lookups use layer `level` (eq. 4.9).
    pub fn view_radius_m(&self, layout: &NodeLayout, level: u8) -> f64 {
        self.config.view_distance * min_side(layout.node_size_m(level))
    }

    /// Centres every layer's window under the viewer, aligned to the layer's
    /// node size. Entries follow in [`Self::refresh_changes`].
    pub(crate) fn recenter(&mut self, layout: &NodeLayout) {
        let half = self.config.node_count as f64 / 2.0;
        for level in 0..layout.levels {
            let [w, h] = layout.node_size_m(level);
            let corner = |p: f64, side: f64| {
                (p / side + 0.5 - half).floor().clamp(-COORD_LIMIT, COORD_LIMIT) as i64
            };
            self.origins[level as usize] = [corner(self.position.x, w), corner(self.position.y, h)];
        }
    }

    /// Step 1 of the update: calls `want(node, distance_m)` for every node
    /// within its layer's load radius of the viewer, measured in 3D from the
    /// viewer to the nearest point of the node's footprint raised to
    /// [`Self::ground_m`], the height under the viewer (Kühnert 4.5.2). A wanted
    /// node's parent is always wanted too (its footprint is nearer and its
    /// radius twice as large), and every wanted node lies in its window.
    pub(crate) fn collect_wanted(&self, layout: &NodeLayout, mut want: impl FnMut(NodeId, f64)) {
        let position = self.position;
        let dz = self.position.z - self.ground_m;
        for level in 0..layout.levels {
            let radius = self.load_radius_m(layout, level);
            if dz.abs() >= radius {
                continue;
            }
            let size = layout.node_size_m(level);
            let nodes = layout.nodes_at(level);
            let range = |axis: usize, p: f64| {
                let first = ((p - radius) / size[axis]).floor().max(0.0);
                let last = ((p + radius) / size[axis]).floor().min(nodes[axis] as f64 - 1.0);
                (first as i64)..=(last as i64)
            };
            for y in range(1, position.y) {
                for x in range(0, position.x) {
                    let near = nearest_gap(position.truncate(), x, y, size);
                    let distance = (near.length_squared() + dz * dz).sqrt();
                    if distance < radius {
                        debug_assert!(
                            self.in_window(level, x, y),
                            "wanted node outside the window"
                        );
                        want(NodeId::new(level, x as u32, y as u32), distance);
                    }
                }
            }
        }
    }

    /// Points every entry at the best resident node, coarsest layer first
    /// so each entry can fall back on its parent's entry.
    pub(crate) fn refresh_all(&mut self, layout: &NodeLayout, atlas: &NodeAtlas) {
        let n = self.config.node_count as i64;
        for level in (0..layout.levels).rev() {
            let [ox, oy] = self.origins[level as usize];
            self.refresh_nodes(layout, atlas, level, ox..ox + n, oy..oy + n, |_, _| true);
            self.refreshed[level as usize] = self.origins[level as usize];
        }
    }

    /// Step 4 of the update, incrementally: thanks to toroidal addressing
    /// only the nodes that entered a moved window are new, and only entries
    /// inside the footprint of a node inserted into or evicted from the
    /// atlas (`changes`, coarsest first) can name a different node.
    pub(crate) fn refresh_changes(
        &mut self,
        layout: &NodeLayout,
        atlas: &NodeAtlas,
        changes: &[NodeId],
    ) {
        let n = self.config.node_count as i64;
        for level in (0..layout.levels).rev() {
            let [ox, oy] = self.origins[level as usize];
            let [px, py] = self.refreshed[level as usize];
            if [ox, oy] != [px, py] {
                let entered =
                    |x: i64, y: i64| !((px..px + n).contains(&x) && (py..py + n).contains(&y));
                self.refresh_nodes(layout, atlas, level, ox..ox + n, oy..oy + n, entered);
                self.refreshed[level as usize] = [ox, oy];
            }
        }
        debug_assert!(
            changes.windows(2).all(|w| w[0].level >= w[1].level),
            "changes are coarsest first"
        );
        for id in changes {
            for level in (0..=id.level).rev() {
                let shift = id.level - level;
                let (x0, y0) = ((id.x as i64) << shift, (id.y as i64) << shift);
                let [ox, oy] = self.origins[level as usize];
                let xs = x0.max(ox)..(x0 + (1 << shift)).min(ox + n);
                let ys = y0.max(oy)..(y0 + (1 << shift)).min(oy + n);
                self.refresh_nodes(layout, atlas, level, xs, ys, |_, _| true);
            }
        }
    }

    /// Recomputes the entries of the window nodes of layer `level` in the given
    /// ranges for which `pick` says so.
    fn refresh_nodes(
        &mut self,
        layout: &NodeLayout,
        atlas: &NodeAtlas,
        level: u8,
        xs: std::ops::Range<i64>,
        ys: std::ops::Range<i64>,
        pick: impl Fn(i64, i64) -> bool,
    ) {
        let [nx, ny] = layout.nodes_at(level);
        for y in ys {
            for x in xs.clone() {
                if !pick(x, y) {
                    continue;
                }
                let inside = (0..nx as i64).contains(&x) && (0..ny as i64).contains(&y);
                let entry = if inside { self.best_entry(atlas, level, x, y) } else { Entry::NONE };
                let index = self.entry_index(level, x, y);
                self.entries[index] = entry;
            }
        }
    }

    fn best_entry(&self, atlas: &NodeAtlas, level: u8, x: i64, y: i64) -> Entry {
        if let Some(slot) = atlas.slot_of(NodeId::new(level, x as u32, y as u32)) {
            return Entry { slot, atlas_level: level };
        }
        // Not resident: the parent's entry, which lies in the next window
        // up because the windows nest; the root level is always resident.
        let parent = self.entry(level + 1, x / 2, y / 2);
        debug_assert!(parent.is_some_and(|e| e != Entry::NONE), "no fallback for {level}/{x}/{y}");
        parent.unwrap_or(Entry::NONE)
    }
}

/// Offset from `p` to the nearest point of node `(x, y)`'s footprint.
fn nearest_gap(p: DVec2, x: i64, y: i64, size: [f64; 2]) -> DVec2 {
    let gap = |p: f64, k: i64, side: f64| {
        let (lo, hi) = (k as f64 * side, (k + 1) as f64 * side);
        if p < lo {
            lo - p
        } else if p > hi {
            p - hi
        } else {
            0.0
        }
    };
    DVec2::new(gap(p.x, x, size[0]), gap(p.y, y, size[1]))
}

fn min_side(size: [f64; 2]) -> f64 {
    size[0].min(size[1])
}
