//! The chunked clipmap (Kühnert 4.5): pages the node pyramid of any
//! [`NodeSource`] into a [`NodeAtlas`] of fixed size shared by several views,
//! each with its own [`ClippedQuadtree`], and answers height queries from the
//! best resident data.
//!
//! Every frame [`Clipmap::update`] runs the four steps of Kühnert 4.5.7:
//! 1. each view centres its quadtree under the viewer and lists the nodes
//!    within its `load_distance` (scaled by each level's node size);
//! 2. the union over views is compared with the atlas: resident nodes are
//!    marked used, the rest become unused (kept as a cache, reused least
//!    recently used first), and missing ones are requested coarsest first,
//!    then nearest first, never more than the atlas can take;
//! 3. at most `budget` finished loads are copied into atlas slots;
//! 4. each view's entries are re-pointed at the best resident node.
//!
//! The root level is loaded when the clipmap is built and pinned, so every
//! lookup inside the data answers, from the finest resident ancestor when the
//! node it would like is not there yet.
//!
//! A node whose read fails is never put in the atlas. An I/O error is
//! retried with backoff; a node whose bytes fail their check, or that stays
//! unreadable, is reported once on stderr (node and file), counted
//! ([`Clipmap::corrupt_nodes`], [`Clipmap::unreadable_nodes`]) and never
//! requested again, so the views answer from its finest resident ancestor
//! for good. Queued loads no view wants any more are cancelled. See the
//! loader module for the numbers.

mod atlas;
mod earth_wanted;
mod hash;
mod loader;
mod lru;
mod quadtree;

use std::sync::Arc;

use glam::{DVec2, DVec3};

pub use atlas::{NodeAtlas, SlotState};
pub use loader::{LoaderMode, READ_ATTEMPTS, RETRY_FIRST_DELAY_FRAMES};
pub use quadtree::{ClippedQuadtree, Entry};

use crate::earth::GridPlacement;
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use earth_wanted::EarthMetric;
use hash::{node_map, NodeMap};
use loader::{Loaded, Loader, Outcome, Verdict};

/// Settings shared by all views.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipmapConfig {
    /// Slots in the node atlas; must exceed the root level's node count.
    pub atlas_slots: u32,
    /// The most bytes the atlas's nodes may take (a memory budget), each
    /// counted at its own size; `None`: counted in slots only.
    pub atlas_bytes: Option<u64>,
    /// Most finished loads copied into the atlas per frame.
    pub budget: u32,
    /// Whether nodes are read inline or on a loader thread.
    pub loader: LoaderMode,
}

/// Settings of one view's clipped quadtree. Distances are in node sizes of
/// each level (Kühnert's `view_distance` and `load_distance` in multiples of
/// the leaf node size, scaled by the level).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewConfig {
    /// Entries per side of each layer (`node_count`), 4 to 256.
    pub node_count: u32,
    /// Lookups use layer `l` up to `view_distance` node sizes of level `l`.
    pub view_distance: f64,
    /// Nodes of level `l` are loaded up to `load_distance` node sizes away;
    /// `view_distance <= load_distance <= (node_count - 3) / 2`, the largest
    /// radius whose nodes always fit the window centred under the viewer.
    pub load_distance: f64,
}

impl ViewConfig {
    /// The largest `load_distance` a window of `node_count` nodes supports.
    pub fn max_load_distance(node_count: u32) -> f64 {
        (node_count as f64 - 3.0) / 2.0
    }
}

/// Names one view of a [`Clipmap`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ViewId(usize);

