//! `weft config show`: every default of a model kind's preset, as the config.toml of a run.

use anyhow::Context;
use clap::Subcommand;
use weft_models::ModelKind;
use weft_pipeline::train::preset_toml;

#[derive(Subcommand)]
pub enum ConfigCommand {
    /// Print the model and training configuration of a preset as TOML (every default
    /// written out; edit and pass to `weft train --config`).
    Show {
        /// The system: multilevel, hood, densegats, multiresgnet or garfitnet.
        #[arg(long, default_value = "multilevel")]
        model: ModelKind,
        /// cpu or paper.
        #[arg(long, default_value = "cpu")]
        preset: String,
    },
}

pub fn run(c: ConfigCommand) -> anyhow::Result<()> {
    match c {
        ConfigCommand::Show { model, preset } => {
            super::emit(&preset_toml(model, &preset).context("--preset")?)
        }
    }
}
