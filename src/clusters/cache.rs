//! Which clusters have blocks in the cluster buffers, made from which
//! tiles' blocks. Per frame, like the tile cache (Polok's two passes):
//! clusters the frame no longer has give their blocks back; clusters that
//! are new, or whose members changed, announce their sizes; the runs are
//! placed and each fills its blocks from its members' tile blocks; one
//! dirty range per run piece is uploaded.
//!
//! A cluster has two blocks, in two allocators: its vertices in the vertex
//! buffer, its indices in the index buffer. The vertex buffer is cut into
//! fixed windows of 2^16 vertices ([`crate::render::cluster::window`]),
//! with a one-vertex fence reserved between neighbours so no block crosses
//! one; a cluster's attribute base is its window's start. Each new or
//! changed cluster picks a window: the fullest window in use that still
//! has room for it (best fit; all resident clusters are drawn, so windows
//! in use are the ones the frame draws), else the lowest with room. Each
//! window's new blocks are then placed as one run inside it, so a frame
//! uploads one transfer per window that received blocks (per run piece
//! with a transfer cap), where one run for all would be one transfer.

use super::{ClusterKey, Formation, Placement};
use crate::allocator::{
    AllocError, AllocatorConfig, ConfigError, ContiguousAllocator, GeneratorId, Request,
    VertexFormat,
};
use crate::lod::TileKey;
use crate::render::cluster::{window, window_count, window_of, MAX_MEMBERS, WINDOW_VERTICES};
use crate::render::cluster_draws::part_bit;
use crate::render::{Cluster, ClusterDraws, ClusterOrder, DrawList, Member, Slice, TileUniforms};
use crate::tiles::block::{INDEX_BYTES, VERTEX_BYTES};
use crate::tiles::TileVertex;
use std::collections::HashMap;
use std::ops::Range;

/// Sizes fixed when the cache is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ClusterConfig {
    /// Bytes of the cluster vertex buffer (and its staging copy).
    pub capacity_bytes: u32,
    /// Bytes of the cluster index buffer (and its staging copy).
    pub index_capacity_bytes: u32,
    /// Clusters that may have a block at once.
    pub max_clusters: u32,
    /// Longest single transfer in bytes; `None` for one transfer per frame.
    pub transfer_cap: Option<u32>,
    /// Frames a released block stays out of reuse.
    pub frames_in_flight: u32,
    /// In which order the clusters are drawn.
    pub order: ClusterOrder,
}

/// Why the frame's clusters could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ClusterError {
    /// The allocator refused the configuration.
    #[error("cluster cache configuration: {0}")]
    Config(#[from] ConfigError),
    /// More clusters than the cache holds.
    #[error("{clusters} clusters, the cache holds {max}")]
    TooManyClusters {
        /// Clusters the frame has.
        clusters: usize,
        /// Clusters the cache holds.
        max: u32,
    },
    /// The cluster buffer cannot take this frame's new clusters.
    #[error("cluster buffer full: {0}")]
    BufferFull(AllocError),
    /// No window of the cluster vertex buffer has room for a cluster.
    #[error("no window of the cluster buffer has room for a cluster of {vertices} vertices")]
    NoWindow {
        /// The cluster's vertices.
        vertices: u32,
    },
}

/// What one frame of the cluster cache did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ClusterFrameStats {
    /// Clusters drawn.
    pub clusters: usize,
    /// Clusters whose block was made this frame.
    pub made: usize,
    /// Bytes of the cluster staging copy uploaded.
    pub bytes_uploaded: u64,
    /// Transfers: one per run piece.
    pub transfers: usize,
    /// Bytes held by clusters' blocks, vertices and indices.
    pub used_bytes: u64,
    /// Distinct attribute bases (windows) of the frame's clusters.
    pub bases: usize,
    /// The fewest windows the frame's cluster vertices could fill: their
    /// bytes over a window's, rounded up.
    pub least_bases: usize,
}

/// Which tile block a member was made from: a remade tile has new bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct MemberSource {
    key: TileKey,
    byte_offset: u32,
    index_count: u32,
    slot: u8,
}

impl Default for MemberSource {
    fn default() -> Self {
        MemberSource { key: TileKey::new(0, 0, 0), byte_offset: 0, index_count: 0, slot: 0 }
    }
}

impl MemberSource {
    fn of(tile: &TileUniforms, slot: u8) -> Self {
        MemberSource {
            key: tile.key,
            byte_offset: tile.byte_offset,
            index_count: tile.index_count,
            slot,
        }
    }
}