/// Why a clipmap or a view cannot be built or updated.
#[derive(Debug, thiserror::Error)]
pub enum ClipmapError {
    /// The source's layout has no levels.
    #[error("clipmap: the node source has no levels")]
    NoLevels,
    /// The atlas is too small for the root level plus one node.
    #[error("clipmap: {slots} atlas slots cannot hold the {roots} root nodes and one more")]
    TooFewSlots {
        /// Slots asked for.
        slots: u32,
        /// Nodes at the root level.
        roots: u64,
    },
    /// `budget` is zero.
    #[error("clipmap: the load budget must be at least one node per frame")]
    ZeroBudget,
    /// The loader thread's queue length is zero.
    #[error("clipmap: the loader queue must hold at least one request")]
    ZeroQueue,
    /// `node_count` is outside 4..=256.
    #[error("clipmap: node_count {0} must be between 4 and 256")]
    NodeCount(u32),
    /// The view and load distances are not ordered or too large for the window.
    #[error("clipmap: need 0 < view_distance {view} <= load_distance {load} <= {max} for node_count {node_count}")]
    Distances {
        /// The `view_distance` asked for.
        view: f64,
        /// The `load_distance` asked for.
        load: f64,
        /// The largest `load_distance` the window supports.
        max: f64,
        /// The window's entries per side.
        node_count: u32,
    },
    /// The viewer's position has a NaN or infinite coordinate.
    #[error("clipmap: viewer position {0} is not finite")]
    Position(DVec3),
    /// A root-level node could not be read.
    #[error("clipmap: loading the root level: {0}")]
    Root(NodeError),
    /// The loader thread could not be started.
    #[error("clipmap: starting the loader thread: {0}")]
    Spawn(std::io::Error),
    /// The loader thread has gone away.
    #[error("clipmap: the loader thread stopped (the node source panicked)")]
    LoaderStopped,
}

/// Why a lookup has no answer.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum LookupError {
    /// The point (metres east, north) lies outside the pyramid's extent.
    #[error("point ({0}, {1}) is outside the data")]
    OutsideData(f64, f64),
    /// The point (metres east, north) lies outside the view's window.
    #[error("point ({0}, {1}) is outside the view's quadtree")]
    OutsideView(f64, f64),
}

/// Where a lookup found its data (Kühnert eq. 4.10, 4.11).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeLookup {
    /// The atlas slot holding `node`.
    pub slot: u32,
    /// The node whose posts answer the lookup.
    pub node: NodeId,
    /// Position inside the node, 0..=1 east and north (eq. 4.11).
    pub atlas_coords: DVec2,
}

/// A height from the clipmap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightSample {
    /// The surface height at the point, bilinear in the answering node.
    pub height_m: f32,
    /// The answering node's `delta`: the full-resolution surface is within
    /// this many metres of `height_m`.
    pub error_bound_m: f32,
    /// The node that answered.
    pub node: NodeId,
}

/// What one [`Clipmap::update`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct ClipmapStats {
    /// The clipmap frame this update made (1 for the first update).
    pub frame: u64,
    /// Nodes wanted by at least one view.
    pub wanted: u32,
    /// Wanted nodes not resident after step 2.
    pub missing: u32,
    /// Requests queued for the loader thread this frame (0 when inline).
    pub requested: u32,
    /// Loads copied into the atlas this frame (at most the budget).
    pub applied: u32,
    /// Unused nodes whose slots those loads took.
    pub evicted: u32,
    /// Finished loads dropped: no longer wanted, or no slot free.
    pub discarded: u32,
    /// Loads that failed this frame (see [`Clipmap::last_load_error`]);
    /// an I/O error is retried later, any other failure gives the node up.
    pub failed: u32,
    /// Nodes given up this frame: damaged, refused, or unreadable after
    /// [`READ_ATTEMPTS`] reads. Each is reported once and stays missing.
    pub given_up: u32,
    /// Queued loads the loader skipped this frame because no view wanted
    /// their node any more (0 when inline).
    pub cancelled: u32,
    /// Requests still with the loader thread after the frame.
    pub in_flight: u32,
    /// Missing nodes not requested because the atlas's byte budget has no
    /// room for them, even by evicting every unused node: the views draw
    /// their ancestors (coarser, never holes).
    pub over_budget: u32,
}

/// A node not resident but wanted, with its priority.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    id: NodeId,
    distance_m: f64,
}

/// The chunked clipmap over one node source.
pub struct Clipmap {
    source: Arc<dyn NodeSource>,
    layout: NodeLayout,
    config: ClipmapConfig,
    atlas: NodeAtlas,
    views: Vec<ClippedQuadtree>,
    loader: Loader,
    /// This frame's union of wanted nodes, with the nearest view's distance.
    wanted: NodeMap<f64>,
    candidates: Vec<Candidate>,
    last_error: Option<NodeError>,
    /// Nodes given up because their bytes failed their check.
    corrupt_nodes: u64,
    /// Nodes given up after [`READ_ATTEMPTS`] reads failed with I/O errors.
    unreadable_nodes: u64,
    frame: u64,
    /// Distances on the ellipsoid, for a grid drawn on the earth
    /// ([`Self::set_earth`]); `None`: chart distances.
    earth: Option<EarthMetric>,
    /// Chart metres in one turn of longitude, when the grid wraps: nodes
    /// across its seam are wanted too, and views and lookups are brought
    /// into the grid's turn.
    wrap_m: Option<f64>,
}

