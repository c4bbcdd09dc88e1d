//! `ridgeline import FILES... --out cache/NAME`: reads the elevation files
//! into layers (files of one spacing form one layer, a mosaic) held in
//! memory-mapped spills under `cache/NAME/.import-PID`, builds one node
//! pyramid over all of them streaming, band by band, within `--memory-mb`
//! on every core with a progress bar (finer layers win, see
//! `ridgeline::pyramid::layers`), writes `cache/NAME/pyramid.rlp`
//! atomically as it goes, then each node's error map beside it
//! (`meshes.rlm`, see `ridgeline::meshes`).
//!
//! `--shard K/N` builds only shard K's parts (`cache/NAME/shard-K-of-N.rlp`
//! and `.rlm`), `--merge-shards N` merges the N shards' parts into the
//! same two files one process writes (see `ridgeline::pyramid::shard`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use ridgeline::dem::{ElevationGrid, GridView};
use ridgeline::meshes::shards::{self, ShardOptions, ShardReport};
use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::pyramid::shard::Shard;
use ridgeline::pyramid::spilled::{raise_to_sea_surface, spill_layers, SpilledLayer};
use ridgeline::pyramid::{
    self, BuildOptions, Pyramid, PyramidInfo, StreamOptions, FILE_NAME, MAX_SYNTHETIC_SIZE,
};
use ridgeline::spill::ScratchDir;

use super::progress::Bar;

/// The least `--memory-mb` an import accepts: one SRTM1 tile's decode.
const MIN_MEMORY_MB: u64 = 64;

#[derive(clap::Args)]
pub struct ImportArgs {
    /// Elevation files (GeoTIFF, SRTM .hgt, DTED, ESRI ASCII grid, netCDF-3):
    /// files of one spacing are mosaicked into a layer, layers of different
    /// spacings are stacked, finer over coarser.
    #[arg(required_unless_present = "synthetic")]
    pub files: Vec<PathBuf>,
    /// Cache directory to build, for example cache/alps; an existing pyramid
    /// there is replaced only once the new one is complete.
    #[arg(long)]
    pub out: PathBuf,
    /// Cells per node side.
    #[arg(long, default_value_t = BuildOptions::default().node_size)]
    pub node_size: u32,
    /// Posts repeated from the neighbours on each side of a node.
    #[arg(long, default_value_t = BuildOptions::default().border)]
    pub border: u32,
    /// Peak memory the build may use, MB, whatever the input's size: the
    /// layers live in memory-mapped files under the cache and the nodes
    /// are built and written band by band. Each input file is decoded
    /// whole, one at a time, so the largest file counts against it too.
    #[arg(long, default_value_t = 1024)]
    pub memory_mb: u64,
    /// Build from a deterministic synthetic SIZE x SIZE grid instead of
    /// files (scale tests and benchmarks).
    #[arg(long, hide = true, conflicts_with = "files")]
    pub synthetic: Option<u32>,
    /// Build only shard K of N (K from 0 to N-1): its part of the pyramid
    /// and error maps, written to OUT/shard-K-of-N.rlp and .rlm. Run all N
    /// (on any machines, in any order, each restartable), then
    /// `--merge-shards N` with the same files and options.
    #[arg(long, value_name = "K/N", conflicts_with = "merge_shards")]
    pub shard: Option<Shard>,
    /// Merge the parts of N shards in OUT into OUT/pyramid.rlp and
    /// meshes.rlm (the bytes one process writes); give the same files and
    /// options as the shards. The levels above the shards' split are built
    /// here. The previous dataset stays until the merge is complete.
    #[arg(long, value_name = "N")]
    pub merge_shards: Option<u32>,
    /// Raise heights below sea level to it (0 m): for data that keep the
    /// sea floor (ETOPO, GEBCO), so the sea is drawn as its surface. Land
    /// below sea level (Dead Sea, Caspian) is then drawn at 0 m, above the
    /// real ground. Shards and their merge must all be given it or not.
    #[arg(long)]
    pub sea_surface: bool,
}

pub fn run(args: &ImportArgs) -> Result<()> {
    let existed = args.out.exists();
    let result = import(args);
    if let Some(shard) = args.shard {
        // Its scratch is gone by now; the directory goes if empty.
        let _ = std::fs::remove_dir(shard_scratch(args, shard));
    }
    if result.is_err() && !existed {
        // A failed first import leaves no empty cache directory behind;
        // `remove_dir` refuses a directory that holds anything.
        let _ = std::fs::remove_dir(&args.out);
    }
    result
}

/// Where the import's scratch goes: OUT, or for a shard OUT/.shard-K-of-N,
/// so that a shard clears only its own stale scratch, never that of a
/// shard running on another machine over a shared directory.
fn scratch_parent(args: &ImportArgs) -> Result<PathBuf> {
    let Some(shard) = args.shard else { return Ok(args.out.clone()) };
    let dir = shard_scratch(args, shard);
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("{}: cannot create the shard's scratch", dir.display()))?;
    Ok(dir)
}

fn shard_scratch(args: &ImportArgs, shard: Shard) -> PathBuf {
    args.out.join(format!(".shard-{}-of-{}", shard.index, shard.count))
}

