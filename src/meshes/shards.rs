//! A dataset built by N shards and merged: each shard's two parts (its
//! pyramid part, see [`crate::pyramid::shard`], and the error maps of its
//! nodes) and the merge into `pyramid.rlp` and `meshes.rlm`, the bytes
//! one process writes.
//!
//! - **Files.** Shard K of N writes `DIR/shard-K-of-N.rlp` and then
//!   `DIR/shard-K-of-N.rlm`, each renamed into place when complete: a
//!   killed shard leaves the previous part or none (and a temporary its
//!   rerun removes), and a rerun writes the same bytes. A node's map looks
//!   only at the node's own subtree ([`super::build`]) and, for its shared
//!   edges, at its share square's, which the shard holds whole (the split
//!   is never finer than the share level), so a shard's maps are a single
//!   process's.
//! - **Identity.** The map part's header carries, where a whole map file
//!   carries its pyramid's identity, the CRC-32 of the *inputs key*
//!   ([`inputs_key`]: the layers' placement and heights, node size and
//!   border, N and the mesh options), K and the identity of the pyramid
//!   part it was built from. The merge computes the same from its own
//!   inputs: a part of other sources, options, shard count or shard, or a
//!   map part older than its pyramid part, is refused, naming the file.
//! - **The merge** checks that every part is there, whole (every record's
//!   checksum) and belongs to its inputs before it writes anything, writes the new pyramid and map file
//!   beside the dataset (`DIR/.merge-*`), and renames them over the old
//!   ones only once both are complete: a failed merge leaves the previous
//!   dataset as it was.

use std::path::{Path, PathBuf};

use super::file::{build_store, merge_parts, pyramid_identity, MapFile, MAP_FILE_NAME};
use super::source::stored_nodes;
use super::{MeshOptions, MeshesError};
use crate::dem::GridView;
use crate::node::{NodeData, NodeError, NodeId, NodeSource, SHARE_LEVEL};
use crate::pyramid::shard::{self, check_count, inputs_key, Shard};
use crate::pyramid::{sync_dir, Progress, Pyramid, PyramidError, PyramidInfo, StreamError};
use crate::pyramid::{StreamOptions, FILE_NAME};
use crate::spill::ScratchDir;
use rayon::prelude::*;

/// The two parts shard K of N writes into the dataset's directory.
#[derive(Clone, Debug)]
pub struct PartPaths {
    /// The pyramid file of the shard's nodes.
    pub pyramid: PathBuf,
    /// The map file part of the shard's nodes.
    pub meshes: PathBuf,
}

impl PartPaths {
    /// `dir/shard-K-of-N.rlp` and `.rlm`.
    pub fn of(dir: &Path, shard: Shard) -> PartPaths {
        let stem = format!("shard-{}-of-{}", shard.index, shard.count);
        PartPaths {
            pyramid: dir.join(format!("{stem}.rlp")),
            meshes: dir.join(format!("{stem}.rlm")),
        }
    }
}

/// How the shards and the merge build: the same for all of them.
#[derive(Clone, Copy, Debug)]
pub struct ShardOptions {
    /// Node size, border and memory (the memory may differ between them).
    pub stream: StreamOptions,
    /// How the error maps are built.
    pub meshes: MeshOptions,
}