impl Clipmap {
    /// Builds the atlas, loads and pins the root level, starts the loader.
    pub fn new(source: Arc<dyn NodeSource>, config: ClipmapConfig) -> Result<Self, ClipmapError> {
        let layout = *source.layout();
        let top = layout.levels.checked_sub(1).ok_or(ClipmapError::NoLevels)?;
        let [rx, ry] = layout.nodes_at(top);
        let roots = rx as u64 * ry as u64;
        if (config.atlas_slots as u64) <= roots {
            return Err(ClipmapError::TooFewSlots { slots: config.atlas_slots, roots });
        }
        if config.budget == 0 {
            return Err(ClipmapError::ZeroBudget);
        }
        if config.loader == (LoaderMode::Thread { queue: 0 }) {
            return Err(ClipmapError::ZeroQueue);
        }
        let changes = 2 * config.budget as usize + roots as usize;
        let mut atlas = NodeAtlas::new(config.atlas_slots, &layout, changes, config.atlas_bytes);
        let mut buffer = NodeData::with_capacity(&layout);
        for y in 0..ry {
            for x in 0..rx {
                let id = NodeId::new(top, x, y);
                source.read_node(id, &mut buffer).map_err(ClipmapError::Root)?;
                atlas.insert(id, &mut buffer, SlotState::Pinned, 0).expect("slots were counted");
            }
        }
        atlas.clear_changes(); // no view yet; each new view refreshes fully
        let fit = config.atlas_bytes.is_some();
        let loader =
            Loader::new(source.clone(), config.loader, fit).map_err(ClipmapError::Spawn)?;
        Ok(Clipmap {
            source,
            layout,
            config,
            atlas,
            views: Vec::new(),
            loader,
            wanted: node_map(0),
            candidates: Vec::new(),
            last_error: None,
            corrupt_nodes: 0,
            unreadable_nodes: 0,
            earth: None,
            wrap_m: None,
            frame: 0,
        })
    }

    /// Adds a view at `position` (metres: x east, y north, z altitude),
    /// immediately answering lookups from whatever is resident.
    pub fn add_view(
        &mut self,
        config: ViewConfig,
        position: DVec3,
    ) -> Result<ViewId, ClipmapError> {
        validate_view(config)?;
        check_position(position)?;
        let mut view = ClippedQuadtree::new(config, &self.layout, position);
        view.refresh_all(&self.layout, &self.atlas);
        self.views.push(view);
        let id = ViewId(self.views.len() - 1);
        let ground = self.ground_under(id);
        self.views[id.0].set_ground(ground);
        self.reserve_wanted();
        Ok(id)
    }

    /// Moves a view; takes effect at the next [`Clipmap::update`]. Over a
    /// grid that wraps, the position is brought into the grid's turn (a
    /// path across the seam runs on past it in the chart), so the view's
    /// windows stay over the data and the height under it is found.
    pub fn set_view_position(&mut self, view: ViewId, position: DVec3) -> Result<(), ClipmapError> {
        check_position(position)?;
        let p = self.wrapped(position.truncate());
        self.views[view.0].set_position(p.extend(position.z));
        Ok(())
    }

    /// Measures the wanted set on the ellipsoid where the grid `placement`
    /// places is drawn on it (a geographic grid or one of a known
    /// projection; `None` or a grid placed by assumption: in the chart). A grid whose columns span 360 degrees wraps: the nodes
    /// across its seam are wanted next to the viewer, and views and lookups
    /// are brought into its turn.
    pub fn set_earth(&mut self, placement: Option<GridPlacement>) {
        self.earth = placement.and_then(EarthMetric::new);
        let spacing_m = self.layout.spacing_m[0];
        let period = self.earth.and_then(|e| e.period_posts()).map(|n| n * spacing_m);
        self.wrap_m = period.filter(|p| p.is_finite() && *p > 0.0);
        self.reserve_wanted();
    }

