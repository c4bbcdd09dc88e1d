//! Shards of a pyramid: which nodes each of N processes builds, the
//! pyramid file of one shard's nodes (its *part*), and the merge of the
//! parts with the levels above them into the file one process writes.
//! [`crate::meshes::shards`] adds the error maps and the command's files.
//!
//! - **The split.** A *split level* is chosen from the layout and N alone:
//!   the coarsest level with at least `2 N` nodes, none of them holding
//!   more than `1 / 2N` of the work (the share level if none has), never
//!   finer than the share level ([`NodeLayout::share_level`]).
//!   Its nodes are dealt to the shards in node order (row by row from the
//!   south), in contiguous runs of about equal work, a node's work being
//!   the posts of every layer under it at the layer's own level
//!   ([`Split`]). A shard owns the whole subtrees under its split nodes.
//! - **A part** holds the shard's nodes of the split level and finer, cut
//!   from the layers (the windows they cover) with their deltas: a delta
//!   looks only at the node's own subtree (`pyramid::delta`), so they are
//!   a single process's. It is a pyramid file like any other (its other
//!   nodes absent, its statistics its own), written atomically.
//! - **The merge** copies the parts' nodes level by level in node order
//!   (re-encoded from their posts and summaries, each record checked), then
//!   cuts the levels above the split from the layers as a single process
//!   does, and writes the header: the same bytes.

use std::str::FromStr;

use super::build::{place_layers, BuildOptions};
use super::error::StreamError;
use super::format::{NodeSummary, PyramidInfo};
use super::layers::Composite;
use super::open::Pyramid;
use super::progress::Progress;
use super::stream::{with_prepared, write_pyramid, LevelPlan, PartNodes, StreamOptions};
use crate::dem::GridView;
use crate::geo::GeoRef;
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::spill::ScratchDir;