/// Why a shard or a merge failed. Every variant names the file or option.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// The shard count is 0.
    #[error("{count} shards: {problem}")]
    Count {
        /// The count given.
        count: u32,
        /// Why it is refused.
        problem: String,
    },
    /// A part the merge needs is not there.
    #[error(
        "{path}: missing: run `ridgeline import --shard {shard}` with the merge's sources and options first"
    )]
    Missing {
        /// The part.
        path: PathBuf,
        /// The shard that writes it.
        shard: Shard,
    },
    /// A part is damaged or belongs to other inputs (`problem` names it).
    #[error(
        "{problem}; rerun `ridgeline import --shard {shard}` with the merge's sources and options"
    )]
    Part {
        /// The shard that writes it.
        shard: Shard,
        /// What is wrong, naming the file.
        problem: String,
    },
    /// Building the pyramid or a part of it failed.
    #[error(transparent)]
    Stream(#[from] StreamError),
    /// Writing or opening a pyramid file failed.
    #[error(transparent)]
    Pyramid(#[from] PyramidError),
    /// Building or merging the error maps failed.
    #[error(transparent)]
    Meshes(#[from] MeshesError),
    /// Reading a part or renaming the merged files into place failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The failure.
        source: std::io::Error,
    },
}

/// What a shard built.
#[derive(Clone, Debug)]
pub struct ShardReport {
    /// Its parts.
    pub paths: PartPaths,
    /// The split level.
    pub split_level: u8,
    /// Split nodes it owns, and the split level's nodes.
    pub split_nodes: [usize; 2],
    /// Nodes it stored.
    pub nodes: u64,
}

/// Builds shard `shard`'s parts of the import of `layers` into `dir` (see
/// the module notes); `scratch` and `release` as for
/// [`build_streaming`](crate::pyramid::build_streaming).
pub fn build_shard(
    layers: &[GridView],
    scratch: &ScratchDir,
    options: &ShardOptions,
    shard: Shard,
    dir: &Path,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> Result<ShardReport, ShardError> {
    let paths = PartPaths::of(dir, shard);
    let key = key_of(layers, options, shard.count, release);
    let part = shard::build_part(
        layers,
        scratch,
        &options.stream,
        shard,
        &paths.pyramid,
        release,
        progress,
    )?;
    let pyramid = Pyramid::open(&paths.pyramid)?;
    let stamp = part_identity(key, shard, identity_of(&paths.pyramid)?);
    let nodes = stored_nodes(&pyramid);
    build_store(&pyramid, stamp, &nodes, options.meshes, &paths.meshes, progress)?;
    Ok(ShardReport {
        paths,
        split_level: part.split_level,
        split_nodes: part.split_nodes,
        nodes: nodes.len() as u64,
    })
}

/// The inputs key of `layers` built with `options` in `count` shards. The
/// share level is in it: parts whose maps share other squares' edges (a
/// part built before the level changed) must not merge, since two maps
/// that each say they share an edge hang no skirt there.
fn key_of(layers: &[GridView], options: &ShardOptions, count: u32, release: &dyn Fn()) -> u32 {
    let build = options.stream.build;
    let salt = format!("{:?} share level {SHARE_LEVEL}", options.meshes);
    inputs_key(layers, &build, count, salt.as_bytes(), release)
}

/// What a map part's header carries: the inputs key, K and the identity
/// of the pyramid part it was built from.
fn part_identity(key: u32, shard: Shard, pyramid: u32) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&key.to_le_bytes());
    hasher.update(&shard.index.to_le_bytes());
    hasher.update(&pyramid.to_le_bytes());
    hasher.finalize()
}

fn identity_of(path: &Path) -> Result<u32, ShardError> {
    pyramid_identity(path).map_err(|source| ShardError::Io { path: path.to_path_buf(), source })
}

/// Refuses a shard count of 0 and a missing part, naming it: what a merge
/// can tell before it reads its sources.
pub fn check_parts_exist(dir: &Path, count: u32) -> Result<(), ShardError> {
    check_count(count).map_err(|problem| ShardError::Count { count, problem })?;
    for index in 0..count {
        let shard = Shard { index, count };
        let paths = PartPaths::of(dir, shard);
        let missing = [paths.pyramid, paths.meshes].into_iter().find(|p| !p.exists());
        if let Some(path) = missing {
            return Err(ShardError::Missing { path, shard });
        }
    }
    Ok(())
}

/// Reads every node of a pyramid part, checking its record (a part lacks
/// what [`Pyramid::verify`] asks of a whole pyramid: its other nodes and
/// the levels above it), its pages released as it goes.
fn check_records(pyramid: &Pyramid) -> Result<(), NodeError> {
    let layout = *pyramid.layout();
    for nodes in stored_nodes(pyramid).chunks(CHECKED_PER_RELEASE) {
        let read = |data: &mut NodeData, &id| pyramid.read_node(id, data);
        nodes.par_iter().try_for_each_init(|| NodeData::with_capacity(&layout), read)?;
        pyramid.release_pages();
    }
    Ok(())
}

/// Nodes whose records are checked between two releases of the pages.
const CHECKED_PER_RELEASE: usize = 1024;

/// The files a merge writes beside the dataset before renaming them into
/// place.
struct Staged {
    pyramid: PathBuf,
    meshes: PathBuf,
    /// The map part of the levels above the split.
    coarse: PathBuf,
}

impl Staged {
    fn in_dir(dir: &Path) -> Staged {
        Staged {
            pyramid: dir.join(".merge-pyramid.rlp"),
            meshes: dir.join(".merge-meshes.rlm"),
            coarse: dir.join(".merge-coarse.rlm"),
        }
    }