fn import(args: &ImportArgs) -> Result<()> {
    let started = Instant::now();
    check_args(args)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create the cache", args.out.display()))?;
    let scratch_in = scratch_parent(args)?;
    let scratch = ScratchDir::create(&scratch_in)
        .with_context(|| format!("{}: cannot create the import's scratch", scratch_in.display()))?;
    let bar = Bar::new();
    let (synthetic, spilled) = read_sources(args, &scratch, &bar)?;
    let views: Vec<GridView> = match &synthetic {
        Some(grid) => vec![grid.view()],
        None => spilled.iter().map(SpilledLayer::view).collect(),
    };
    let options = StreamOptions {
        build: BuildOptions { node_size: args.node_size, border: args.border },
        band_bytes: args.memory_mb << 20 >> 2,
    };
    let release = || spilled.iter().for_each(|l| l.heights.release());
    let input_bytes: usize = views.iter().map(|l| l.heights.len() * 4).sum();
    let sharded = ShardOptions { stream: options, meshes: MeshOptions::default() };
    if let Some(shard) = args.shard {
        let report =
            shards::build_shard(&views, &scratch, &sharded, shard, &args.out, &release, &bar)
                .with_context(|| format!("building shard {shard}"))?;
        bar.finish();
        print_shard(shard, &report, started);
        return Ok(());
    }
    let path = args.out.join(FILE_NAME);
    let info = match args.merge_shards {
        Some(count) => {
            shards::merge_shards(&views, &scratch, &sharded, count, &args.out, &release, &bar)
                .with_context(|| format!("merging {count} shards in {}", args.out.display()))?
        }
        None => {
            let info = pyramid::build_streaming(&views, &scratch, &options, &path, &release, &bar)
                .context("building the node pyramid")?;
            drop(views);
            drop(spilled);
            drop(scratch);
            let opened = std::sync::Arc::new(Pyramid::open(&args.out)?);
            MeshedSource::open_or_build(opened, sharded.meshes, &bar)
                .context("building the error maps")?;
            info
        }
    };
    bar.finish();
    print_written(args, &path, &info, input_bytes, started);
    Ok(())
}

/// Refuses what the import cannot run with before anything is read: too
/// little memory, a merge without its parts.
fn check_args(args: &ImportArgs) -> Result<()> {
    if args.memory_mb < MIN_MEMORY_MB {
        bail!("--memory-mb {}: at least {MIN_MEMORY_MB} MB is needed", args.memory_mb);
    }
    if let Some(count) = args.merge_shards {
        shards::check_parts_exist(&args.out, count).context("--merge-shards")?;
    }
    Ok(())
}

/// The import's heights: a synthetic grid, or every file spilled into its
/// layer under `scratch`; raised to the sea's surface with `--sea-surface`.
fn read_sources(
    args: &ImportArgs,
    scratch: &ScratchDir,
    bar: &Bar,
) -> Result<(Option<ElevationGrid>, Vec<SpilledLayer>)> {
    let mut synthetic = match args.synthetic {
        Some(size) => Some(pyramid::synthetic_grid(size).with_context(|| {
            format!("--synthetic {size}: the size must be 1..={MAX_SYNTHETIC_SIZE}")
        })?),
        None => None,
    };
    let mut spilled: Vec<SpilledLayer> = match synthetic {
        Some(_) => Vec::new(),
        None => spill_layers(&args.files, scratch, bar)?,
    };
    if args.sea_surface {
        let raised = raise_to_sea_surface(&mut spilled)
            + synthetic
                .as_mut()
                .map_or(0, |g| ridgeline::dem::sea::raise_to_sea_surface(&mut g.heights));
        eprintln!("--sea-surface: {raised} posts below sea level raised to it");
    }
    Ok((synthetic, spilled))
}

/// The line an import or a merge ends with: what it wrote, from how many
/// bytes of heights (`input_bytes`), since `started`.
fn print_written(
    args: &ImportArgs,
    path: &std::path::Path,
    info: &PyramidInfo,
    input_bytes: usize,
    started: Instant,
) {
    let present: u64 = info.levels.iter().map(|l| l.present).sum();
    let command = match args.merge_shards {
        Some(count) => format!("ridgeline import --merge-shards {count}"),
        None => "ridgeline import".into(),
    };
    println!(
        "{command}: wrote {} ({} layers, {} levels, {} of {} nodes stored, {:.1} MB of heights in) in {:.1} s",
        path.display(),
        info.layers,
        info.layout.levels,
        present,
        info.layout.node_count(),
        input_bytes as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
}

/// The line a shard ends with: its parts, its nodes, how to merge.
fn print_shard(shard: Shard, report: &ShardReport, started: Instant) {
    println!(
        "ridgeline import --shard {shard}: wrote {} and {} ({} nodes under {} of the {} nodes \
         of level {}) in {:.1} s; merge all {} with --merge-shards {}",
        report.paths.pyramid.display(),
        report.paths.meshes.display(),
        report.nodes,
        report.split_nodes[0],
        report.split_nodes[1],
        report.split_level,
        started.elapsed().as_secs_f64(),
        shard.count,
        shard.count
    );
}