/// Shard `index` of `count` (`K/N` on the command line, K from 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// K: which shard, `0..count`.
    pub index: u32,
    /// N: how many shards.
    pub count: u32,
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    /// `K/N`: K below N, N at least 1.
    fn from_str(text: &str) -> Result<Shard, String> {
        let expected = || format!("'{text}' is not K/N (shard K of N, K from 0), e.g. 0/4");
        let (k, n) = text.split_once('/').ok_or_else(expected)?;
        let index: u32 = k.trim().parse().map_err(|_| expected())?;
        let count: u32 = n.trim().parse().map_err(|_| expected())?;
        check_count(count).map_err(|problem| format!("{text}: {problem}"))?;
        if index >= count {
            return Err(format!(
                "{text}: K must be below N (the {count} shards are numbered 0 to {})",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }
}

/// Refuses a shard count of 0.
pub fn check_count(count: u32) -> Result<(), String> {
    match count {
        0 => Err("N must be at least 1".into()),
        _ => Ok(()),
    }
}

/// The split level and which shard owns each of its nodes.
pub struct Split {
    /// The level whose nodes are dealt out.
    pub level: u8,
    /// Nodes of the split level per row.
    nodes_x: u32,
    /// Per node of the split level (node order), its shard.
    owner: Vec<u32>,
}

impl Split {
    /// The split of `layout` into `count` shards (see the module notes).
    fn new(layout: &NodeLayout, composite: &Composite, count: u32) -> Split {
        let (level, work) = split_level(layout, composite, count);
        let total: f64 = work.iter().sum();
        let mut before = 0.0;
        let owner = work
            .iter()
            .enumerate()
            .map(|(k, &w)| {
                // The node's middle decides: runs of about total / count.
                // No node exceeds total / 2N, so every run has a middle.
                let share = match total > 0.0 {
                    true => (before + w / 2.0) / total,
                    false => (k as f64 + 0.5) / work.len() as f64,
                };
                before += w;
                ((share * count as f64) as u32).min(count - 1)
            })
            .collect();
        Split { level, nodes_x: layout.nodes_at(level)[0], owner }
    }

    /// The shard owning node `id`, `None` above the split level.
    pub fn owner(&self, id: NodeId) -> Option<u32> {
        let shift = self.level.checked_sub(id.level)?;
        let (x, y) = (id.x >> shift, id.y >> shift);
        self.owner.get(y as usize * self.nodes_x as usize + x as usize).copied()
    }

    /// How many split nodes `shard` owns.
    pub fn owned_by(&self, shard: u32) -> usize {
        self.owner.iter().filter(|&&o| o == shard).count()
    }

    /// How many nodes the split level has.
    pub fn nodes(&self) -> usize {
        self.owner.len()
    }
}

/// The split level and its nodes' work: the coarsest level with at least
/// `2 count` nodes none of which holds more than `1 / (2 count)` of the
/// work (the share level if none does), so that runs of whole nodes come
/// within about half a share of even. Never finer than the share level
/// ([`NodeLayout::share_level`]): a shard then holds every square whose
/// inner node edges its maps share, and builds them as one process does.
fn split_level(layout: &NodeLayout, composite: &Composite, count: u32) -> (u8, Vec<f64>) {
    let wanted = 2 * count as u64;
    let work_at = |level: u8| {
        let [nodes_x, nodes_y] = layout.nodes_at(level);
        let ids = (0..nodes_y).flat_map(|y| (0..nodes_x).map(move |x| NodeId::new(level, x, y)));
        ids.map(|id| node_work(layout, composite, id)).collect::<Vec<f64>>()
    };
    let finest = layout.share_level();
    for level in (finest.max(1)..layout.levels).rev() {
        if layout.nodes_at_count(level) < wanted {
            continue;
        }
        let work = work_at(level);
        let total: f64 = work.iter().sum();
        if work.iter().all(|&w| w * wanted as f64 <= total) {
            return (level, work);
        }
    }
    (finest, work_at(finest))
}

/// The work under node `id`: per layer, its posts there at its own level.
fn node_work(layout: &NodeLayout, composite: &Composite, id: NodeId) -> f64 {
    let span = layout.span(id.level) as f64;
    let area = [id.x as f64 * span, id.y as f64 * span];
    composite
        .layers
        .iter()
        .map(|layer| {
            let [[x0, x1], [y0, y1]] = layer.bounds();
            let wide = (x1.min(area[0] + span) - x0.max(area[0])).max(0.0);
            let tall = (y1.min(area[1] + span) - y0.max(area[1])).max(0.0);
            wide * tall / 4f64.powi(layer.native as i32)
        })
        .sum()
}

/// The CRC-32 of everything a shard's part depends on but K: the layers'
/// placement and heights, the build options, N and the caller's `salt`
/// (its own options). `release` is called after every band of heights.
pub fn inputs_key(
    layers: &[GridView],
    build: &BuildOptions,
    count: u32,
    salt: &[u8],
    release: &dyn Fn(),
) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(b"ridgeline shards 1");
    hasher.update(format!("{count} {build:?} {} ", layers.len()).as_bytes());
    hasher.update(salt);
    for layer in layers {
        let placed =
            format!("{} {} {:?} {}", layer.width, layer.height, layer.georef, layer.voids_filled);
        hasher.update(placed.as_bytes());
        for band in layer.heights.chunks(8 << 20) {
            hasher.update(bytemuck::cast_slice(band));
            release();
        }
    }
    hasher.finalize()
}

/// The layout and georeference a build of `layers` has (without their
/// blend weights, which do not change it).
pub fn layout_of(
    layers: &[GridView],
    build: &BuildOptions,
) -> Result<(NodeLayout, GeoRef), StreamError> {
    let weights = vec![None; layers.len()];
    let (layout, georef, _) = place_layers(layers, &weights, build)?;
    Ok((layout, georef))
}

/// What a shard's part holds.
#[derive(Clone, Copy, Debug)]
pub struct PartReport {
    /// The split level.
    pub split_level: u8,
    /// Split nodes the shard owns, and the split level's nodes.
    pub split_nodes: [usize; 2],
}

/// Writes shard `shard`'s part of the pyramid of `layers` to `path`,
/// atomically; `scratch` and `release` as for
/// [`build_streaming`](super::build_streaming).
pub fn build_part(
    layers: &[GridView],
    scratch: &ScratchDir,
    options: &StreamOptions,
    shard: Shard,
    path: &std::path::Path,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> Result<PartReport, StreamError> {
    with_prepared(layers, scratch, options, release, progress, |prepared, release| {
        let split = Split::new(&prepared.layout, &prepared.composite, shard.count);
        let keep = |id: NodeId| split.owner(id) == Some(shard.index);
        let plan = LevelPlan {
            copied: 0,
            parts: None,
            top: split.level + 1,
            keep: Some(&keep),
            whole: false,
        };
        write_pyramid(prepared, &plan, path, release, progress)?;
        let split_nodes = [split.owned_by(shard.index), split.nodes()];
        Ok(PartReport { split_level: split.level, split_nodes })
    })
}

/// Writes the pyramid of `layers` to `path`, atomically, its levels up to
/// the split copied from `parts` (shard K's part at K, opened and checked
/// against the inputs by the caller), the others cut from the layers.
/// Returns what it wrote and the split level.
pub fn merge_parts(
    layers: &[GridView],
    scratch: &ScratchDir,
    options: &StreamOptions,
    parts: &[Pyramid],
    path: &std::path::Path,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> Result<(PyramidInfo, u8), StreamError> {
    with_prepared(layers, scratch, options, release, progress, |prepared, release| {
        let split = Split::new(&prepared.layout, &prepared.composite, parts.len() as u32);
        let nodes = OwnedNodes { split: &split, pyramids: parts };
        let plan = LevelPlan {
            copied: split.level + 1,
            parts: Some(&nodes),
            top: u8::MAX,
            keep: None,
            whole: true,
        };
        let info = write_pyramid(prepared, &plan, path, release, progress)?;
        Ok((info, split.level))
    })
}

/// The nodes of the split level and finer, each from its owner's part.
struct OwnedNodes<'a> {
    split: &'a Split,
    pyramids: &'a [Pyramid],
}

impl PartNodes for OwnedNodes<'_> {
    fn node(&self, id: NodeId) -> Result<Option<(Vec<f32>, NodeSummary)>, NodeError> {
        let Some(pyramid) = self.split.owner(id).and_then(|k| self.pyramids.get(k as usize)) else {
            return Ok(None);
        };
        if !pyramid.has_node(id) {
            return Ok(None);
        }
        let mut data = NodeData::with_capacity(pyramid.layout());
        pyramid.read_node(id, &mut data)?;
        let summary = NodeSummary { min: data.min, max: data.max, delta: data.delta };
        Ok(Some((data.heights, summary)))
    }

    fn release_pages(&self) {
        self.pyramids.iter().for_each(NodeSource::release_pages);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shard_is_k_of_n_with_k_below_n() {
        assert_eq!("2/4".parse(), Ok(Shard { index: 2, count: 4 }));
        let refused = |text: &str, says: &str| {
            let problem = text.parse::<Shard>().expect_err(text);
            assert!(problem.contains(says), "{text}: {problem}");
        };
        refused("4/4", "K must be below N");
        refused("0/0", "N must be at least 1");
        refused("1", "is not K/N");
        refused("a/4", "is not K/N");
        refused("-1/4", "is not K/N");
    }
}
