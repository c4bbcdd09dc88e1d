//! Maps built a block at a time (issue 21): a node of level `depth` and
//! the stored nodes under it whose maps are on the same reference lattice
//! (all of them where level-0 data lie under the block) are squares of one
//! grid, so the block's grid is read once and its triangles scanned once
//! ([`OwnCodes`]); each node's map is then its square's codes
//! ([`OwnCodes::restrict`]) and its square of the grid
//! ([`ReferenceGrid::cut`]), the very map [`super::build_map`] builds alone.
//! Before, every level from 1 to `depth` redid a full-resolution RTIN over
//! the posts under it.
//!
//! Shared edges (issues 22 and 25): a member finer than the share level
//! ([`NodeLayout::share_level`]) whose share square is stored on its
//! lattice codes the posts of its edges inside that square from the
//! square's own map ([`OwnCodes::restrict_sharing`]), so its neighbour
//! there codes them alike. The square's codes are the same whichever
//! block (or shard) they are read from.

use super::build::{map_from_codes, MapPlan};
use rayon::prelude::*;
use std::collections::HashMap;

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
    /// Per post of the block, the code its share square's own map gives
    /// it (`NodeLayout::share_square`; empty where no member shares): the
    /// members' shared edges start from them.
    share_codes: Vec<u8>,
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

    /// Reads and scans the block of `top` (a stored node); with `shares`,
    /// keeps its share squares' codes for members that share edges.
    pub fn new(
        source: &dyn NodeSource,
        top: NodeId,
        options: &MeshOptions,
        shares: bool,
    ) -> Result<Block, MeshesError> {
        let plan = MapPlan::of(source, top, options);
        let reference = reference_grid(source, top, plan.post_level)?;
        let grid = HeightGrid::with_voids(reference.side, &reference.heights)
            .map_err(|e| MeshesError::Mesh { id: top, source: e })?;
        let codes = OwnCodes::new(&grid, Diagonal::of_node(top.x, top.y), Metric::Surface);
        let share_codes = match shares {
            true => share_codes(&codes, source.layout(), top, plan.post_level),
            false => Vec::new(),
        };
        Ok(Block { top, plan, reference, codes, share_codes })
    }

    /// Whether the block builds node `id` (the top or a node under it):
    /// `id` is on its lattice, and the block holds the codes of `square`,
    /// `id`'s share square if it shares edges.
    fn serves(
        &self,
        source: &dyn NodeSource,
        id: NodeId,
        options: &MeshOptions,
        square: Option<NodeId>,
    ) -> bool {
        let holds = |q: NodeId| q.level <= self.top.level && !self.share_codes.is_empty();
        MapPlan::of(source, id, options).post_level == self.plan.post_level
            && square.is_none_or(holds)
    }

    /// Node `id`'s map (served by the block), cut from it: its square's
    /// codes, the edges inside `square` (its share square, if it shares)
    /// from that square's own map.
    fn map_of(
        &self,
        source: &dyn NodeSource,
        id: NodeId,
        options: &MeshOptions,
        square: Option<NodeId>,
    ) -> Result<ErrorMap, MeshesError> {
        let plan = MapPlan::of(source, id, options);
        debug_assert_eq!(plan.post_level, self.plan.post_level);
        let reference = self.reference.cut(source, self.top, id)?;
        let layout = source.layout();
        let up = self.top.level - id.level;
        let posts = layout.node_size << (id.level - plan.post_level);
        let origin = [id.x - (self.top.x << up), id.y - (self.top.y << up)].map(|v| v * posts);
        let shared = square.map_or(0, |q| inner_edges(id, q));
        let diagonal = Diagonal::of_node(id.x, id.y);
        let codes = match shared {
            0 => self.codes.restrict(origin, posts, diagonal),
            _ => self.codes.restrict_sharing(origin, posts, diagonal, shared, &self.share_codes),
        };
        debug_assert!(shared == 0 || !self.share_codes.is_empty(), "a square the block holds");
        // Its quantised heights may leave its edges unshared (`build`).
        Ok(map_from_codes(layout, id, options, plan, &reference, codes, shared))
    }
}

/// Node `id`'s share square if it shares the edges inside it: the square
/// is stored and its map is on `id`'s lattice. Every build decides this
/// from the pyramid alone, so a build in shards shares what one process
/// does.
pub fn share_square(source: &dyn NodeSource, id: NodeId, options: &MeshOptions) -> Option<NodeId> {
    let square = source.layout().share_square(id)?;
    let lattice = |n: NodeId| MapPlan::of(source, n, options).post_level;
    (source.has_node(square) && lattice(square) == lattice(id)).then_some(square)
}

