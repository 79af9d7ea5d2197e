//! `weft train`: train a model kind on a dataset into a run directory.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use weft_models::ModelKind;
use weft_pipeline::train::{train_run, TrainSpec};

#[derive(Args)]
pub struct TrainArgs {
    /// The system to train: multilevel, hood, densegats, multiresgnet or garfitnet.
    #[arg(long, default_value = "multilevel")]
    pub model: ModelKind,
    /// Dataset directory (from `weft data generate`); every model but hood, which
    /// trains from bodies, procedural garments and motions.
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Run directory to write (config.toml, checkpoints/, metrics.jsonl, curves.png).
    #[arg(long)]
    pub out: PathBuf,
    /// Model and training preset: cpu or paper (default: the config file's, else cpu).
    #[arg(long)]
    pub preset: Option<String>,
    /// A TOML file with [model] and [train] fields laid over the preset (the format
    /// `weft config show` prints); an unknown key is refused, naming it.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Optimiser steps of the whole run, at least 1 (overrides [train] steps).
    #[arg(long)]
    pub steps: Option<std::num::NonZeroUsize>,
    /// Seed of initialisation and data order (overrides [train] seed).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Continue the run in --out from its latest checkpoint.
    #[arg(long)]
    pub resume: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(a: &TrainArgs) -> anyhow::Result<()> {
    let spec = TrainSpec {
        model: a.model,
        data: a.data.clone(),
        out: a.out.clone(),
        preset: a.preset.clone(),
        config: a.config.clone(),
        steps: a.steps.map(usize::from),
        seed: a.seed,
        resume: a.resume,
        progress: !a.quiet,
    };
    let started = Instant::now();
    let outcome = train_run(&spec, &mut |line| eprintln!("{line}"))?;
    let validation = weft_train::metrics::describe(&outcome.validation);
    super::emit(&format!(
        "trained {} steps in {:.1} s ({:.1} ms/step, {} skipped), stage {}\nvalidation: {validation}\ncheckpoint: {}\nmetrics: {}\ncurves: {}",
        outcome.steps,
        started.elapsed().as_secs_f64(),
        outcome.mean_step_ms,
        outcome.skipped,
        outcome.stage,
        outcome.checkpoint.display(),
        a.out.join("metrics.jsonl").display(),
        a.out.join("curves.png").display(),
    ))
}
