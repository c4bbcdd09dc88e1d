//! `ridgeline import FILES... --out cache/NAME`: reads the elevation files into
//! one grid, builds the node pyramid on every core with a progress bar, and
//! writes `cache/NAME/pyramid.rlp` atomically.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use ridgeline::dem::ElevationGrid;
use ridgeline::pyramid::{self, BuildOptions, FILE_NAME, MAX_SYNTHETIC_SIZE};

use super::progress::Bar;

#[derive(clap::Args)]
pub struct ImportArgs {
    /// Elevation files (GeoTIFF, SRTM .hgt, DTED, ESRI ASCII grid), mosaicked into one grid.
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
    let grid = match args.synthetic {
        Some(size) => pyramid::synthetic_grid(size).with_context(|| {
            format!("--synthetic {size}: the size must be 1..={MAX_SYNTHETIC_SIZE}")
        })?,
        None => read_dem_files(&args.files)?,
    };
    let options = BuildOptions { node_size: args.node_size, border: args.border };
    let bar = Bar::new();
    let built = pyramid::build(&grid, &options, &bar).context("building the node pyramid")?;
    let input_bytes = grid.heights.len() * 4;
    drop(grid);
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create the cache", args.out.display()))?;
    let path = args.out.join(FILE_NAME);
    pyramid::write_atomic(&built, &path, &bar)?;
    bar.finish();
    let layout = built.layout();
    println!(
        "ridgeline import: wrote {} ({} levels, {} nodes, {:.1} MB of heights in) in {:.1} s",
        path.display(),
        layout.levels,
        layout.node_count(),
        input_bytes as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Reads the elevation files into one grid (mosaicked, voids filled).
fn read_dem_files(files: &[PathBuf]) -> Result<ElevationGrid> {
    Ok(ridgeline::dem::import_files(files)?)
}
