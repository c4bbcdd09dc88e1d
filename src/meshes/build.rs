//! One node's error map, built from the pyramid alone: every node is built
//! on its own (no parent, no neighbour), so nodes build in parallel, in
//! any order, on any machine.
//!
//! Per node of level `l`:
//! 1. the reference grid: the best data on the lattice of level
//!    `r = max(l - depth, finest)` ([`super::reference`]), `finest` the
//!    finest level with a node stored under it;
//! 2. the RTIN error map of that grid, exact against its posts and the
//!    data's cell diagonals ([`Metric::Surface`]), its hierarchy continuing
//!    the parent's ([`Diagonal::of_node`]);
//! 3. a node no finer node lies under (a *leaf*: level 0, or a coarse
//!    base) keeps a code for every post of its own lattice (dense: it is
//!    drawn however near the camera comes, so any error may be asked of
//!    it); any other node keeps the posts whose code is above its level's
//!    floor ([`MeshOptions::floor_m`]) and those every mesh has, with their
//!    heights and the data's normals there (sparse).

use super::reference::{reference_grid, ReferenceGrid};
use super::{MeshOptions, MeshesError};
use crate::mesh::code::{error_code, threshold_code};
use crate::mesh::rtin::round_up_to_f32;
use crate::mesh::{Diagonal, HeightGrid, Metric, Rtin, RtinOptions};
use crate::node::{ErrorMap, NodeId, NodeLayout, NodeSource};
use crate::tiles::extract::forced_step;

/// What a node's map is built on: the level of its reference lattice and
/// whether it is a leaf (dense).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapPlan {
    /// The level whose lattice the map's posts are on.
    pub post_level: u8,
    /// No finer node lies under the node.
    pub leaf: bool,
    /// The lattice is coarser than the finest data under the node.
    pub hierarchy_leaves: bool,
}

impl MapPlan {
    /// Node `id`'s plan (the node must be stored).
    pub fn of(source: &dyn NodeSource, id: NodeId, options: &MeshOptions) -> MapPlan {
        let finest = finest_stored_level(source, id);
        let post_level = (id.level - id.level.min(options.depth)).max(finest);
        // Half cells are drawn along the data's diagonal only on the data's
        // own lattice (see `RtinOptions::hierarchy_leaves`).
        MapPlan { post_level, leaf: finest == id.level, hierarchy_leaves: post_level > finest }
    }
}

/// Builds node `id`'s error map (the node must be stored) from its own
/// reference grid and RTIN.
pub fn build_map(
    source: &dyn NodeSource,
    id: NodeId,
    options: &MeshOptions,
) -> Result<ErrorMap, MeshesError> {
    let plan = MapPlan::of(source, id, options);
    let reference = reference_grid(source, id, plan.post_level)?;
    let grid = HeightGrid::with_voids(reference.side, &reference.heights)
        .map_err(|e| MeshesError::Mesh { id, source: e })?;
    let rtin_options = RtinOptions {
        metric: Metric::Surface,
        diagonal: Diagonal::of_node(id.x, id.y),
        hierarchy_leaves: plan.hierarchy_leaves,
        ..RtinOptions::default()
    };
    let rtin = Rtin::new(&grid, rtin_options).map_err(|e| MeshesError::Mesh { id, source: e })?;
    let side = reference.side;
    let codes: Vec<u8> =
        (0..side * side).map(|k| error_code(rtin.error_at(k % side, k / side) as f64)).collect();
    Ok(map_from_codes(source.layout(), id, options, plan, &reference, codes, 0))
}

