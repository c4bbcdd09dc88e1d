//! Building the pyramid in memory from one or more layers of elevation data:
//! level by level, the nodes that data of that resolution reach are cut out
//! of the composite surface (see [`super::layers`]), border included, and
//! each node's delta is measured against the best data under it.

use rayon::prelude::*;

use super::built::{node_of, BuiltLevel, BuiltPyramid};
use super::delta::{node_delta, InMemory};
use super::error::BuildError;
use super::format::{GridStats, LevelSummary, NodeSummary, PostWindow, PyramidInfo};
use super::layers::{blend_weights, Composite, PlacedLayer};
use super::limits::{check_levels, check_node, MAX_POSTS_PER_SIDE};
use super::progress::Progress;
use crate::dem::ElevationGrid;
use crate::dem::GridView;
use crate::geo::GeoRef;
use crate::node::{NodeId, NodeLayout};

/// Relative slack when comparing spacings and lattice positions.
const LATTICE_SLACK: f64 = 1e-6;

/// How to cut the grid into nodes (see the module notes in [`super`] for the
/// defaults).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Cells per node side.
    pub node_size: u32,
    /// Posts repeated from the neighbours on each side of a node.
    pub border: u32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions { node_size: 64, border: 2 }
    }
}

/// Builds the pyramid of one grid (NaN heights are no-data), using every
/// core rayon offers.
pub fn build(
    grid: &ElevationGrid,
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<BuiltPyramid, BuildError> {
    build_layers(std::slice::from_ref(grid), options, progress)
}

/// Builds one pyramid from `layers` of any resolutions, extents and
/// lattices in one coordinate system: finer data win where they exist, each
/// level holds nodes only where data at least as coarse as the level are
/// (see [`super::layers`] for the lattice, the native level of a layer and
/// the blend). Where several layers share a spacing, the first given wins.
pub fn build_layers(
    layers: &[ElevationGrid],
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<BuiltPyramid, BuildError> {
    let views: Vec<GridView> = layers.iter().map(ElevationGrid::view).collect();
    check_options(options)?;
    for (k, layer) in views.iter().enumerate() {
        check_layer(k, *layer, &mut || {})?;
    }
    let weights: Vec<Option<Vec<f32>>> = weighted(&views)
        .into_iter()
        .zip(&views)
        .map(|(weighted, v)| {
            weighted.then(|| blend_weights(*v, v.georef.spacing_m([v.width, v.height])))
        })
        .collect();
    let weights: Vec<Option<&[f32]>> = weights.iter().map(Option::as_deref).collect();
    let (layout, georef, composite) = place_layers(&views, &weights, options)?;
    let finest = finest_window(&composite);
    let mut levels: Vec<BuiltLevel> = Vec::with_capacity(layout.levels as usize);
    for lod in 0..layout.levels {
        let below = levels.last().map(|l| l.slots.as_slice());
        let candidates = candidates(&layout, &composite, lod, below);
        progress.phase(&format!("level {lod}: nodes"), candidates.len() as u64);
        levels.push(cut_level(&layout, &composite, lod, &candidates, progress));
    }
    let mut summaries = Vec::with_capacity(levels.len());
    for lod in 0..layout.levels {
        let present = levels[lod as usize].summaries.len();
        progress.phase(&format!("level {lod}: delta"), present as u64);
        let deltas: Vec<f32> = if lod == 0 {
            // Level 0 passes through every post of the best data.
            vec![0.0; present]
        } else {
            let level = &levels[lod as usize];
            let ids = present_ids(&layout, lod, level);
            let finer = InMemory { levels: &levels, layout: &layout };
            ids.par_iter()
                .map(|&id| {
                    let (posts, _) = node_of(&levels, &layout, id).expect("a present node");
                    let delta = node_delta(&finer, &layout, id, posts);
                    progress.advance(1);
                    delta
                })
                .collect()
        };
        let level = &mut levels[lod as usize];
        level.summaries.iter_mut().zip(deltas).for_each(|(s, delta)| s.delta = delta);
        let nodes = layout.nodes_at(lod);
        summaries.push(summarise_level(nodes, &level.summaries, &level.has_data));
    }
    let stats = grid_stats(&summaries, &composite, &mut || {})?;
    let layer_count = layers.len() as u32;
    let info =
        PyramidInfo { layout, georef, stats, layers: layer_count, finest, levels: summaries };
    Ok(BuiltPyramid { info, levels })
}

/// The level-0 posts of the finest layer on the lattice (see [`PyramidInfo::finest`]).
pub(super) fn finest_window(composite: &Composite) -> PostWindow {
    composite
        .layers
        .iter()
        .filter_map(|l| l.exact.map(|first| (first, l.grid)))
        .min_by(|a, b| spacing_area(&a.1).total_cmp(&spacing_area(&b.1)))
        .map(|(first, grid)| PostWindow {
            first: first.map(|f| f.max(0) as u32),
            posts: [grid.width, grid.height],
        })
        .unwrap_or_default()
}

/// Heights checked or counted between two calls of a `band_done`
/// callback: 32 MB of `f32`, so memory-mapped layers can drop their pages.
const BAND_POSTS: usize = 8 << 20;

/// Rows of `grid` in bands of about [`BAND_POSTS`] posts: the first row
/// and the rows of each band.
fn row_bands(grid: GridView) -> impl Iterator<Item = std::ops::Range<u32>> {
    let rows = (BAND_POSTS / grid.width.max(1) as usize).max(1) as u32;
    (0..grid.height.div_ceil(rows)).map(move |b| b * rows..((b + 1) * rows).min(grid.height))
}

/// The posts of rows `rows` of `grid`.
fn rows_of<'a>(grid: GridView<'a>, rows: &std::ops::Range<u32>) -> &'a [f32] {
    let w = grid.width as usize;
    &grid.heights[rows.start as usize * w..rows.end as usize * w]
}

