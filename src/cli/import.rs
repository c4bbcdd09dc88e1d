//! `ridgeline import FILES... --out cache/NAME`: reads the elevation files
//! into layers (files of one spacing form one layer, a mosaic), builds one
//! node pyramid over all of them on every core with a progress bar (finer
//! layers win, see `ridgeline::pyramid::layers`), and writes
//! `cache/NAME/pyramid.rlp` atomically, then each node's adaptive mesh
//! beside it (`meshes-12m.rlm` for the default tau, see `ridgeline::meshes`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::pyramid::{self, BuildOptions, Pyramid, FILE_NAME, MAX_SYNTHETIC_SIZE};

use super::progress::Bar;

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
    /// Build from a deterministic synthetic SIZE x SIZE grid instead of
    /// files (scale tests and benchmarks).
    #[arg(long, hide = true, conflicts_with = "files")]
    pub synthetic: Option<u32>,
}

pub fn run(args: &ImportArgs) -> Result<()> {
    let started = Instant::now();
    let layers = match args.synthetic {
        Some(size) => vec![pyramid::synthetic_grid(size).with_context(|| {
            format!("--synthetic {size}: the size must be 1..={MAX_SYNTHETIC_SIZE}")
        })?],
        None => ridgeline::dem::import_layers(&args.files)?,
    };
    let options = BuildOptions { node_size: args.node_size, border: args.border };
    let bar = Bar::new();
    let built =
        pyramid::build_layers(&layers, &options, &bar).context("building the node pyramid")?;
    let input_bytes: usize = layers.iter().map(|l| l.heights.len() * 4).sum();
    drop(layers);
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create the cache", args.out.display()))?;
    let path = args.out.join(FILE_NAME);
    pyramid::write_atomic(&built, &path, &bar)?;
    let opened = std::sync::Arc::new(Pyramid::open(&args.out)?);
    MeshedSource::open_or_build(opened, MeshOptions::default(), &bar)
        .context("building the error maps")?;
    bar.finish();
    let layout = built.layout();
    let present: u64 = built.info.levels.iter().map(|l| l.present).sum();
    println!(
        "ridgeline import: wrote {} ({} layers, {} levels, {} of {} nodes stored, {:.1} MB of heights in) in {:.1} s",
        path.display(),
        built.info.layers,
        layout.levels,
        present,
        layout.node_count(),
        input_bytes as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