/// Node `id`'s map from its reference grid and the error code of every
/// post of it (row-major): dense for a leaf, else the posts above the
/// floor and those every mesh has. `shared_edges` are the edges whose
/// posts `codes` took from its share square; a map whose stored heights
/// cannot keep the height lattice (`quantise_heights`) shares none.
pub fn map_from_codes(
    layout: &NodeLayout,
    id: NodeId,
    options: &MeshOptions,
    plan: MapPlan,
    reference: &ReferenceGrid,
    codes: Vec<u8>,
    shared_edges: u8,
) -> ErrorMap {
    debug_assert_eq!(codes.len(), reference.heights.len());
    let cells = reference.side - 1;
    let mut map = ErrorMap {
        post_level: plan.post_level,
        cells,
        floor_m: 0.0,
        reference_delta: reference.delta,
        hierarchy_leaves: plan.hierarchy_leaves,
        shared_edges,
        ..ErrorMap::default()
    };
    if plan.leaf {
        map.codes = codes;
    } else {
        map.floor_m = options.floor_m(layout, id.level) as f32;
        let tile_posts = options.tile_cells << (id.level - plan.post_level);
        let forced = forced_step(layout, plan.post_level, cells, tile_posts, map.floor_m as f64);
        keep_sparse(&mut map, reference, forced, &codes);
        fill_posts(&mut map, reference, layout);
        if id.level - plan.post_level > HEIGHTS_FROM_PYRAMID_SHIFT {
            quantise_heights(&mut map);
        }
    }
    map.count_codes();
    map.index_rows();
    map.debug_check();
    map
}

/// A sparse map at most this many levels finer than its node stores no
/// heights or normals: they are the pyramid's, and page-in reads them
/// from the at most 4^2 nodes of its lattice under the node
/// ([`super::pagein`], the same bits as [`fill_posts`]). Those maps (levels 1 and 2 over level-0 data) keep
/// most of their posts, and their heights and normals were 60 % of the
/// map file. Coarser maps keep few posts from many nodes: they store
/// their heights, quantised (`quantise_heights`).
pub const HEIGHTS_FROM_PYRAMID_SHIFT: u8 = 2;

/// Steps a stored map's heights span: `u16` codes, the last one NaN.
const HEIGHT_STEPS: f64 = 65_534.0;

/// The step of the heights every stored map whose range spans at most
/// 2047 m keeps (a power of two, so a height on it is exact in `f32`
/// far beyond any terrain's, and at least 8 units in the last place of
/// heights within +-16 km): maps of neighbouring nodes that share an edge
/// code its posts to the same heights.
pub const SHARED_HEIGHT_STEP: f32 = 1.0 / 32.0;

/// Keeps the posts a sparse map needs (codes above the floor's, and the
/// corners of the squares every mesh of the node splits to) with their
/// codes.
fn keep_sparse(map: &mut ErrorMap, reference: &ReferenceGrid, forced: u32, codes: &[u8]) {
    let side = reference.side;
    let floor_code = threshold_code(map.floor_m as f64);
    for j in 0..side {
        for i in 0..side {
            let code = codes[(j * side + i) as usize];
            let on_forced = i % forced == 0 && j % forced == 0;
            if code > floor_code || on_forced {
                map.keys.push(j * side + i);
                map.codes.push(code);
            }
        }
    }
}

/// Fills a sparse map's heights and normals at its keys from its
/// reference grid, at build (page-in reads the same bits without the
/// grid: [`super::pagein`]).
pub fn fill_posts(map: &mut ErrorMap, reference: &ReferenceGrid, layout: &NodeLayout) {
    debug_assert_eq!(reference.side, map.side());
    let side = reference.side;
    let scale = (1u64 << map.post_level) as f64;
    let spacing = [layout.spacing_m[0] * scale, layout.spacing_m[1] * scale];
    map.heights.clear();
    map.normals.clear();
    map.heights.reserve_exact(map.keys.len());
    map.normals.reserve_exact(map.keys.len());
    for &key in &map.keys {
        map.heights.push(reference.heights[key as usize]);
        map.normals.push(reference.normal(key % side, key / side, spacing));
    }
}