/// Per layer, whether it is blended over coarser ones and needs blend
/// weights (every layer but the coarsest, see [`place_layers`]).
pub(super) fn weighted(layers: &[GridView]) -> Vec<bool> {
    let order = coarsest_first(layers);
    let mut weighted = vec![false; layers.len()];
    order.iter().skip(1).for_each(|&k| weighted[k] = true);
    weighted
}

/// Layer indices coarsest first; among equal spacings the first given
/// last, so it wins.
fn coarsest_first(layers: &[GridView]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..layers.len()).collect();
    order.sort_by(|&a, &b| {
        spacing_area(&layers[b]).total_cmp(&spacing_area(&layers[a])).then(b.cmp(&a))
    });
    order
}

pub(super) fn check_options(options: &BuildOptions) -> Result<(), BuildError> {
    let BuildOptions { node_size, border } = *options;
    check_node(node_size, border).map_err(BuildError::InvalidOptions)?;
    Ok(())
}

/// Why layer `k` cannot be built, if it cannot; `band_done` is called
/// after each band of rows.
pub(super) fn check_layer(
    k: usize,
    grid: GridView,
    band_done: &mut dyn FnMut(),
) -> Result<(), BuildError> {
    let fail = |why: String| Err(BuildError::InvalidGrid(format!("layer {}: {why}", k + 1)));
    let samples = [grid.width, grid.height];
    let expected = (grid.width as usize).checked_mul(grid.height as usize);
    if samples.contains(&0) || expected != Some(grid.heights.len()) {
        return fail(format!("{samples:?} samples but {} heights", grid.heights.len()));
    }
    if let Some(problem) = grid.georef.problem(samples) {
        return fail(problem);
    }
    let mut any_data = false;
    for rows in row_bands(grid) {
        let band = rows_of(grid, &rows);
        if let Some(index) = band.par_iter().position_any(|h| h.is_infinite()) {
            let index = index + rows.start as usize * grid.width as usize;
            let (i, j) = (index % grid.width as usize, index / grid.width as usize);
            return fail(format!("height at sample ({i}, {j}) is {}", grid.heights[index]));
        }
        any_data = any_data || band.par_iter().any(|h| !h.is_nan());
        band_done();
    }
    if !any_data {
        return fail("no post has data".into());
    }
    Ok(())
}

fn spacing_area(grid: &GridView) -> f64 {
    grid.georef.spacing[0] * grid.georef.spacing[1]
}

