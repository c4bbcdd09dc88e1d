//! Building the pyramid in memory from an elevation grid: level by level,
//! downsample the level raster, cut it into nodes with their borders, and
//! measure each node's delta against the full-resolution grid.

use rayon::prelude::*;

use super::delta::level_deltas;
use super::error::BuildError;
use super::format::{GridStats, LevelSummary, NodeSummary, PyramidInfo};
use super::limits::{check_levels, check_node};
use super::progress::Progress;
use super::raster::LevelRaster;
use crate::dem::ElevationGrid;
use crate::node::{NodeId, NodeLayout};

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

/// One level's nodes in memory.
struct BuiltLevel {
    /// Node `n`'s stored posts are `heights[n * side^2..(n + 1) * side^2]`.
    heights: Vec<f32>,
    summaries: Vec<NodeSummary>,
}

/// A whole pyramid in memory, ready for [`write_atomic`](super::write_atomic).
pub struct BuiltPyramid {
    /// The header's content: layout, georeference, statistics, level summaries.
    pub info: PyramidInfo,
    levels: Vec<BuiltLevel>,
}

impl BuiltPyramid {
    /// The node layout the pyramid was built with.
    pub fn layout(&self) -> &NodeLayout {
        &self.info.layout
    }

    /// The stored posts (border included) and summary of node `id`.
    pub fn node(&self, id: NodeId) -> Option<(&[f32], NodeSummary)> {
        if !self.info.layout.contains(id) {
            return None;
        }
        let level = &self.levels[id.level as usize];
        let index = id.y as usize * self.info.layout.nodes_at(id.level)[0] as usize + id.x as usize;
        let posts = self.info.layout.stored_side() as usize;
        let posts = posts * posts;
        Some((&level.heights[index * posts..(index + 1) * posts], level.summaries[index]))
    }

    /// Every node's posts and summary in file order (finest level first).
    pub(crate) fn levels(&self) -> impl Iterator<Item = (&[f32], &[NodeSummary])> {
        self.levels.iter().map(|l| (l.heights.as_slice(), l.summaries.as_slice()))
    }

    /// Summaries of all nodes in file order.
    pub fn node_summaries(&self) -> Vec<NodeSummary> {
        self.levels.iter().flat_map(|l| l.summaries.iter().copied()).collect()
    }
}

