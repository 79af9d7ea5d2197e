//! `weft train`: train the Multilevel model on a dataset into a run directory.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use weft_models::multilevel::Multilevel;
use weft_nn::backend::{cpu_autodiff, retain_freed_memory, seeded};
use weft_train::{train, MultilevelRun, MultilevelTask, RunOptions};

#[derive(Args)]
pub struct TrainArgs {
    /// Dataset directory (from `weft data generate`).
    #[arg(long)]
    pub data: PathBuf,
    /// Run directory to write (config.toml, checkpoints/, metrics.jsonl, curves.png).
    #[arg(long)]
    pub out: PathBuf,
    /// Model and training preset: cpu or paper (default: the config file's, else cpu).
    #[arg(long)]
    pub preset: Option<String>,
    /// A TOML file with [model] and [train] fields laid over the preset (the format
    /// `weft config show` prints).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Optimiser steps of the whole run (overrides [train] steps).
    #[arg(long)]
    pub steps: Option<usize>,
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
    retain_freed_memory();
    let explicit =
        a.preset.is_some() || a.config.is_some() || a.steps.is_some() || a.seed.is_some();
    let mut cfg = if a.resume && !explicit {
        // The run's own config.toml is the configuration of a resumed run.
        MultilevelRun::from_run_dir(&a.out)?
    } else {
        MultilevelRun::resolve(a.preset.as_deref(), a.config.as_deref())?
    };
    if let Some(steps) = a.steps {
        cfg.train.steps = steps;
    }
    if let Some(seed) = a.seed {
        cfg.train.seed = seed;
    }
    cfg.train.validate()?;
    if !a.data.is_dir() {
        bail!(
            "{}: no such dataset directory (make one with `weft data generate`)",
            a.data.display()
        );
    }
    let run = cfg.run_dir(&a.out)?;
    let device = seeded(&cpu_autodiff(), cfg.train.seed);
    let started = Instant::now();
    let mut task = MultilevelTask::from_dataset(&a.data, &cfg.model, &cfg.train, &device)
        .with_context(|| format!("loading {}", a.data.display()))?;
    let model = Multilevel::new(&cfg.model, &device)?;
    eprintln!(
        "training {} preset on {} sequences ({} windows of {} frames per epoch), {} steps -> {}",
        cfg.preset,
        task.sequence_count(),
        weft_train::TrainTask::item_count(&task),
        cfg.train.window,
        cfg.train.steps,
        a.out.display()
    );
    let options = RunOptions {
        resume: a.resume,
        progress: !a.quiet,
        session_steps: None,
    };
    let (_, outcome) = train(&mut task, model, &run, &options)?;
    let validation = outcome
        .validation_mm
        .map_or("not measured".to_string(), |v| format!("{v:.2} mm"));
    super::emit(&format!(
        "trained {} steps in {:.1} s ({:.1} ms/step, {} skipped), phase {}\nvalidation mean vertex error: {validation}\ncheckpoint: {}\nmetrics: {}\ncurves: {}",
        outcome.steps,
        started.elapsed().as_secs_f64(),
        outcome.mean_step_ms,
        outcome.skipped,
        outcome.phase.name(),
        outcome.checkpoint.display(),
        a.out.join("metrics.jsonl").display(),
        a.out.join("curves.png").display(),
    ))
}