    /// `point` brought into the grid's turn when it wraps.
    fn wrapped(&self, point: DVec2) -> DVec2 {
        match self.wrap_m {
            Some(period) => DVec2::new(point.x.rem_euclid(period), point.y),
            None => point,
        }
    }

    /// Room for every view's largest wanted set, so frames never allocate
    /// (three times that across a seam: the view and its two shifts).
    fn reserve_wanted(&mut self) {
        let shifts = if self.wrap_m.is_some() { 3 } else { 1 };
        let per_view = |v: &ClippedQuadtree| {
            let across = (2.0 * v.config().load_distance).ceil() as usize + 2;
            shifts * across * across * self.layout.levels as usize
        };
        let most: usize = self.views.iter().map(per_view).sum();
        self.wanted.reserve(most.saturating_sub(self.wanted.len()));
        self.candidates.reserve(most.saturating_sub(self.candidates.len()));
    }

    /// One frame of the four-step update (see the module docs).
    pub fn update(&mut self) -> Result<ClipmapStats, ClipmapError> {
        self.frame += 1;
        let mut stats = ClipmapStats { frame: self.frame, ..ClipmapStats::default() };
        self.collect_wanted();
        let wanted = &self.wanted;
        self.loader.cancel_unwanted(|id| wanted.contains_key(&id));
        self.compare_with_atlas(&mut stats);
        self.load(&mut stats)?;
        self.atlas.sort_changes();
        for view in &mut self.views {
            view.refresh_changes(&self.layout, &self.atlas, self.atlas.changes());
        }
        self.atlas.clear_changes();
        stats.in_flight = self.loader.in_flight();
        debug_assert_eq!(self.atlas.check(), Ok(()));
        Ok(stats)
    }

    /// Step 1: recentres every view and gathers the union of wanted nodes.
    fn collect_wanted(&mut self) {
        self.wanted.clear();
        for index in 0..self.views.len() {
            let ground = self.ground_under(ViewId(index));
            let view = &mut self.views[index];
            view.set_ground(ground);
            view.recenter(&self.layout);
            let wanted = &mut self.wanted;
            let source = &self.source;
            let mut want = |id: NodeId, distance: f64| {
                // An absent node means no finer data here: its ancestor serves.
                if source.has_node(id) {
                    wanted.entry(id).and_modify(|d| *d = d.min(distance)).or_insert(distance);
                }
            };
            match &self.earth {
                Some(earth) => earth.collect(view, &self.layout, &mut want),
                None => view.collect_wanted(&self.layout, &mut want),
            }
        }
    }

    /// The terrain height under a view from its current entries (Kühnert
    /// 4.5.2), at the nearest point of the data.
    fn ground_under(&self, view: ViewId) -> f64 {
        let p = self.views[view.0].position();
        let [ex, ey] = self.layout.extent_m();
        let (x, y) = (p.x.clamp(0.0, ex), p.y.clamp(0.0, ey));
        let height = self.height_at(view, DVec2::new(x, y)).map_or(0.0, |s| s.height_m as f64);
        // No data under the view: sea level, as far as distances go.
        if height.is_finite() {
            height
        } else {
            0.0
        }
    }

    /// Step 2: marks resident wanted nodes used, releases the rest, lists
    /// the missing ones by priority.
    fn compare_with_atlas(&mut self, stats: &mut ClipmapStats) {
        self.candidates.clear();
        stats.wanted = self.wanted.len() as u32;
        if let Some(budget) = self.atlas.byte_budget() {
            return self.compare_within_bytes(budget, stats);
        }
        for (&id, &distance_m) in &self.wanted {
            match self.atlas.slot_of(id) {
                Some(slot) => self.atlas.mark_used(slot, self.frame),
                None => {
                    stats.missing += 1;
                    if self.loader.may_request(id, self.frame) {
                        self.candidates.push(Candidate { id, distance_m });
                    }
                }
            }
        }
        self.atlas.release_unused(self.frame);
        // Coarsest first (they are everyone's fallback), then nearest; the
        // id breaks ties so the order never depends on the hash map.
        self.candidates.sort_unstable_by(|a, b| {
            (b.id.level.cmp(&a.id.level))
                .then(a.distance_m.total_cmp(&b.distance_m))
                .then(a.id.cmp(&b.id))
        });
    }

