//! The `ridgeline` command line.

mod cli;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// Ridgeline: a synthetic-vision terrain display for low-power OpenGL ES boards.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Fly the built-in approach over the built-in terrain (the main job).
    Fly,
    /// Build a node pyramid cache from elevation files.
    Import(cli::import::ImportArgs),
    /// Describe a node pyramid cache.
    Info(cli::info::InfoArgs),
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command.unwrap_or(Command::Fly) {
        Command::Fly => {
            println!("ridgeline: the renderer is not built yet; the allocator is (cargo bench --bench allocator).");
        }
        Command::Import(args) => cli::import::run(&args)?,
        Command::Info(args) => cli::info::run(&args)?,
    }
    Ok(())
}
