//! `weft`: learn and run garment deformation on moving bodies. This binary only parses
//! arguments and wires the library crates together; every algorithm lives in a crate.

mod cmd;

use clap::Parser;
use std::process::ExitCode;

/// weft — graph neural networks for garment deformation, from meshes to animation.
#[derive(Parser)]
#[command(name = "weft", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: cmd::Command,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cmd::run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // One line: the cause chain joined with ": ", as ripgrep and cargo do.
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