    /// Step 2 with a byte budget: the wanted nodes in order of the error
    /// their absence would draw (their size over their distance: a missing
    /// node's tiles fall back to its parent, whose error is about twice
    /// its own), kept while they fit `budget` bytes beside the pinned
    /// nodes. Resident ones kept are marked used; those past the budget
    /// are not, so they become unused and are evicted first; missing ones
    /// kept become candidates, the others are counted as over budget.
    /// Coarsest-first, as without a budget, would spend the budget on far
    /// coarse nodes and leave out the finest under the camera.
    fn compare_within_bytes(&mut self, budget: u64, stats: &mut ClipmapStats) {
        let layout = self.layout;
        let wanted = self.wanted.iter().map(|(&id, &distance_m)| Candidate { id, distance_m });
        self.candidates.extend(wanted);
        let priority = |c: &Candidate| layout.span(c.id.level) as f64 / c.distance_m.max(1.0);
        self.candidates
            .sort_unstable_by(|a, b| priority(b).total_cmp(&priority(a)).then(a.id.cmp(&b.id)));
        let mut left = budget.saturating_sub(self.atlas.pinned_bytes());
        let mut kept = 0;
        let mut full = false;
        for index in 0..self.candidates.len() {
            let candidate = self.candidates[index];
            let slot = self.atlas.slot_of(candidate.id);
            if slot.is_none() {
                stats.missing += 1;
            }
            if full {
                stats.over_budget += slot.is_none() as u32;
                continue;
            }
            let bytes = match slot {
                Some(slot) if self.atlas.state(slot) == SlotState::Pinned => 0,
                Some(slot) => self.atlas.bytes_in(slot),
                None => self.source.node_bytes_of(candidate.id),
            };
            if bytes > left {
                // Priority order: what does not fit holds back the rest.
                full = true;
                stats.over_budget += slot.is_none() as u32;
                continue;
            }
            left -= bytes;
            match slot {
                Some(slot) => self.atlas.mark_used(slot, self.frame),
                None if self.loader.may_request(candidate.id, self.frame) => {
                    self.candidates[kept] = candidate;
                    kept += 1;
                }
                None => {}
            }
        }
        self.candidates.truncate(kept);
        self.atlas.release_unused(self.frame);
    }

    /// Steps 2 (requests) and 3: loads missing nodes, at most as many as
    /// the atlas can take (in slots, and in bytes with a budget) and, per
    /// frame, at most `budget` applied.
    fn load(&mut self, stats: &mut ClipmapStats) -> Result<(), ClipmapError> {
        let room = self.atlas.available().saturating_sub(self.loader.in_flight()) as usize;
        let count = self.fitting(room);
        if self.loader.is_threaded() {
            for index in 0..count {
                if !self.loader.request(self.candidates[index].id) {
                    break;
                }
                stats.requested += 1;
            }
            while stats.applied < self.config.budget {
                match self.loader.try_finished() {
                    Ok(Some(loaded)) => self.apply(loaded, stats),
                    Ok(None) => break,
                    Err(_) => return Err(ClipmapError::LoaderStopped),
                }
            }
        } else {
            for index in 0..count.min(self.config.budget as usize) {
                let loaded = self.loader.load_now(self.candidates[index].id);
                self.apply(loaded, stats);
            }
        }
        Ok(())
    }

    /// How many of the candidates, in priority order, to request: at most
    /// `room` slots, and with a byte budget as many as its room holds once
    /// the loads under way arrive (each counted at
    /// [`NodeSource::node_bytes_of`]).
    fn fitting(&self, room: usize) -> usize {
        let count = room.min(self.candidates.len());
        let Some(bytes) = self.atlas.byte_room() else { return count };
        let source = self.source.as_ref();
        let coming: u64 = self.loader.in_flight_ids().map(|id| source.node_bytes_of(id)).sum();
        let mut left = bytes.saturating_sub(coming);
        for (index, candidate) in self.candidates[..count].iter().enumerate() {
            let need = source.node_bytes_of(candidate.id);
            if need > left {
                // Priority order: a node that does not fit (until unused
                // ones are evicted or loads arrive) holds back the rest.
                return index;
            }
            left -= need;
        }
        count
    }