/// Rounds a map's heights to `HEIGHT_STEPS` even steps over their range
/// (what the file stores, two bytes a post) and adds the half step to its
/// reference delta, so every mesh's error bound covers the rounding.
fn quantise_heights(map: &mut ErrorMap) {
    let finite = map.heights.iter().filter(|h| h.is_finite());
    let (lo, hi) =
        finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| (lo.min(h), hi.max(h)));
    if lo > hi {
        return; // No data: NaN is stored as is.
    }
    // At least 2^3 units in the last place of the largest height, so that
    // a stored height codes back to its own step (the file round-trips).
    let ulps = lo.abs().max(hi.abs()) as f64 * (f32::EPSILON as f64) * 8.0;
    let fitted = ((hi - lo) as f64 / HEIGHT_STEPS).max(ulps).max(f32::MIN_POSITIVE as f64);
    // On the height lattice where the range fits it (a base on a multiple
    // of the step, one step spare for it): neighbours then keep a shared
    // edge's posts at the same heights, to the bit. Else the map's own
    // step, and its edges are not shared: the two sides' heights differ
    // by up to a step (`tests/scene_cracks.rs` found 1 cm), which only a
    // skirt fills.
    let common = SHARED_HEIGHT_STEP as f64;
    let (base, step) = match fitted * HEIGHT_STEPS <= common * (HEIGHT_STEPS - 1.0) {
        true => (((lo as f64 / common).floor() * common) as f32, SHARED_HEIGHT_STEP),
        false => {
            map.shared_edges = 0;
            (lo, fitted as f32)
        }
    };
    map.height_step = step;
    for h in map.heights.iter_mut().filter(|h| h.is_finite()) {
        *h = dequantise(base, step, quantise(base, step, *h));
    }
    // Half a step, and the f32 rounding of the stepped height.
    let rounding = step as f64 / 2.0 + ulps / 8.0;
    map.reference_delta = round_up_to_f32(map.reference_delta as f64 + rounding);
}

/// The step code of height `h` over `base` (finite, within the range).
pub fn quantise(base: f32, step: f32, h: f32) -> u16 {
    ((h as f64 - base as f64) / step as f64).round().clamp(0.0, HEIGHT_STEPS) as u16
}

/// The height of step code `q`.
pub fn dequantise(base: f32, step: f32, q: u16) -> f32 {
    (base as f64 + q as f64 * step as f64) as f32
}

/// The finest level with a node stored under node `id` (`id.level` for a
/// leaf: no child stored).
pub fn finest_stored_level(source: &dyn NodeSource, id: NodeId) -> u8 {
    let layout = source.layout();
    let mut finest = id.level;
    for down in 1..=id.level {
        let level = id.level - down;
        let n = 1u32 << down;
        let any = (0..n).any(|dy| {
            (0..n).any(|dx| {
                let child = NodeId::new(level, id.x * n + dx, id.y * n + dy);
                layout.contains(child) && source.has_node(child)
            })
        });
        if !any {
            break;
        }
        finest = level;
    }
    finest
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stored(heights: &[f32], shared_edges: u8) -> ErrorMap {
        ErrorMap { heights: heights.to_vec(), shared_edges, ..ErrorMap::default() }
    }

    /// Two neighbours over different ranges keep the post on their shared
    /// edge at the same height, to the bit, and within half a step of it.
    #[test]
    fn neighbours_quantise_a_shared_post_alike() {
        let post = 1234.567_f32;
        let mut west = stored(&[312.25, post, 1801.9], ErrorMap::EAST);
        let mut east = stored(&[post, 2044.0, 990.125, f32::NAN], ErrorMap::WEST);
        quantise_heights(&mut west);
        quantise_heights(&mut east);
        assert_eq!(west.heights[1].to_bits(), east.heights[0].to_bits());
        assert!((west.heights[1] - post).abs() <= SHARED_HEIGHT_STEP / 2.0);
        assert_eq!((west.shared_edges, east.shared_edges), (ErrorMap::EAST, ErrorMap::WEST));
        assert!(east.heights[3].is_nan());
        assert!(east.reference_delta >= SHARED_HEIGHT_STEP / 2.0);
    }

    /// A range the height lattice cannot span in `u16` steps keeps its own
    /// step, and shares no edge.
    #[test]
    fn a_range_past_the_height_lattice_shares_no_edge() {
        let mut map = stored(&[-150.0, 1900.0, 2100.5], ErrorMap::NORTH | ErrorMap::EAST);
        quantise_heights(&mut map);
        assert!(map.height_step > SHARED_HEIGHT_STEP);
        assert_eq!(map.shared_edges, 0);
        let within = |h: f32, q: f32| (h - q).abs() <= map.height_step / 2.0 + 1e-3;
        assert!([-150.0, 1900.0, 2100.5].iter().zip(&map.heights).all(|(&h, &q)| within(h, q)));
    }
}