    fn remove(&self) {
        for path in [&self.pyramid, &self.meshes, &self.coarse] {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Merges the `count` shards' parts in `dir` with the levels above their
/// split, cut from `layers` (the shards' sources), into `dir`'s
/// [`FILE_NAME`] and [`MAP_FILE_NAME`] (see the module notes).
pub fn merge_shards(
    layers: &[GridView],
    scratch: &ScratchDir,
    options: &ShardOptions,
    count: u32,
    dir: &Path,
    release: &dyn Fn(),
    progress: &dyn Progress,
) -> Result<PyramidInfo, ShardError> {
    let staged = Staged::in_dir(dir);
    let inputs = Inputs { layers, scratch, options, release, progress };
    let merged = inputs.merge_staged(count, dir, &staged).and_then(|info| {
        let outputs = [(&staged.pyramid, FILE_NAME), (&staged.meshes, MAP_FILE_NAME)];
        for (from, name) in outputs {
            let to = dir.join(name);
            std::fs::rename(from, &to).map_err(|source| ShardError::Io { path: to, source })?;
        }
        sync_dir(dir).map_err(|source| ShardError::Io { path: dir.to_path_buf(), source })?;
        Ok(info)
    });
    staged.remove();
    merged
}

/// What a merge builds from.
struct Inputs<'a> {
    layers: &'a [GridView<'a>],
    scratch: &'a ScratchDir,
    options: &'a ShardOptions,
    release: &'a dyn Fn(),
    progress: &'a dyn Progress,
}

impl Inputs<'_> {
    /// The merge into the staged files.
    fn merge_staged(
        &self,
        count: u32,
        dir: &Path,
        staged: &Staged,
    ) -> Result<PyramidInfo, ShardError> {
        check_parts_exist(dir, count)?;
        let (pyramids, mut maps) = self.open_parts(dir, count)?;
        let stream = &self.options.stream;
        let (info, split_level) = shard::merge_parts(
            self.layers,
            self.scratch,
            stream,
            &pyramids,
            &staged.pyramid,
            self.release,
            self.progress,
        )?;
        drop(pyramids);
        let pyramid = Pyramid::open(&staged.pyramid)?;
        let identity = identity_of(&staged.pyramid)?;
        let coarse: Vec<NodeId> =
            stored_nodes(&pyramid).into_iter().filter(|id| id.level > split_level).collect();
        let meshes = self.options.meshes;
        build_store(&pyramid, identity, &coarse, meshes, &staged.coarse, self.progress)?;
        maps.push(MapFile::open_part(&staged.coarse, &info.layout)?);
        merge_parts(&maps, &info.layout, identity, &staged.meshes)?;
        Ok(info)
    }

    /// Opens every shard's parts and checks them against the inputs.
    fn open_parts(
        &self,
        dir: &Path,
        count: u32,
    ) -> Result<(Vec<Pyramid>, Vec<MapFile>), ShardError> {
        let key = key_of(self.layers, self.options, count, self.release);
        let (layout, georef) = shard::layout_of(self.layers, &self.options.stream.build)?;
        let mut pyramids = Vec::with_capacity(count as usize);
        let mut maps = Vec::with_capacity(count as usize + 1);
        for index in 0..count {
            let shard = Shard { index, count };
            let paths = PartPaths::of(dir, shard);
            let part = |problem: String| ShardError::Part { shard, problem };
            let pyramid = Pyramid::open(&paths.pyramid).map_err(|e| part(e.to_string()))?;
            check_records(&pyramid).map_err(|e| part(e.to_string()))?;
            if pyramid.info().layout != layout || pyramid.info().georef != georef {
                return Err(part(format!(
                    "{}: built for another layout (other sources, --node-size or --border)",
                    paths.pyramid.display()
                )));
            }
            let map =
                MapFile::open_part(&paths.meshes, &layout).map_err(|e| part(e.to_string()))?;
            map.verify().map_err(|e| part(e.to_string()))?;
            if map.info().pyramid != part_identity(key, shard, identity_of(&paths.pyramid)?) {
                return Err(part(format!(
                    "{}: built from other sources, options or shard count than this merge, or \
                     for another shard, or before its pyramid part {} was rebuilt",
                    paths.meshes.display(),
                    paths.pyramid.display()
                )));
            }
            pyramids.push(pyramid);
            maps.push(map);
        }
        Ok((pyramids, maps))
    }
}