/// A cluster not yet placed in a window.
const NO_BASE: u32 = u32::MAX;

/// How one window is used.
#[derive(Clone, Copy, Debug, Default)]
struct WindowUse {
    /// Resident clusters placed in it.
    clusters: u32,
    /// Queued clusters that chose it this frame.
    chosen: u32,
    /// Bytes of its largest free gap not yet promised this frame.
    room: u32,
}

#[derive(Clone, Copy, Debug)]
struct Resident {
    key: ClusterKey,
    members: [MemberSource; MAX_MEMBERS],
    count: u8,
    /// Its attribute base, bytes from the buffer's start.
    base: u32,
    /// Where its indices start, bytes.
    index_byte_offset: u32,
    last_frame: u64,
}

#[derive(Clone, Copy, Debug)]
struct Job {
    slot: u32,
    placements: (u32, u32),
    /// Bytes of its vertex block and of its index block.
    sizes: (u32, u32),
    /// The window it goes to.
    window: u32,
    /// Where its vertex block was placed, bytes.
    vertex_start: u32,
}

/// The clusters resident in the cluster buffer; see the module documentation.
pub struct ClusterCache {
    config: ClusterConfig,
    /// Every cluster's vertices.
    allocator: ContiguousAllocator,
    /// Every cluster's indices.
    index_allocator: ContiguousAllocator,
    /// Per window: resident clusters in it, and its room this frame
    /// (bytes of its largest free gap not yet promised to a new cluster).
    windows: Vec<WindowUse>,
    slots: Vec<Option<Resident>>,
    spare: Vec<u32>,
    by_key: HashMap<ClusterKey, u32>,
    frame: u64,
    formation: Formation,
    requests: Vec<Request>,
    index_requests: Vec<Request>,
    jobs: Vec<Job>,
    dirty: Vec<Range<u32>>,
    index_dirty: Vec<Range<u32>>,
    /// Each attribute base and its nearest cluster's rank (scratch).
    bases: Vec<(u32, u32)>,
    stats: ClusterFrameStats,
}

impl ClusterCache {
    /// An empty cache.
    pub fn new(config: ClusterConfig) -> Result<Self, ClusterError> {
        let max = config.max_clusters as usize;
        let allocator_config = |capacity, fences| AllocatorConfig {
            capacity,
            max_generators: config.max_clusters + fences,
            alignment: 4,
            transfer_cap: config.transfer_cap,
            frames_in_flight: config.frames_in_flight,
        };
        let windows = window_count(config.capacity_bytes);
        let mut allocator =
            ContiguousAllocator::new(allocator_config(config.capacity_bytes, windows))?;
        fence_windows(&mut allocator, config.max_clusters)?;
        let index_allocator =
            ContiguousAllocator::new(allocator_config(config.index_capacity_bytes, 0))?;
        Ok(ClusterCache {
            config,
            allocator,
            index_allocator,
            windows: vec![WindowUse::default(); window_count(config.capacity_bytes) as usize],
            slots: vec![None; max],
            spare: (0..config.max_clusters).rev().collect(),
            by_key: HashMap::with_capacity(max),
            frame: 0,
            formation: Formation::with_capacity(max),
            requests: Vec::with_capacity(max),
            index_requests: Vec::with_capacity(max),
            jobs: Vec::with_capacity(max),
            dirty: Vec::with_capacity(max),
            index_dirty: Vec::with_capacity(max),
            bases: Vec::with_capacity(max),
            stats: ClusterFrameStats::default(),
        })
    }

    /// The sizes it was built with.
    pub fn config(&self) -> &ClusterConfig {
        &self.config
    }

    /// The staging copy the cluster vertex buffer mirrors.
    pub fn staging(&self) -> &[u8] {
        self.allocator.staging()
    }

    /// The ranges of the vertex staging copy the GPU must receive this frame.
    pub fn dirty_ranges(&self) -> &[Range<u32>] {
        &self.dirty
    }

    /// The staging copy the cluster index buffer mirrors.
    pub fn index_staging(&self) -> &[u8] {
        self.index_allocator.staging()
    }

    /// The ranges of the index staging copy the GPU must receive this frame.
    pub fn index_dirty_ranges(&self) -> &[Range<u32>] {
        &self.index_dirty
    }

    /// What the last update did.
    pub fn stats(&self) -> ClusterFrameStats {
        self.stats
    }

    /// The last frame's formation (its placements and clusters).
    pub fn formation(&self) -> &Formation {
        &self.formation
    }

