//! The `ridgeline` command line.

mod cli;

#[global_allocator]
static HEAP: cli::heap::Counting = cli::heap::Counting;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// Ridgeline: a synthetic-vision terrain display for low-power OpenGL ES boards.
#[derive(Parser)]
#[command(version, about, args_conflicts_with_subcommands = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// With no subcommand, `ridgeline` flies: these are `fly`'s options.
    #[command(flatten)]
    fly: cli::fly::FlyArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Fly a camera path over a terrain (the main job; the default command).
    Fly(cli::fly::FlyArgs),
    /// Measure the screen-space error the display draws against the full-resolution mesh.
    Accuracy(cli::accuracy::AccuracyArgs),
    /// Build a node pyramid cache from elevation files.
    Import(cli::import::ImportArgs),
    /// Describe a node pyramid cache.
    Info(cli::info::InfoArgs),
}

/// Errors end the program with their whole chain on one line and exit code 1
/// (no backtrace: these are the user's files and options, not our bugs).
fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("ridgeline: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<()> {
    let cli = Cli::parse();
    match cli.command.unwrap_or(Command::Fly(cli.fly)) {
        Command::Fly(args) => cli::fly::run(&args)?,
        Command::Accuracy(args) => cli::accuracy::run(&args)?,
        Command::Import(args) => cli::import::run(&args)?,
        Command::Info(args) => cli::info::run(&args)?,
    }
    Ok(())
}