/// The lattice of `finest`'s spacing, through its posts, that spans every
/// layer: its origin and posts per side.
fn lattice(
    layers: &[GridView<'_>],
    finest: &GridView<'_>,
) -> Result<([f64; 2], [u32; 2]), BuildError> {
    let spacing = finest.georef.spacing;
    let mut low = [f64::INFINITY; 2];
    let mut high = [f64::NEG_INFINITY; 2];
    for layer in layers {
        let size = [layer.width, layer.height];
        for a in 0..2 {
            low[a] = low[a].min(layer.georef.origin[a]);
            let last = layer.georef.origin[a] + (size[a] - 1) as f64 * layer.georef.spacing[a];
            high[a] = high[a].max(last);
        }
    }
    let mut origin = [0.0; 2];
    let mut posts = [0u32; 2];
    for a in 0..2 {
        let before = ((finest.georef.origin[a] - low[a]) / spacing[a] - LATTICE_SLACK).ceil();
        origin[a] = finest.georef.origin[a] - before.max(0.0) * spacing[a];
        let count = ((high[a] - origin[a]) / spacing[a] + LATTICE_SLACK).floor() + 1.0;
        if !(count >= 1.0 && count <= MAX_POSTS_PER_SIDE as f64) {
            return Err(BuildError::InvalidGrid(format!(
                "the layers span {count} posts of the finest spacing {spacing:?}; at most \
                 {MAX_POSTS_PER_SIDE} per side"
            )));
        }
        posts[a] = count as u32;
    }
    Ok((origin, posts))
}

/// The level-0 lattice over the union of `layers`, its layout and
/// georeference, and the layers placed on it, coarsest first.
pub(super) fn place_layers<'a>(
    layers: &[GridView<'a>],
    weights: &[Option<&'a [f32]>],
    options: &BuildOptions,
) -> Result<(NodeLayout, GeoRef, Composite<'a>), BuildError> {
    let Some(first) = layers.first() else {
        return Err(BuildError::InvalidGrid("no layer to build".into()));
    };
    let crs = first.georef.crs;
    if let Some((k, other)) = layers.iter().enumerate().find(|(_, l)| l.georef.crs != crs) {
        return Err(BuildError::InvalidGrid(format!(
            "layer {} is in {:?} but layer 1 in {crs:?}: all layers must share one coordinate system",
            k + 1,
            other.georef.crs
        )));
    }
    let finest = layers
        .iter()
        .enumerate()
        .min_by(|a, b| spacing_area(a.1).total_cmp(&spacing_area(b.1)).then(a.0.cmp(&b.0)))
        .map(|(_, l)| l)
        .expect("at least one layer");
    let spacing = finest.georef.spacing;
    let (origin, posts) = lattice(layers, finest)?;
    let georef = GeoRef { crs, origin, spacing };
    if let Some(problem) = georef.problem(posts) {
        return Err(BuildError::InvalidGrid(problem));
    }
    let levels = NodeLayout::levels_for(posts, options.node_size);
    check_levels(levels).map_err(BuildError::InvalidOptions)?;
    let layout = NodeLayout {
        levels,
        node_size: options.node_size,
        border: options.border,
        posts,
        spacing_m: georef.spacing_m(posts),
    };
    let placed = coarsest_first(layers)
        .iter()
        .map(|&k| {
            let grid = layers[k];
            let offset = [0, 1].map(|a| (grid.georef.origin[a] - origin[a]) / spacing[a]);
            let scale = [0, 1].map(|a| grid.georef.spacing[a] / spacing[a]);
            let on_lattice = (0..2).all(|a| {
                (scale[a] - 1.0).abs() < LATTICE_SLACK
                    && (offset[a] - offset[a].round()).abs() < 1e-3
            });
            let exact = on_lattice.then(|| offset.map(|o| o.round() as i64));
            let ratio = scale[0].min(scale[1]) * (1.0 + LATTICE_SLACK);
            let native = (ratio.max(1.0).log2().floor() as u8).min(levels - 1);
            let weights = weights[k];
            let last = posts.map(|p| p as i64 - 1);
            PlacedLayer { grid, offset, scale, exact, native, last, weights }
        })
        .collect();
    Ok((layout, georef, Composite { layers: placed }))
}

/// Nodes of `lod` that may hold data: those meeting a layer whose native
/// level is `lod` or finer, and the parents of every present node of the
/// level below (so every present node's ancestors are present), the latter
/// marked `true`.
pub(super) fn candidates(
    layout: &NodeLayout,
    composite: &Composite,
    lod: u8,
    below: Option<&[Option<u32>]>,
) -> Vec<(NodeId, bool)> {
    let [nodes_x, nodes_y] = layout.nodes_at(lod);
    let mut wanted = vec![false; nodes_x as usize * nodes_y as usize];
    let mut parent = vec![false; wanted.len()];
    let span = layout.span(lod) as f64;
    for layer in composite.layers.iter().filter(|l| l.native <= lod) {
        let [[x0, x1], [y0, y1]] = layer.bounds();
        let range = |low: f64, high: f64, count: u32| {
            let first = ((low / span).floor() - 1.0).max(0.0) as u32;
            let last = ((high / span).floor() as u32).min(count - 1);
            first..=last
        };
        for y in range(y0, y1, nodes_y) {
            for x in range(x0, x1, nodes_x) {
                let (a, b) = (x as f64 * span, (x + 1) as f64 * span);
                let (c, d) = (y as f64 * span, (y + 1) as f64 * span);
                if a <= x1 && b >= x0 && c <= y1 && d >= y0 {
                    wanted[(y * nodes_x + x) as usize] = true;
                }
            }
        }
    }
    if let Some(below) = below {
        let [child_x, _] = layout.nodes_at(lod - 1);
        for (index, slot) in below.iter().enumerate() {
            if slot.is_some() {
                let (x, y) = (index as u32 % child_x / 2, index as u32 / child_x / 2);
                parent[(y * nodes_x + x) as usize] = true;
            }
        }
    }
    (0..wanted.len())
        .filter(|&k| wanted[k] || parent[k])
        .map(|k| (NodeId::new(lod, k as u32 % nodes_x, k as u32 / nodes_x), parent[k]))
        .collect()
}

/// Cuts the `candidates` of level `lod` out of the composite, in parallel;
/// a candidate whose centre posts are all no-data is absent unless it is
/// the parent of a present node.
fn cut_level(
    layout: &NodeLayout,
    composite: &Composite,
    lod: u8,
    candidates: &[(NodeId, bool)],
    progress: &dyn Progress,
) -> BuiltLevel {
    let side = layout.stored_side() as usize;
    let cut: Vec<Option<(Vec<f32>, NodeSummary, bool)>> = candidates
        .par_iter()
        .map(|&(id, parent)| {
            let mut posts = vec![0.0f32; side * side];
            let (summary, has_data) = cut_node(layout, composite, id, &mut posts);
            progress.advance(1);
            (has_data || parent).then_some((posts, summary, has_data))
        })
        .collect();
    let [nodes_x, nodes_y] = layout.nodes_at(lod);
    let mut level = BuiltLevel {
        slots: vec![None; nodes_x as usize * nodes_y as usize],
        heights: Vec::new(),
        summaries: Vec::new(),
        has_data: Vec::new(),
    };
    for ((id, _), node) in candidates.iter().zip(cut) {
        let Some((posts, summary, has_data)) = node else { continue };
        let index = id.y as usize * nodes_x as usize + id.x as usize;
        level.slots[index] = Some(level.summaries.len() as u32);
        level.heights.extend_from_slice(&posts);
        level.summaries.push(summary);
        level.has_data.push(has_data);
    }
    level
}

/// Fills node `id`'s stored posts from the composite; positions beyond the
/// data's edge take the edge post's place (Kühnert's rule for borders
/// without a neighbour). Returns the min and max of the centre posts with
/// data (0 and 0 when there are none) and whether there were any.
pub(super) fn cut_node(
    layout: &NodeLayout,
    composite: &Composite,
    id: NodeId,
    posts: &mut [f32],
) -> (NodeSummary, bool) {
    let side = layout.stored_side() as i64;
    let border = layout.border as i64;
    let span = layout.span(id.level) as i64;
    let step = 1i64 << id.level;
    let position = |node: u32, p: i64, count: u32| {
        (node as i64 * span + (p - border) * step).clamp(0, count as i64 - 1)
    };
    let centre = border..=border + layout.node_size as i64;
    let mut summary = NodeSummary { min: f32::INFINITY, max: f32::NEG_INFINITY, delta: 0.0 };
    for (q, row) in posts.chunks_exact_mut(side as usize).enumerate() {
        let y = position(id.y, q as i64, layout.posts[1]);
        for (p, post) in row.iter_mut().enumerate() {
            let x = position(id.x, p as i64, layout.posts[0]);
            *post = composite.height(x, y);
            if centre.contains(&(q as i64)) && centre.contains(&(p as i64)) && !post.is_nan() {
                summary.min = summary.min.min(*post);
                summary.max = summary.max.max(*post);
            }
        }
    }
    let has_data = summary.min <= summary.max;
    if !has_data {
        summary.min = 0.0;
        summary.max = 0.0;
    }
    (summary, has_data)
}

/// The ids of a level's present nodes in slot order.
fn present_ids(layout: &NodeLayout, lod: u8, level: &BuiltLevel) -> Vec<NodeId> {
    let [nodes_x, _] = layout.nodes_at(lod);
    level
        .slots
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_some())
        .map(|(k, _)| NodeId::new(lod, k as u32 % nodes_x, k as u32 / nodes_x))
        .collect()
}

pub(super) fn summarise_level(
    nodes: [u32; 2],
    summaries: &[NodeSummary],
    has_data: &[bool],
) -> LevelSummary {
    let with_data = || summaries.iter().zip(has_data).filter(|(_, d)| **d);
    let height_min = with_data().map(|(s, _)| s.min).fold(f32::INFINITY, f32::min);
    let height_max = with_data().map(|(s, _)| s.max).fold(f32::NEG_INFINITY, f32::max);
    let (height_min, height_max) =
        if height_min <= height_max { (height_min, height_max) } else { (0.0, 0.0) };
    LevelSummary {
        nodes,
        present: summaries.len() as u64,
        delta_max: summaries.iter().map(|s| s.delta).fold(0.0, f32::max),
        height_min,
        height_max,
    }
}

/// Heights over every level and the void counts of the layers;
/// `band_done` is called after each band of rows.
pub(super) fn grid_stats(
    levels: &[LevelSummary],
    composite: &Composite,
    band_done: &mut dyn FnMut(),
) -> Result<GridStats, BuildError> {
    let with_data = levels.iter().filter(|l| l.present > 0 && l.height_min <= l.height_max);
    let (height_min, height_max) = with_data
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), l| {
            (lo.min(l.height_min), hi.max(l.height_max))
        });
    if height_min.partial_cmp(&height_max).is_none_or(|o| o.is_gt()) {
        return Err(BuildError::InvalidGrid("no post of any layer has data".into()));
    }
    let mut stats = GridStats {
        height_min,
        height_max,
        voids_filled: composite.layers.iter().map(|l| l.grid.voids_filled).sum(),
        posts_from_layer: 0,
        posts_no_data: 0,
    };
    for (k, layer) in composite.layers.iter().enumerate() {
        let grid = layer.grid;
        for rows in row_bands(grid) {
            let (from_layer, no_data) = void_counts(composite, k, rows);
            stats.posts_from_layer += from_layer;
            stats.posts_no_data += no_data;
            band_done();
        }
    }
    Ok(stats)
}

/// Of the void posts of layer `k` in `rows`: how many another layer
/// covers, and how many have no data.
fn void_counts(composite: &Composite, k: usize, rows: std::ops::Range<u32>) -> (u64, u64) {
    let layer = &composite.layers[k];
    let grid = layer.grid;
    rows.into_par_iter()
        .map(|q| {
            let row = &grid.heights[q as usize * grid.width as usize..][..grid.width as usize];
            let mut counts = (0u64, 0u64);
            for (p, h) in row.iter().enumerate() {
                if !h.is_nan() {
                    continue;
                }
                let x = (layer.offset[0] + p as f64 * layer.scale[0]).round() as i64;
                let y = (layer.offset[1] + q as f64 * layer.scale[1]).round() as i64;
                if composite.height_without(x, y, k).is_nan() {
                    counts.1 += 1;
                } else {
                    counts.0 += 1;
                }
            }
            counts
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}