    /// Forms `list`'s clusters, makes the blocks of new or changed ones
    /// from the tile blocks in `tile_staging` (`tile_dirty`: the tile
    /// ranges remade this frame), and writes the frame's cluster draws
    /// into `draws` (the list's own, [`DrawList::cluster`]).
    pub fn update(
        &mut self,
        list: &DrawList,
        tile_staging: &[u8],
        tile_dirty: &[Range<u32>],
        draws: ClusterDraws<'_>,
    ) -> Result<(), ClusterError> {
        self.frame += 1;
        self.allocator.begin_frame();
        self.index_allocator.begin_frame();
        self.dirty.clear();
        self.index_dirty.clear();
        self.requests.clear();
        self.index_requests.clear();
        self.jobs.clear();
        self.stats = ClusterFrameStats::default();
        let mut formation = std::mem::take(&mut self.formation);
        formation.form(&list.tiles);
        let outcome = self.update_with(&formation, list, tile_staging, tile_dirty, draws);
        self.formation = formation;
        outcome
    }

    fn update_with(
        &mut self,
        formation: &Formation,
        list: &DrawList,
        tile_staging: &[u8],
        tile_dirty: &[Range<u32>],
        draws: ClusterDraws<'_>,
    ) -> Result<(), ClusterError> {
        let placements = formation.placements();
        let clusters = formation.clusters().count();
        if clusters > self.config.max_clusters as usize {
            let max = self.config.max_clusters;
            return Err(ClusterError::TooManyClusters { clusters, max });
        }
        self.keep_unchanged(placements, list, tile_dirty);
        self.release_unused();
        self.announce_changed(placements, list);
        if !self.jobs.is_empty() {
            self.make(placements, list, tile_staging)?;
        }
        self.list(placements, list, draws);
        Ok(())
    }

    /// Marks the clusters of `placements` that are resident with the same
    /// members, none of them remade (`tile_dirty`), as kept this frame.
    fn keep_unchanged(
        &mut self,
        placements: &[Placement],
        list: &DrawList,
        tile_dirty: &[Range<u32>],
    ) {
        let mut start = 0;
        while start < placements.len() {
            let end = group_end(placements, start);
            let members = &placements[start..end];
            let key = members[0].key;
            let same = self.by_key.get(&key).is_some_and(|&slot| {
                let resident = self.slots[slot as usize].as_ref().expect("mapped slots are full");
                resident.count as usize == members.len()
                    && members.iter().zip(&resident.members).all(|(p, m)| {
                        let tile = &list.tiles[p.tile as usize];
                        *m == MemberSource::of(tile, p.slot) && !remade(tile, tile_dirty)
                    })
            });
            if same {
                let slot = self.by_key[&key];
                self.slots[slot as usize].as_mut().expect("mapped").last_frame = self.frame;
            }
            start = end;
        }
    }

    /// New and changed clusters take a slot and announce their size (a
    /// job each).
    fn announce_changed(&mut self, placements: &[Placement], list: &DrawList) {
        let mut start = 0;
        while start < placements.len() {
            let end = group_end(placements, start);
            let key = placements[start].key;
            let slot = match self.by_key.get(&key) {
                Some(&slot)
                    if self.slots[slot as usize].expect("mapped").last_frame == self.frame =>
                {
                    start = end;
                    continue;
                }
                Some(&slot) => slot,
                None => {
                    let slot = self.spare.pop().expect("fewer clusters than slots, checked");
                    self.by_key.insert(key, slot);
                    slot
                }
            };
            let members = &placements[start..end];
            let (vertices, indices) = members.iter().fold((0, 0), |(v, i), p| {
                (v + p.vertices, i + list.tiles[p.tile as usize].index_count)
            });
            let sizes = (vertices * VERTEX_BYTES, (indices * INDEX_BYTES).next_multiple_of(4));
            if let Some(old) = self.slots[slot as usize] {
                self.leave_window(old.base);
            }
            let placements = (start as u32, end as u32);
            self.jobs.push(Job { slot, placements, sizes, window: 0, vertex_start: 0 });
            let mut resident = Resident {
                key,
                members: [MemberSource::default(); MAX_MEMBERS],
                count: members.len() as u8,
                base: NO_BASE,
                index_byte_offset: 0,
                last_frame: self.frame,
            };
            for (m, p) in resident.members.iter_mut().zip(members) {
                *m = MemberSource::of(&list.tiles[p.tile as usize], p.slot);
            }
            self.slots[slot as usize] = Some(resident);
            start = end;
        }
    }