/// Builds the pyramid of `grid`, using every core rayon offers.
pub fn build(
    grid: &ElevationGrid,
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<BuiltPyramid, BuildError> {
    let (layout, stats) = check_input(grid, options)?;
    let mut levels = Vec::with_capacity(layout.levels as usize);
    let mut summaries = Vec::with_capacity(layout.levels as usize);
    let mut raster = LevelRaster::finest(grid);
    for lod in 0..layout.levels {
        if lod > 0 {
            raster = raster.downsample();
        }
        let nodes = layout.nodes_at(lod);
        progress.phase(&format!("level {lod}: split"), layout.nodes_at_count(lod));
        let (heights, mut node_summaries) = split_level(&raster, &layout, progress);
        progress.phase(&format!("level {lod}: delta"), grid.height as u64);
        let deltas = level_deltas(grid, &raster, nodes, layout.span(lod), progress);
        node_summaries.iter_mut().zip(deltas).for_each(|(s, delta)| s.delta = delta);
        debug_assert_eq!(
            heights.len(),
            node_summaries.len() * (layout.stored_side() as usize).pow(2)
        );
        summaries.push(summarise_level(nodes, &node_summaries));
        levels.push(BuiltLevel { heights, summaries: node_summaries });
    }
    let info = PyramidInfo { layout, georef: grid.georef, stats, levels: summaries };
    Ok(BuiltPyramid { info, levels })
}

/// The layout for `grid` and its height statistics, or why it cannot be built.
fn check_input(
    grid: &ElevationGrid,
    options: &BuildOptions,
) -> Result<(NodeLayout, GridStats), BuildError> {
    let BuildOptions { node_size, border } = *options;
    check_node(node_size, border).map_err(BuildError::InvalidOptions)?;
    let samples = [grid.width, grid.height];
    let expected = (grid.width as usize).checked_mul(grid.height as usize);
    if samples.contains(&0) || expected != Some(grid.heights.len()) {
        return Err(BuildError::InvalidGrid(format!(
            "{samples:?} samples but {} heights",
            grid.heights.len()
        )));
    }
    if let Some(problem) = grid.georef.problem(samples) {
        return Err(BuildError::InvalidGrid(problem));
    }
    if let Some(index) = grid.heights.par_iter().position_any(|h| !h.is_finite()) {
        let (i, j) = (index % grid.width as usize, index / grid.width as usize);
        return Err(BuildError::InvalidGrid(format!(
            "height at sample ({i}, {j}) is {}",
            grid.heights[index]
        )));
    }
    let levels = NodeLayout::levels_for(samples, node_size);
    check_levels(levels).map_err(BuildError::InvalidOptions)?;
    let layout = NodeLayout {
        levels,
        node_size,
        border,
        posts: samples,
        spacing_m: grid.georef.spacing_m(samples),
    };
    let (height_min, height_max) = min_max(&grid.heights);
    Ok((layout, GridStats { height_min, height_max, voids_filled: grid.voids_filled }))
}

fn min_max(heights: &[f32]) -> (f32, f32) {
    heights
        .par_iter()
        .fold(|| (f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| (lo.min(h), hi.max(h)))
        .reduce(|| (f32::INFINITY, f32::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// Cuts level `raster.level` into its nodes, border included (Kühnert's split
/// and stitch), in parallel; summaries carry min and max, delta comes later.
fn split_level(
    raster: &LevelRaster,
    layout: &NodeLayout,
    progress: &dyn Progress,
) -> (Vec<f32>, Vec<NodeSummary>) {
    let [nodes_x, nodes_y] = layout.nodes_at(raster.level);
    let side = layout.stored_side() as usize;
    let mut heights = vec![0.0f32; nodes_x as usize * nodes_y as usize * side * side];
    let summaries = heights
        .par_chunks_mut(side * side)
        .enumerate()
        .map(|(n, posts)| {
            let (x, y) = (n as u32 % nodes_x, n as u32 / nodes_x);
            let summary = cut_node(raster, layout, x, y, posts);
            progress.advance(1);
            summary
        })
        .collect();
    (heights, summaries)
}

/// Copies node `(x, y)`'s window of the raster into `posts`; posts past the
/// raster's edge repeat its edge (Kühnert's rule for borders without a
/// neighbour). Returns the min and max of the centre posts.
fn cut_node(
    raster: &LevelRaster,
    layout: &NodeLayout,
    x: u32,
    y: u32,
    posts: &mut [f32],
) -> NodeSummary {
    let side = layout.stored_side() as usize;
    let border = layout.border as i64;
    let centre = border as usize..=border as usize + layout.node_size as usize;
    let first = |node: u32| node as i64 * layout.node_size as i64 - border;
    let clamp = |index: i64, count: u32| index.clamp(0, count as i64 - 1) as u32;
    let columns: Vec<usize> =
        (0..side as i64).map(|p| clamp(first(x) + p, raster.cols) as usize).collect();
    let mut summary = NodeSummary { min: f32::INFINITY, max: f32::NEG_INFINITY, delta: 0.0 };
    for (q, out) in posts.chunks_exact_mut(side).enumerate() {
        let row = raster.row(clamp(first(y) + q as i64, raster.rows));
        for (post, &k) in out.iter_mut().zip(&columns) {
            *post = row[k];
        }
        if centre.contains(&q) {
            for &h in &out[centre.clone()] {
                summary.min = summary.min.min(h);
                summary.max = summary.max.max(h);
            }
        }
    }
    debug_assert!(summary.min <= summary.max);
    summary
}

fn summarise_level(nodes: [u32; 2], summaries: &[NodeSummary]) -> LevelSummary {
    let fold = |f: fn(f32, f32) -> f32, pick: fn(&NodeSummary) -> f32, init: f32| {
        summaries.iter().map(pick).fold(init, f)
    };
    LevelSummary {
        nodes,
        delta_max: fold(f32::max, |s| s.delta, 0.0),
        height_min: fold(f32::min, |s| s.min, f32::INFINITY),
        height_max: fold(f32::max, |s| s.max, f32::NEG_INFINITY),
    }
}
