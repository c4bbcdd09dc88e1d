//! `ridgeline import FILES... --out cache/NAME`: reads the elevation files
//! into layers (files of one spacing form one layer, a mosaic) held in
//! memory-mapped spills under `cache/NAME/.import-PID`, builds one node
//! pyramid over all of them streaming, band by band, within `--memory-mb`
//! on every core with a progress bar (finer layers win, see
//! `ridgeline::pyramid::layers`), writes `cache/NAME/pyramid.rlp`
//! atomically as it goes, then each node's error map beside it
//! (`meshes.rlm`, see `ridgeline::meshes`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use ridgeline::dem::GridView;
use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::pyramid::spilled::{spill_layers, SpilledLayer};
use ridgeline::pyramid::{
    self, BuildOptions, Pyramid, StreamOptions, FILE_NAME, MAX_SYNTHETIC_SIZE,
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
}

pub fn run(args: &ImportArgs) -> Result<()> {
    let existed = args.out.exists();
    let result = import(args);
    if result.is_err() && !existed {
        // A failed first import leaves no empty cache directory behind;
        // `remove_dir` refuses a directory that holds anything.
        let _ = std::fs::remove_dir(&args.out);
    }
    result
}

fn import(args: &ImportArgs) -> Result<()> {
    let started = Instant::now();
    if args.memory_mb < MIN_MEMORY_MB {
        bail!("--memory-mb {}: at least {MIN_MEMORY_MB} MB is needed", args.memory_mb);
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create the cache", args.out.display()))?;
    let scratch = ScratchDir::create(&args.out)
        .with_context(|| format!("{}: cannot create the import's scratch", args.out.display()))?;
    let bar = Bar::new();
    let synthetic = match args.synthetic {
        Some(size) => Some(pyramid::synthetic_grid(size).with_context(|| {
            format!("--synthetic {size}: the size must be 1..={MAX_SYNTHETIC_SIZE}")
        })?),
        None => None,
    };
    let spilled: Vec<SpilledLayer> = match synthetic {
        Some(_) => Vec::new(),
        None => spill_layers(&args.files, &scratch, &bar)?,
    };
    let views: Vec<GridView> = match &synthetic {
        Some(grid) => vec![grid.view()],
        None => spilled.iter().map(SpilledLayer::view).collect(),
    };
    let options = StreamOptions {
        build: BuildOptions { node_size: args.node_size, border: args.border },
        band_bytes: args.memory_mb << 20 >> 2,
    };
    let path = args.out.join(FILE_NAME);
    let release = || spilled.iter().for_each(|l| l.heights.release());
    let info = pyramid::build_streaming(&views, &scratch, &options, &path, &release, &bar)
        .context("building the node pyramid")?;
    let input_bytes: usize = views.iter().map(|l| l.heights.len() * 4).sum();
    drop(views);
    drop(spilled);
    drop(scratch);
    let opened = std::sync::Arc::new(Pyramid::open(&args.out)?);
    MeshedSource::open_or_build(opened, MeshOptions::default(), &bar)
        .context("building the error maps")?;
    bar.finish();
    let present: u64 = info.levels.iter().map(|l| l.present).sum();
    println!(
        "ridgeline import: wrote {} ({} layers, {} levels, {} of {} nodes stored, {:.1} MB of heights in) in {:.1} s",
        path.display(),
        info.layers,
        info.layout.levels,
        present,
        info.layout.node_count(),
        input_bytes as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
