//! Which clusters have a block in the cluster buffer, made from which
//! tiles' blocks. Per frame, like the tile cache (Polok's two passes):
//! clusters the frame no longer has give their blocks back; clusters that
//! are new, or whose members changed, announce their size; the run is
//! placed and each fills its block from its members' tile blocks; one
//! dirty range per run piece is uploaded.

use super::{cluster_base, ClusterKey, Formation, Placement};
use crate::allocator::{
    AllocError, AllocatorConfig, ConfigError, ContiguousAllocator, GeneratorId, Request,
    VertexFormat,
};
use crate::lod::TileKey;
use crate::render::cluster::MAX_MEMBERS;
use crate::render::{Cluster, DrawList, Member, TileUniforms};
use crate::tiles::block::{INDEX_BYTES, VERTEX_BYTES};
use crate::tiles::TileVertex;
use std::collections::HashMap;
use std::ops::Range;

/// Sizes fixed when the cache is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ClusterConfig {
    /// Bytes of the cluster buffer (and its staging copy).
    pub capacity_bytes: u32,
    /// Clusters that may have a block at once.
    pub max_clusters: u32,
    /// Longest single transfer in bytes; `None` for one transfer per frame.
    pub transfer_cap: Option<u32>,
    /// Frames a released block stays out of reuse.
    pub frames_in_flight: u32,
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
    /// Bytes held by clusters' blocks.
    pub used_bytes: u64,
    /// Distinct attribute bases of the frame's clusters.
    pub bases: usize,
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
}

/// The clusters resident in the cluster buffer; see the module documentation.
pub struct ClusterCache {
    config: ClusterConfig,
    allocator: ContiguousAllocator,
    slots: Vec<Option<Resident>>,
    spare: Vec<u32>,
    by_key: HashMap<ClusterKey, u32>,
    frame: u64,
    formation: Formation,
    requests: Vec<Request>,
    jobs: Vec<Job>,
    dirty: Vec<Range<u32>>,
    /// Each attribute base and its nearest cluster's rank (scratch).
    bases: Vec<(u32, u32)>,
    stats: ClusterFrameStats,
}

impl ClusterCache {
    /// An empty cache.
    pub fn new(config: ClusterConfig) -> Result<Self, ClusterError> {
        let max = config.max_clusters as usize;
        let allocator = ContiguousAllocator::new(AllocatorConfig {
            capacity: config.capacity_bytes,
            max_generators: config.max_clusters,
            alignment: 4,
            transfer_cap: config.transfer_cap,
            frames_in_flight: config.frames_in_flight,
        })?;
        Ok(ClusterCache {
            config,
            allocator,
            slots: vec![None; max],
            spare: (0..config.max_clusters).rev().collect(),
            by_key: HashMap::with_capacity(max),
            frame: 0,
            formation: Formation::with_capacity(max),
            requests: Vec::with_capacity(max),
            jobs: Vec::with_capacity(max),
            dirty: Vec::with_capacity(max),
            bases: Vec::with_capacity(max),
            stats: ClusterFrameStats::default(),
        })
    }

    /// The sizes it was built with.
    pub fn config(&self) -> &ClusterConfig {
        &self.config
    }

    /// The staging copy the cluster buffer mirrors.
    pub fn staging(&self) -> &[u8] {
        self.allocator.staging()
    }