    /// Copies a finished load into the atlas if it is still wanted; a failed
    /// one is retried later or given up (and reported once).
    fn apply(&mut self, loaded: Loaded, stats: &mut ClipmapStats) {
        let Loaded { id, mut data, outcome } = loaded;
        match outcome {
            Outcome::Cancelled => stats.cancelled += 1,
            Outcome::Failed(error) => {
                stats.failed += 1;
                let verdict = self.loader.failure(id, &error, self.frame);
                if !matches!(verdict, Verdict::RetryAt { .. }) {
                    stats.given_up += 1;
                    self.report_given_up(id, &error, verdict);
                }
                self.last_error = Some(error);
            }
            Outcome::Read => {
                self.loader.succeeded(id);
                // Loads are planned at node_bytes_of; a fitted buffer is that.
                debug_assert!(
                    self.atlas.byte_budget().is_none()
                        || data.heap_bytes() == self.source.node_bytes_of(id),
                    "{id:?}: {} bytes read, {} planned",
                    data.heap_bytes(),
                    self.source.node_bytes_of(id)
                );
                if !self.wanted.contains_key(&id) {
                    stats.discarded += 1;
                } else {
                    match self.atlas.insert(id, &mut data, SlotState::Used, self.frame) {
                        Some(insertion) => {
                            stats.applied += 1;
                            stats.evicted += insertion.evicted.is_some() as u32;
                        }
                        None => stats.discarded += 1,
                    }
                }
            }
        }
        self.loader.recycle(data);
    }

    /// Counts a node given up and says so on stderr, once per node (a node
    /// given up is never requested again).
    fn report_given_up(&mut self, id: NodeId, error: &NodeError, verdict: Verdict) {
        let fallback = "treated as missing; its coarser ancestor is drawn";
        match verdict {
            Verdict::Damaged => {
                self.corrupt_nodes += 1;
                eprintln!("ridgeline: {error}; {fallback}");
            }
            Verdict::GaveUp => {
                self.unreadable_nodes += 1;
                eprintln!(
                    "ridgeline: node {id:?} unreadable after {READ_ATTEMPTS} attempts: {error}; \
                     {fallback}"
                );
            }
            Verdict::Refused if matches!(error, NodeError::Absent { .. }) => {}
            Verdict::Refused => eprintln!("ridgeline: node {id:?}: {error}; {fallback}"),
            Verdict::RetryAt { .. } => {}
        }
    }

    /// The lookup of Kühnert eq. 4.10 and 4.11 in layer `level` of a view:
    /// the best resident node covering the point at that level or coarser.
    pub fn lookup(&self, view: ViewId, point: DVec2, level: u8) -> Result<NodeLookup, LookupError> {
        let point = self.wrapped(point);
        let outside = LookupError::OutsideData(point.x, point.y);
        let level = level.min(self.layout.levels - 1);
        let located = self.layout.locate(level, point.x, point.y).ok_or(outside)?;
        let quadtree = &self.views[view.0];
        let (x, y) = (located.id.x as i64, located.id.y as i64);
        let entry =
            quadtree.entry(level, x, y).ok_or(LookupError::OutsideView(point.x, point.y))?;
        debug_assert_ne!(entry, Entry::NONE, "a located node is inside the pyramid");
        let node = self.atlas.node_in(entry.slot).expect("entries name resident slots");
        let at = self.layout.locate(entry.atlas_level, point.x, point.y).ok_or(outside)?;
        debug_assert_eq!(at.id, node);
        let posts = DVec2::from(at.posts) / self.layout.node_size as f64;
        Ok(NodeLookup { slot: entry.slot, node, atlas_coords: posts })
    }

    /// The layer a lookup at `point` should use for rendering (eq. 4.9): the
    /// finest whose view radius holds the 3D distance from the viewer,
    /// heights approximated by the ground under the viewer at the last
    /// update.
    pub fn quadtree_level(&self, view: ViewId, point: DVec2) -> u8 {
        let quadtree = &self.views[view.0];
        let p = quadtree.position();
        let dz = p.z - quadtree.ground_m();
        let distance = (point.distance_squared(p.truncate()) + dz * dz).sqrt();
        (0..self.layout.levels)
            .find(|&level| distance < quadtree.view_radius_m(&self.layout, level))
            .unwrap_or(self.layout.levels - 1)
    }

