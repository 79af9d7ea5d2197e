//! `weft config show`: every default of a preset, as the config.toml of a run.

use clap::Subcommand;
use weft_train::MultilevelRun;

#[derive(Subcommand)]
pub enum ConfigCommand {
    /// Print the model and training configuration of a preset as TOML (every default
    /// written out; edit and pass to `weft train --config`).
    Show {
        /// cpu or paper.
        #[arg(long, default_value = "cpu")]
        preset: String,
    },
}

pub fn run(c: ConfigCommand) -> anyhow::Result<()> {
    match c {
        ConfigCommand::Show { preset } => super::emit(&MultilevelRun::preset(&preset)?.to_toml()?),
    }
}