    /// The ranges of the staging copy the GPU must receive this frame.
    pub fn dirty_ranges(&self) -> &[Range<u32>] {
        &self.dirty
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
    /// ranges remade this frame), and lists the clusters in `list`.
    pub fn update(
        &mut self,
        list: &mut DrawList,
        tile_staging: &[u8],
        tile_dirty: &[Range<u32>],
    ) -> Result<(), ClusterError> {
        self.frame += 1;
        self.allocator.begin_frame();
        self.dirty.clear();
        self.requests.clear();
        self.jobs.clear();
        self.stats = ClusterFrameStats::default();
        let mut formation = std::mem::take(&mut self.formation);
        formation.form(&list.tiles);
        let outcome = self.update_with(&formation, list, tile_staging, tile_dirty);
        self.formation = formation;
        outcome
    }

    fn update_with(
        &mut self,
        formation: &Formation,
        list: &mut DrawList,
        tile_staging: &[u8],
        tile_dirty: &[Range<u32>],
    ) -> Result<(), ClusterError> {
        let placements = formation.placements();
        let clusters = formation.clusters().count();
        if clusters > self.config.max_clusters as usize {
            let max = self.config.max_clusters;
            return Err(ClusterError::TooManyClusters { clusters, max });
        }
        // Which clusters are kept as they are.
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
        self.release_unused();
        // New and changed clusters announce their size.
        let mut start = 0;
        while start < placements.len() {
            let end = group_end(placements, start);
            let key = placements[start].key;
            let slot = match self.by_key.get(&key) {
                Some(&slot) if self.slots[slot as usize].expect("mapped").last_frame == self.frame => {
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
            let bytes = (vertices * VERTEX_BYTES + indices * INDEX_BYTES).next_multiple_of(VERTEX_BYTES);
            self.requests.push(Request {
                generator: GeneratorId(slot),
                format: VertexFormat(0),
                size: bytes,
            });
            self.jobs.push(Job { slot, placements: (start as u32, end as u32) });
            let mut resident = Resident {
                key,
                members: [MemberSource::default(); MAX_MEMBERS],
                count: members.len() as u8,
                base: 0,
                index_byte_offset: 0,
                last_frame: self.frame,
            };
            for (m, p) in resident.members.iter_mut().zip(members) {
                *m = MemberSource::of(&list.tiles[p.tile as usize], p.slot);
            }
            self.slots[slot as usize] = Some(resident);
            start = end;
        }
        if !self.requests.is_empty() {
            self.make(placements, list, tile_staging)?;
        }
        self.list(placements, list);
        Ok(())
    }

    /// Clusters the frame no longer has give their blocks back.
    fn release_unused(&mut self) {
        for slot in 0..self.slots.len() as u32 {
            let unused = matches!(self.slots[slot as usize], Some(r) if r.last_frame != self.frame);
            if unused {
                let resident = self.slots[slot as usize].take().expect("matched");
                self.by_key.remove(&resident.key);
                self.allocator.release(GeneratorId(slot)).expect("slot ids are in range");
                self.spare.push(slot);
            }
        }
    }

    /// Places the run and fills every queued cluster's block.
    fn make(
        &mut self,
        placements: &[Placement],
        list: &DrawList,
        tile_staging: &[u8],
    ) -> Result<(), ClusterError> {
        let (slots, jobs, dirty) = (&mut self.slots, &self.jobs, &mut self.dirty);
        let mut bytes_uploaded = 0u64;
        let outcome = self.allocator.allocate(&self.requests).map(|mut plan| {
            for (index, job) in jobs.iter().enumerate() {
                let range = plan.range(index);
                let resident = slots[job.slot as usize].as_mut().expect("queued");
                debug_assert_eq!(range.start % VERTEX_BYTES, 0, "blocks are whole vertices");
                let first = range.start / VERTEX_BYTES;
                let members = &placements[job.placements.0 as usize..job.placements.1 as usize];
                let vertices: u32 = members.iter().map(|p| p.vertices).sum();
                let base = cluster_base(first, first + vertices);
                resident.base = base * VERTEX_BYTES;
                resident.index_byte_offset = range.start + vertices * VERTEX_BYTES;
            }
            plan.fill(|index, _request, block| {
                let job = jobs[index];
                let resident = slots[job.slot as usize].as_ref().expect("queued");
                let members = &placements[job.placements.0 as usize..job.placements.1 as usize];
                fill_block(block, resident, members, list, tile_staging);
                bytes_uploaded += block.len() as u64;
            });
            dirty.extend(plan.dirty_ranges().iter().cloned());
        });
        match outcome {
            Ok(()) => {
                self.stats.made = self.jobs.len();
                self.stats.bytes_uploaded = bytes_uploaded;
                self.stats.transfers = self.dirty.len();
                Ok(())
            }
            Err(error) => {
                // Nothing placed: forget the clusters queued, so the next
                // frame makes them again.
                for job in &self.jobs {
                    if let Some(resident) = self.slots[job.slot as usize].take() {
                        self.by_key.remove(&resident.key);
                        let _ = self.allocator.release(GeneratorId(job.slot));
                        self.spare.push(job.slot);
                    }
                }
                Err(ClusterError::BufferFull(error))
            }
        }
    }

    /// Lists the frame's clusters in `list`, in draw order: by attribute
    /// base, the bases in the order of their nearest cluster, and nearest
    /// first within one base (so each base's pointers are set once).
    fn list(&mut self, placements: &[Placement], list: &mut DrawList) {
        list.clusters.clear();
        list.members.clear();
        let mut start = 0;
        while start < placements.len() {
            let end = group_end(placements, start);
            let key = placements[start].key;
            let resident = self.slots[self.by_key[&key] as usize].expect("made");
            let first_member = list.members.len() as u32;
            let mut first_index = 0;
            let mut voids = false;
            for p in &placements[start..end] {
                let tile = &list.tiles[p.tile as usize];
                list.members.push(Member {
                    tile: p.tile,
                    slot: p.slot,
                    first_index,
                    index_count: tile.index_count,
                });
                first_index += tile.index_count;
                voids |= tile.voids;
            }
            list.clusters.push(Cluster {
                base: resident.base,
                index_byte_offset: resident.index_byte_offset,
                first_member,
                member_count: (end - start) as u32,
                voids,
            });
            start = end;
        }
        // Nearest member (tiles are listed nearest first), then the
        // nearest cluster of each base.
        let members = &list.members;
        let nearest = |c: &Cluster| {
            let first = c.first_member as usize;
            members[first..first + c.member_count as usize].iter().map(|m| m.tile).min().unwrap_or(0)
        };
        list.clusters.sort_unstable_by_key(|c| (c.base, nearest(c)));
        self.bases.clear();
        for cluster in &list.clusters {
            if self.bases.last().map(|b| b.0) != Some(cluster.base) {
                self.bases.push((cluster.base, nearest(cluster)));
            }
        }
        self.stats.bases = self.bases.len();
        let bases = &self.bases;
        let group = |c: &Cluster| {
            let at = bases.binary_search_by_key(&c.base, |b| b.0).expect("every base listed");
            bases[at].1
        };
        list.clusters.sort_unstable_by_key(|c| (group(c), nearest(c)));
        list.clustered = true;
        let used = self.allocator.stats().live_bytes;
        self.stats.clusters = list.clusters.len();
        self.stats.used_bytes = used;
    }
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

/// Writes a cluster's block: each member's vertices with its slot, then
/// every member's indices numbered from the cluster's base, then zeros.
fn fill_block(
    block: &mut [u8],
    resident: &Resident,
    members: &[Placement],
    list: &DrawList,
    tile_staging: &[u8],
) {
    let block_start = resident.index_byte_offset
        - members.iter().map(|p| p.vertices).sum::<u32>() * VERTEX_BYTES;
    let mut at = 0usize;
    let mut first_vertex = (block_start - resident.base) / VERTEX_BYTES;
    let vertex_bytes = VERTEX_BYTES as usize;
    let index_start: usize = members.iter().map(|p| p.vertices as usize).sum::<usize>() * vertex_bytes;
    let mut index_at = index_start;
    for p in members {
        let tile = &list.tiles[p.tile as usize];
        let source = tile.block(tile_staging);
        for vertex in source.vertices() {
            let vertex = TileVertex { _pad: p.slot as u16, ..vertex };
            block[at..at + vertex_bytes].copy_from_slice(bytemuck::bytes_of(&vertex));
            at += vertex_bytes;
        }
        for t in 0..source.triangle_count() {
            for index in source.triangle(t) {
                let rebased = first_vertex + index as u32;
                debug_assert!(rebased < 1 << 16);
                block[index_at..index_at + 2].copy_from_slice(&(rebased as u16).to_ne_bytes());
                index_at += 2;
            }
        }
        first_vertex += p.vertices;
    }
    block[index_at..].fill(0);
}