    /// Clusters the frame no longer has give their blocks back.
    fn release_unused(&mut self) {
        for slot in 0..self.slots.len() as u32 {
            let unused = matches!(self.slots[slot as usize], Some(r) if r.last_frame != self.frame);
            if unused {
                self.forget(slot);
            }
        }
    }

    /// Gives slot `slot`'s blocks and base back.
    fn forget(&mut self, slot: u32) {
        if let Some(resident) = self.slots[slot as usize].take() {
            self.by_key.remove(&resident.key);
            if resident.base != NO_BASE {
                self.leave_window(resident.base);
            }
            self.allocator.release(GeneratorId(slot)).expect("slot ids are in range");
            self.index_allocator.release(GeneratorId(slot)).expect("slot ids are in range");
            self.spare.push(slot);
        }
    }

    /// One cluster fewer is placed in the window starting at `base` (bytes).
    fn leave_window(&mut self, base: u32) {
        self.windows[window_of(base) as usize].clusters -= 1;
    }

    /// Picks each queued cluster's window (see the module documentation),
    /// then orders the queue by window, so each window's requests are one
    /// slice, and lists the requests in that order.
    fn choose_windows(&mut self) -> Result<(), ClusterError> {
        let capacity = self.config.capacity_bytes;
        for (k, w) in self.windows.iter_mut().enumerate() {
            let range = window(k as u32, capacity).expect("windows of the buffer");
            w.room = self.allocator.largest_gap_in(range);
            w.chosen = 0;
        }
        for job in &mut self.jobs {
            let size = job.sizes.0;
            let fits = |w: &WindowUse| w.room >= size;
            let in_use = |w: &WindowUse| w.clusters + w.chosen > 0;
            let in_use = self.windows.iter().enumerate().filter(|(_, w)| in_use(w) && fits(w));
            let best = in_use.min_by_key(|(_, w)| w.room).map(|(k, _)| k);
            let Some(k) = best.or_else(|| self.windows.iter().position(fits)) else {
                return Err(ClusterError::NoWindow { vertices: size / VERTEX_BYTES });
            };
            job.window = k as u32;
            self.windows[k].room -= size;
            self.windows[k].chosen += 1;
        }
        self.jobs.sort_unstable_by_key(|job| (job.window, job.slot));
        let format = VertexFormat(0);
        for job in &self.jobs {
            let generator = GeneratorId(job.slot);
            self.requests.push(Request { generator, format, size: job.sizes.0 });
            self.index_requests.push(Request { generator, format, size: job.sizes.1 });
        }
        Ok(())
    }

    /// Places the runs and fills every queued cluster's blocks.
    fn make(
        &mut self,
        placements: &[Placement],
        list: &DrawList,
        tile_staging: &[u8],
    ) -> Result<(), ClusterError> {
        let outcome = self.choose_windows().and_then(|()| {
            self.place_and_fill(placements, list, tile_staging).map_err(ClusterError::BufferFull)
        });
        if let Err(error) = outcome {
            // Forget the clusters queued, so the next frame makes them again.
            for k in 0..self.jobs.len() {
                self.forget(self.jobs[k].slot);
            }
            return Err(error);
        }
        self.stats.made = self.jobs.len();
        self.stats.transfers = self.dirty.len() + self.index_dirty.len();
        Ok(())
    }

