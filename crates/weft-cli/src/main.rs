//! `weft`: learn and run garment deformation on moving bodies. This binary only parses
//! arguments and wires the library crates together; every algorithm lives in a crate.

mod cmd;

use clap::{error::ErrorKind, Arg, ArgAction, Command, CommandFactory, FromArgMatches, Parser};
use std::process::ExitCode;

/// weft — graph neural networks for garment deformation, from meshes to animation.
#[derive(Parser)]
#[command(name = "weft", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: cmd::Command,
}

fn main() -> ExitCode {
    let cli = match parse() {
        Ok(cli) => cli,
        Err(err)
            if matches!(
                err.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) =>
        {
            err.exit()
        }
        Err(err) => {
            // One line: clap's message (the lines before its first blank one, which
            // name the argument, also a missing one's) joined, and a pointer to --help
            // instead of the usage block that follows.
            let text = err.to_string();
            let message: Vec<&str> = text
                .lines()
                .take_while(|l| !l.trim().is_empty())
                .map(str::trim)
                .collect();
            eprintln!("{} (see `--help`)", message.join(" "));
            return ExitCode::from(2);
        }
    };
    // Every command that runs a network allocates and frees megabyte tensors per step;
    // glibc's defaults page them back in each time (HOOD's paper step at 4 000 vertices:
    // 449–473 → 358–363 ms, docs/benchmarks.md). `WEFT_MALLOC_DEFAULTS=1` keeps glibc's
    // defaults, for measuring the difference.
    if std::env::var_os("WEFT_MALLOC_DEFAULTS").is_none() {
        weft_nn::backend::retain_freed_memory();
    }
    // The main thread joins rayon's pool as its thread 0, so that a parallel operation
    // started here runs its first half in place and the other worker steals the rest.
    // Otherwise the main thread hands each operation to the pool and sleeps until a
    // worker wakes it: three threads on two cores, two context switches per operation,
    // and a training step makes thousands of small ones (docs/benchmarks.md, "The main
    // thread in rayon's pool"). Fails only if a pool was built already, which nothing
    // before this line does.
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global();
    match cmd::run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // One line: the cause chain joined with ": ", as ripgrep and cargo do.
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}

/// Parses the command line with negative numbers accepted as option values everywhere
/// (`--betas -1,2`, `--frames -5`): the option's own parser then accepts the value or
/// refuses it naming the option, instead of clap reporting an "unexpected argument
/// '-5'" that names none.
fn parse() -> Result<Cli, clap::Error> {
    let command = negative_values(Cli::command());
    Cli::from_arg_matches(&command.try_get_matches()?)
}

fn negative_values(command: Command) -> Command {
    command
        .mut_args(|arg: Arg| {
            if matches!(arg.get_action(), ArgAction::Set | ArgAction::Append) {
                arg.allow_negative_numbers(true)
            } else {
                arg
            }
        })
        .mut_subcommands(negative_values)
}
