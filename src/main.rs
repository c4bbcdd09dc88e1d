//! The `ridgeline` command line.

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
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command.unwrap_or(Command::Fly) {
        Command::Fly => {
            println!("ridgeline: the renderer is not built yet; the allocator is (cargo bench --bench allocator).");
        }
    }
    Ok(())
}