    fn place_and_fill(
        &mut self,
        placements: &[Placement],
        list: &DrawList,
        tile_staging: &[u8],
    ) -> Result<(), AllocError> {
        let capacity = self.config.capacity_bytes;
        let ClusterCache {
            allocator,
            index_allocator,
            windows,
            slots,
            jobs,
            requests,
            index_requests,
            dirty,
            index_dirty,
            stats,
            ..
        } = self;
        let members_of =
            |job: &Job| &placements[job.placements.0 as usize..job.placements.1 as usize];
        let mut bytes = 0u64;
        // One run per window that receives blocks.
        let mut start = 0;
        while start < jobs.len() {
            let k = jobs[start].window;
            let end = start + jobs[start..].iter().take_while(|j| j.window == k).count();
            let range = window(k, capacity).expect("a window of the buffer");
            let base = range.start;
            let mut plan = allocator.allocate_within(&requests[start..end], range)?;
            for (i, job) in jobs[start..end].iter_mut().enumerate() {
                let block = plan.range(i);
                debug_assert_eq!((block.start - base) % VERTEX_BYTES, 0, "whole vertices");
                job.vertex_start = block.start;
                slots[job.slot as usize].as_mut().expect("queued").base = base;
                windows[k as usize].clusters += 1;
            }
            plan.fill(|i, _, block| {
                fill_vertices(block, members_of(&jobs[start + i]), list, tile_staging);
                bytes += block.len() as u64;
            });
            dirty.extend(plan.dirty_ranges().iter().cloned());
            start = end;
        }
        let mut index_plan = index_allocator.allocate(index_requests)?;
        for (k, job) in jobs.iter().enumerate() {
            let resident = slots[job.slot as usize].as_mut().expect("queued");
            resident.index_byte_offset = index_plan.range(k).start;
        }
        index_plan.fill(|k, _, block| {
            let job = &jobs[k];
            let base = slots[job.slot as usize].expect("queued").base;
            let first = (job.vertex_start - base) / VERTEX_BYTES;
            fill_indices(block, first, members_of(job), list, tile_staging);
            bytes += block.len() as u64;
        });
        index_dirty.extend(index_plan.dirty_ranges().iter().cloned());
        stats.bytes_uploaded = bytes;
        Ok(())
    }

    /// Lists the frame's clusters in `list`, in draw order: by attribute
    /// base, the bases in the order of their nearest cluster, and nearest
    /// first within one base (so each base's pointers are set once).
    fn list(&mut self, placements: &[Placement], list: &DrawList, draws: ClusterDraws<'_>) {
        let ClusterDraws { clusters, members } = draws;
        clusters.clear();
        members.clear();
        let mut start = 0;
        while start < placements.len() {
            let end = group_end(placements, start);
            let key = placements[start].key;
            let resident = self.slots[self.by_key[&key] as usize].expect("made");
            let first_member = members.len() as u32;
            let mut first_index = 0;
            let mut no_data = false;
            for p in &placements[start..end] {
                let tile = &list.tiles[p.tile as usize];
                members.push(Member {
                    tile: p.tile,
                    slot: p.slot,
                    first_index,
                    index_count: tile.index_count,
                });
                first_index += tile.index_count;
                no_data |= tile.no_data;
            }
            let mut parts = 0;
            for p in &placements[start..end] {
                let tile = &list.tiles[p.tile as usize];
                for slice in [Slice::Far, Slice::Near] {
                    if list.tile_in(tile, slice) {
                        parts |= part_bit(slice, no_data);
                    }
                }
            }
            clusters.push(Cluster {
                base: resident.base,
                index_byte_offset: resident.index_byte_offset,
                first_member,
                member_count: (end - start) as u32,
                no_data,
                parts,
            });
            start = end;
        }
        self.order(placements, clusters, members);
    }

    /// Puts `clusters` in draw order ([`ClusterConfig::order`]) and counts
    /// the attribute bases they use against the fewest `placements`'
    /// vertices could fill.
    fn order(&mut self, placements: &[Placement], clusters: &mut [Cluster], members: &[Member]) {
        // Nearest member (tiles are listed nearest first), then the
        // nearest cluster of each base.
        let nearest = |c: &Cluster| {
            let first = c.first_member as usize;
            members[first..first + c.member_count as usize]
                .iter()
                .map(|m| m.tile)
                .min()
                .unwrap_or(0)
        };
        clusters.sort_unstable_by_key(|c| (c.base, nearest(c)));
        self.bases.clear();
        for cluster in clusters.iter() {
            if self.bases.last().map(|b| b.0) != Some(cluster.base) {
                self.bases.push((cluster.base, nearest(cluster)));
            }
        }
        self.stats.bases = self.bases.len();
        let vertices: u64 = placements.iter().map(|p| p.vertices as u64).sum();
        self.stats.least_bases = vertices.div_ceil(WINDOW_VERTICES as u64) as usize;
        let bases = &self.bases;
        let group = |c: &Cluster| {
            let at = bases.binary_search_by_key(&c.base, |b| b.0).expect("every base listed");
            bases[at].1
        };
        match self.config.order {
            ClusterOrder::ByBase => clusters.sort_unstable_by_key(|c| (group(c), nearest(c))),
            ClusterOrder::NearestFirst => clusters.sort_unstable_by_key(nearest),
        }
        let used = self.allocator.stats().live_bytes + self.index_allocator.stats().live_bytes;
        self.stats.clusters = clusters.len();
        self.stats.used_bytes = used;
    }
}

