//! Maps built a block at a time (issue 21): a node of level `depth` and
//! the stored nodes under it whose maps are on the same reference lattice
//! (all of them where level-0 data lie under the block) are squares of one
//! grid, so the block's grid is read once and its triangles scanned once
//! ([`OwnCodes`]); each node's map is then its square's codes
//! ([`OwnCodes::restrict`]) and its square of the grid
//! ([`ReferenceGrid::cut`]), the very map [`super::build_map`] builds alone.
//! Before, every level from 1 to `depth` redid a full-resolution RTIN over
//! the posts under it.

use super::build::{map_from_codes, MapPlan};
use rayon::prelude::*;

use super::reference::{reference_grid, ReferenceGrid};
use super::{build_map, MeshOptions, MeshesError};
use crate::mesh::{Diagonal, HeightGrid, Metric, OwnCodes};
use crate::node::{ErrorMap, NodeId, NodeLayout, NodeSource};

/// The top node of `id`'s block: its ancestor of level `depth` (or the
/// layout's coarsest level), itself above that.
pub fn block_top(layout: &NodeLayout, depth: u8, id: NodeId) -> NodeId {
    let top_level = depth.min(layout.levels - 1);
    if id.level >= top_level {
        return id;
    }
    let up = top_level - id.level;
    NodeId::new(top_level, id.x >> up, id.y >> up)
}

/// The order records are built and written in: block by block (tops in
/// the layout's node order), each block's nodes in node order. Both a
/// single build and a merge of shards write in it, so their bytes agree.
pub fn record_order(layout: &NodeLayout, depth: u8, ids: &mut [NodeId]) {
    let index = |id: NodeId| layout.node_index(id).unwrap_or(u64::MAX);
    ids.sort_by_key(|&id| (index(block_top(layout, depth, id)), index(id)));
}

/// One block: its grid and its triangles' own codes.
pub struct Block {
    top: NodeId,
    plan: MapPlan,
    reference: ReferenceGrid,
    codes: OwnCodes,
    /// The block's own map's codes: its members' shared edges read them.
    block_codes: Vec<u8>,
}

impl Block {
    /// Whether building `members` (nodes under `top`) through the block
    /// saves work: their posts at least the block's.
    pub fn worth_it(layout: &NodeLayout, top: NodeId, members: &[NodeId], depth: u8) -> bool {
        let posts = |id: NodeId| {
            let side = (layout.node_size as u64) << id.level.min(depth);
            side * side
        };
        members.iter().map(|&id| posts(id)).sum::<u64>() >= posts(top)
    }

    /// Reads and scans the block of `top` (a stored node).
    pub fn new(
        source: &dyn NodeSource,
        top: NodeId,
        options: &MeshOptions,
    ) -> Result<Block, MeshesError> {
        let plan = MapPlan::of(source, top, options);
        let reference = reference_grid(source, top, plan.post_level)?;
        let grid = HeightGrid::with_voids(reference.side, &reference.heights)
            .map_err(|e| MeshesError::Mesh { id: top, source: e })?;
        let diagonal = Diagonal::of_node(top.x, top.y);
        let codes = OwnCodes::new(&grid, diagonal, Metric::Surface);
        let block_codes = codes.restrict([0, 0], reference.side - 1, diagonal);
        Ok(Block { top, plan, reference, codes, block_codes })
    }

    /// Node `id`'s map (a stored node under the top, or the top): cut from
    /// the block when on its lattice, else built alone.
    pub fn map_of(
        &self,
        source: &dyn NodeSource,
        id: NodeId,
        options: &MeshOptions,
    ) -> Result<ErrorMap, MeshesError> {
        let plan = MapPlan::of(source, id, options);
        if plan.post_level != self.plan.post_level {
            return build_map(source, id, options);
        }
        let reference = self.reference.cut(source, self.top, id)?;
        let layout = source.layout();
        let up = self.top.level - id.level;
        let posts = layout.node_size << (id.level - plan.post_level);
        let origin = [id.x - (self.top.x << up), id.y - (self.top.y << up)].map(|v| v * posts);
        let shared = shared_edges(origin, posts, self.reference.side - 1);
        let diagonal = Diagonal::of_node(id.x, id.y);
        let codes = self.codes.restrict_sharing(origin, posts, diagonal, shared, &self.block_codes);
        let mut map = map_from_codes(layout, id, options, plan, &reference, codes);
        map.shared_edges = shared;
        Ok(map)
    }
}

/// The edges of the square of `posts` cells at `origin` that lie inside a
/// block of `cells` cells: there its neighbour is a square of the block too.
fn shared_edges(origin: [u32; 2], posts: u32, cells: u32) -> u8 {
    let mut shared = 0;
    for (inside, bit) in [
        (origin[0] > 0, ErrorMap::WEST),
        (origin[0] + posts < cells, ErrorMap::EAST),
        (origin[1] > 0, ErrorMap::SOUTH),
        (origin[1] + posts < cells, ErrorMap::NORTH),
    ] {
        if inside {
            shared |= bit;
        }
    }
    shared
}

/// Members built at a time: a few per core, so that memory holds a few
/// maps per core, not a block's.
const MEMBERS_AT_A_TIME: usize = 16;

/// Builds the maps of `nodes` (stored nodes of `source`) block by block,
/// in [`record_order`], handing each to `emit` in that order; the nodes
/// read are released after each block (memory must not grow with the
/// pyramid).
pub fn build_blocks(
    source: &dyn NodeSource,
    nodes: &[NodeId],
    options: &MeshOptions,
    emit: &mut dyn FnMut(NodeId, ErrorMap) -> Result<(), MeshesError>,
) -> Result<(), MeshesError> {
    let layout = *source.layout();
    let mut ordered = nodes.to_vec();
    record_order(&layout, options.depth, &mut ordered);
    let mut rest = &ordered[..];
    while let Some(&first) = rest.first() {
        let top = block_top(&layout, options.depth, first);
        let count =
            rest.iter().take_while(|&&id| block_top(&layout, options.depth, id) == top).count();
        let (members, after) = rest.split_at(count);
        rest = after;
        let block = if source.has_node(top) && Block::worth_it(&layout, top, members, options.depth)
        {
            Some(Block::new(source, top, options)?)
        } else {
            None
        };
        for chunk in members.chunks(MEMBERS_AT_A_TIME * rayon::current_num_threads().max(1)) {
            let built: Vec<Result<ErrorMap, MeshesError>> = chunk
                .par_iter()
                .map(|&id| match &block {
                    Some(block) => block.map_of(source, id, options),
                    None => build_map(source, id, options),
                })
                .collect();
            for (&id, map) in chunk.iter().zip(built) {
                emit(id, map?)?;
            }
            // Each member reads its own nodes again (its frame), and the
            // kernel maps whole page-cache folios around each read: a
            // block's 1024 level-0 members held 88 MB of the 16-tile
            // pyramid mapped by the block's end.
            source.release_pages();
        }
        source.release_pages();
    }
    Ok(())
}