/// Per post of `top`'s block (on lattice `post_level`), the codes of the
/// own map of the share square it lies in: each square restricted from
/// the block's codes (the block's own subtree there), so they are the
/// codes that square's own block gives.
fn share_codes(codes: &OwnCodes, layout: &NodeLayout, top: NodeId, post_level: u8) -> Vec<u8> {
    let side = codes.side() as usize;
    let mut out = vec![0u8; side * side];
    let level = layout.share_level();
    if level > top.level || level < post_level {
        return out;
    }
    let cells = layout.node_size << (level - post_level);
    let per_side = 1u32 << (top.level - level);
    for qy in 0..per_side {
        for qx in 0..per_side {
            let q = NodeId::new(
                level,
                (top.x << (top.level - level)) + qx,
                (top.y << (top.level - level)) + qy,
            );
            let origin = [qx * cells, qy * cells];
            let square = codes.restrict(origin, cells, Diagonal::of_node(q.x, q.y));
            let n = cells as usize + 1;
            for j in 0..n {
                let at = (origin[1] as usize + j) * side + origin[0] as usize;
                out[at..at + n].copy_from_slice(&square[j * n..(j + 1) * n]);
            }
        }
    }
    out
}

/// The edges of node `id` inside its share square `square`: there its
/// neighbour shares the square.
fn inner_edges(id: NodeId, square: NodeId) -> u8 {
    let span = 1u32 << (square.level - id.level);
    let mut shared = 0;
    for (inside, bit) in [
        (id.x % span != 0, ErrorMap::WEST),
        ((id.x + 1) % span != 0, ErrorMap::EAST),
        (id.y % span != 0, ErrorMap::SOUTH),
        ((id.y + 1) % span != 0, ErrorMap::NORTH),
    ] {
        if inside {
            shared |= bit;
        }
    }
    shared
}

/// Node `id`'s map (a stored node) built without its block, as a shard
/// holding only its share square builds it: through that square's own
/// block where its edges are shared ([`share_square`]), else alone
/// ([`build_map`]). The block build writes the same map.
pub fn build_map_shared(
    source: &dyn NodeSource,
    id: NodeId,
    options: &MeshOptions,
) -> Result<ErrorMap, MeshesError> {
    match share_square(source, id, options) {
        Some(q) => Block::new(source, q, options, true)?.map_of(source, id, options, Some(q)),
        None => build_map(source, id, options),
    }
}

/// Node `id`'s map: through `block` where it serves the node, else
/// through its share square's block in `squares`, else built alone.
fn member_map(
    source: &dyn NodeSource,
    id: NodeId,
    options: &MeshOptions,
    block: Option<&Block>,
    squares: &HashMap<NodeId, Block>,
) -> Result<ErrorMap, MeshesError> {
    let square = share_square(source, id, options);
    if let Some(block) = block.filter(|b| b.serves(source, id, options, square)) {
        return block.map_of(source, id, options, square);
    }
    match square.and_then(|q| squares.get(&q)) {
        Some(block) => block.map_of(source, id, options, square),
        None => build_map(source, id, options),
    }
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
        let sharing: Vec<Option<NodeId>> =
            members.iter().map(|&id| share_square(source, id, options)).collect();
        let block = if source.has_node(top) && Block::worth_it(&layout, top, members, options.depth)
        {
            let shares = sharing.iter().flatten().any(|q| q.level <= top.level);
            Some(Block::new(source, top, options, shares)?)
        } else {
            None
        };
        // Members that share edges but the block does not serve (no block,
        // or another lattice) are built through their share square's own
        // block, as a shard that holds only that square builds them.
        let mut squares: HashMap<NodeId, Block> = HashMap::new();
        for (&id, square) in members.iter().zip(&sharing) {
            let Some(q) = *square else { continue };
            let served = block.as_ref().is_some_and(|b| b.serves(source, id, options, *square));
            if !served && !squares.contains_key(&q) {
                squares.insert(q, Block::new(source, q, options, true)?);
            }
        }
        for chunk in members.chunks(MEMBERS_AT_A_TIME * rayon::current_num_threads().max(1)) {
            let built: Vec<Result<ErrorMap, MeshesError>> = chunk
                .par_iter()
                .map(|&id| member_map(source, id, options, block.as_ref(), &squares))
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