/// Reserves the fence after each window of `allocator` (generators from
/// `first_fence` on), so no block crosses from one window into the next.
fn fence_windows(
    allocator: &mut ContiguousAllocator,
    first_fence: u32,
) -> Result<(), ClusterError> {
    let capacity = allocator.config().capacity;
    for k in 0..window_count(capacity) {
        let inside = window(k, capacity).expect("counted");
        let fence =
            inside.end..(inside.start + crate::render::cluster::WINDOW_STRIDE).min(capacity);
        if !fence.is_empty() {
            let generator = GeneratorId(first_fence + k);
            allocator.reserve(generator, fence).map_err(ClusterError::BufferFull)?;
        }
    }
    Ok(())
}

/// Whether `tile`'s block was written this frame (remade in place).
fn remade(tile: &TileUniforms, dirty: &[Range<u32>]) -> bool {
    let block = tile.block_range();
    dirty.iter().any(|r| r.start < block.end && block.start < r.end)
}

/// One past the last placement of the cluster starting at `start`.
fn group_end(placements: &[Placement], start: usize) -> usize {
    let key = placements[start].key;
    let mut end = start + 1;
    while end < placements.len() && placements[end].key == key {
        end += 1;
    }
    end
}

/// Writes a cluster's vertex block: each member's vertices with its slot.
fn fill_vertices(block: &mut [u8], members: &[Placement], list: &DrawList, tile_staging: &[u8]) {
    let size = VERTEX_BYTES as usize;
    let mut at = 0;
    for p in members {
        let source = list.tiles[p.tile as usize].block(tile_staging);
        for vertex in source.vertices() {
            let vertex = TileVertex { _pad: p.slot as u16, ..vertex };
            block[at..at + size].copy_from_slice(bytemuck::bytes_of(&vertex));
            at += size;
        }
    }
    debug_assert_eq!(at, block.len());
}

/// Writes a cluster's index block: every member's triangles, numbered from
/// the cluster's base (its first vertex is vertex `first` from there), then
/// zero padding.
fn fill_indices(
    block: &mut [u8],
    mut first: u32,
    members: &[Placement],
    list: &DrawList,
    tile_staging: &[u8],
) {
    let mut at = 0;
    for p in members {
        let source = list.tiles[p.tile as usize].block(tile_staging);
        for t in 0..source.triangle_count() {
            for index in source.triangle(t) {
                let rebased = first + index as u32;
                debug_assert!(rebased < 1 << 16, "the base reaches every vertex");
                block[at..at + 2].copy_from_slice(&(rebased as u16).to_ne_bytes());
                at += 2;
            }
        }
        first += p.vertices;
    }
    block[at..].fill(0);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::cluster::WINDOW_STRIDE;

    #[test]
    fn clusters_go_to_the_fullest_window_in_use_with_room() {
        let config = ClusterConfig {
            capacity_bytes: 3 * WINDOW_STRIDE,
            index_capacity_bytes: 1 << 16,
            max_clusters: 8,
            transfer_cap: None,
            frames_in_flight: 0,
            order: ClusterOrder::ByBase,
        };
        let mut cache = ClusterCache::new(config).expect("a cache");
        assert_eq!(cache.allocator.stats().live_blocks, 3, "a fence after each window");
        let job = |slot, vertices: u32| Job {
            slot,
            placements: (0, 0),
            sizes: (vertices * VERTEX_BYTES, 4),
            window: 0,
            vertex_start: 0,
        };
        cache.jobs.extend([job(0, 40_000), job(1, 30_000), job(2, 20_000), job(3, 5_000)]);
        cache.choose_windows().expect("room");
        // 40 000 vertices open window 0; 30 000 do not fit its 25 536 left
        // and open window 1; 20 000 fit both, best in window 0, and so do
        // 5 000 (5 536 left there against 35 536).
        let chosen: Vec<(u32, u32)> = cache.jobs.iter().map(|j| (j.slot, j.window)).collect();
        assert_eq!(chosen, [(0, 0), (2, 0), (3, 0), (1, 1)], "ordered by window");
        let generators: Vec<u32> = cache.requests.iter().map(|r| r.generator.0).collect();
        assert_eq!(generators, [0, 2, 3, 1], "requests in the jobs' order");
        cache.jobs.push(job(4, 60_000));
        cache.jobs.push(job(5, 60_000));
        let full = cache.choose_windows();
        assert!(matches!(full, Err(ClusterError::NoWindow { vertices: 60_000 })), "{full:?}");
    }
}