    /// The height at `point` from the finest data the view holds there: the
    /// finest layer whose window contains the point, which answers from the
    /// best resident node (terrain awareness wants the best, not the
    /// distance-appropriate, level).
    pub fn height_at(&self, view: ViewId, point: DVec2) -> Result<HeightSample, LookupError> {
        let point = self.wrapped(point);
        let quadtree = &self.views[view.0];
        for level in 0..self.layout.levels {
            let Some(located) = self.layout.locate(level, point.x, point.y) else {
                return Err(LookupError::OutsideData(point.x, point.y));
            };
            if quadtree.in_window(level, located.id.x as i64, located.id.y as i64) {
                let found = self.lookup(view, point, level)?;
                let data = self.atlas.data(found.slot);
                let posts = (found.atlas_coords * self.layout.node_size as f64).to_array();
                let height_m = data.interpolate(&self.layout, posts);
                return Ok(HeightSample { height_m, error_bound_m: data.delta, node: found.node });
            }
        }
        Err(LookupError::OutsideView(point.x, point.y))
    }

    /// The full-resolution height at `point`, read from the source on this
    /// thread (see [`NodeSource::exact_height`]).
    pub fn exact_height(&self, point: DVec2) -> Result<f32, NodeError> {
        self.source.exact_height(point.x, point.y)
    }

    /// Whether the source stores node `id` (an absent node: no data of its
    /// level's resolution there; see [`NodeSource::has_node`]).
    pub fn has_node(&self, id: NodeId) -> bool {
        self.source.has_node(id)
    }

    /// The source's node layout.
    pub fn layout(&self) -> &NodeLayout {
        &self.layout
    }

    /// The settings the clipmap was made with.
    pub fn config(&self) -> ClipmapConfig {
        self.config
    }

    /// The shared node atlas.
    pub fn atlas(&self) -> &NodeAtlas {
        &self.atlas
    }

    /// The clipped quadtree of `view`.
    pub fn view(&self, view: ViewId) -> &ClippedQuadtree {
        &self.views[view.0]
    }

    /// The last frame's number (0 before the first update).
    pub fn frame(&self) -> u64 {
        self.frame
    }

    /// Whether a view wanted `id` in the last update.
    pub fn is_wanted(&self, id: NodeId) -> bool {
        self.wanted.contains_key(&id)
    }

    /// Whether `id` is with the loader thread.
    pub fn is_loading(&self, id: NodeId) -> bool {
        self.loader.is_loading(id)
    }

    /// The most recent failed load's error.
    pub fn last_load_error(&self) -> Option<&NodeError> {
        self.last_error.as_ref()
    }

    /// Nodes whose bytes failed their check when paged in, since the
    /// clipmap was built: each was reported once and is drawn from its
    /// coarser ancestor.
    pub fn corrupt_nodes(&self) -> u64 {
        self.corrupt_nodes
    }

    /// Nodes given up after [`READ_ATTEMPTS`] reads failed with I/O errors.
    pub fn unreadable_nodes(&self) -> u64 {
        self.unreadable_nodes
    }

    /// Whether `id` was given up (damaged, unreadable, or refused by the
    /// source): it is never requested again.
    pub fn has_given_up(&self, id: NodeId) -> bool {
        self.loader.has_given_up(id)
    }
}

fn validate_view(config: ViewConfig) -> Result<(), ClipmapError> {
    let ViewConfig { node_count, view_distance, load_distance } = config;
    if !(4..=256).contains(&node_count) {
        return Err(ClipmapError::NodeCount(node_count));
    }
    let max = ViewConfig::max_load_distance(node_count);
    if !(view_distance > 0.0 && view_distance <= load_distance && load_distance <= max) {
        return Err(ClipmapError::Distances {
            view: view_distance,
            load: load_distance,
            max,
            node_count,
        });
    }
    Ok(())
}

fn check_position(position: DVec3) -> Result<(), ClipmapError> {
    if position.is_finite() {
        Ok(())
    } else {
        Err(ClipmapError::Position(position))
    }
}
