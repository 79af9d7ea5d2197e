//! Training as the CLI and the demo run it: a model kind, a preset overlaid by a config
//! file and flags, a dataset, a run directory. [`train_run`] is the one place that
//! dispatches on [`ModelKind`] for training; a new system adds its arm here.

use std::path::{Path, PathBuf};

use weft_data::characters::CharacterSet;
use weft_data::Split;
use weft_models::multilevel::Multilevel;
use weft_models::refine::RefineConfig;
use weft_models::ModelKind;
use weft_nn::backend::{cpu_autodiff, seeded};
use weft_train::run_config::{ModelSettings, RunConfig, TaskSettings};
use weft_train::tasks::garfit::{load_fit_data, save_stats, GarFitRun, GarFitTask};
use weft_train::tasks::hood::{HoodRun, HoodTask};
use weft_train::tasks::refine::config::{DenseGatsRun, MultiResGnetRun, RefineTraining};
use weft_train::tasks::refine::{fit_normalizer, load_split, save_normalizer, RefineTask};
use weft_train::{train, MultilevelRun, MultilevelTask, Outcome, RunOptions, TrainTask};

use crate::error::{stage, PipelineError};

/// What to train, where, and how the configuration is put together.
#[derive(Clone, Debug)]
pub struct TrainSpec {
    /// The system to train.
    pub model: ModelKind,
    /// Dataset directory (from `weft data generate`); HOOD trains without one.
    pub data: Option<PathBuf>,
    /// Run directory to write.
    pub out: PathBuf,
    /// Preset name (default: the config file's, else `cpu`).
    pub preset: Option<String>,
    /// A TOML file laid over the preset (unknown keys are refused).
    pub config: Option<PathBuf>,
    /// Optimiser steps of the whole run (overrides the configuration).
    pub steps: Option<usize>,
    /// Seed of initialisation and data order (overrides the configuration).
    pub seed: Option<u64>,
    /// Continue the run in `out` from its latest checkpoint.
    pub resume: bool,
    /// Draw a progress bar with ETA on stderr.
    pub progress: bool,
}

/// The configuration of `kind` at `preset` (every default written out) as the
/// config.toml a run would hold: what `weft config show` prints.
pub fn preset_toml(kind: ModelKind, preset: &str) -> Result<String, PipelineError> {
    match kind {
        ModelKind::Multilevel => Ok(MultilevelRun::preset(preset)?.to_toml()?),
        ModelKind::DenseGats => Ok(DenseGatsRun::preset(preset)?.to_toml()?),
        ModelKind::MultiResGnet => Ok(MultiResGnetRun::preset(preset)?.to_toml()?),
        ModelKind::GarFitNet => Ok(GarFitRun::preset(preset)?.to_toml()?),
        ModelKind::Hood => Ok(HoodRun::preset(preset)?.to_toml()?),
    }
}

/// Trains `spec.model`; `log` gets a line describing the run before it starts.
pub fn train_run(spec: &TrainSpec, log: &mut dyn FnMut(&str)) -> Result<Outcome, PipelineError> {
    match spec.model {
        ModelKind::Multilevel => {
            let cfg = resolve_multilevel(spec)?;
            train_multilevel(&cfg, dataset(spec)?, &spec.out, &run_options(spec), log)
        }
        ModelKind::DenseGats => {
            let cfg: DenseGatsRun = resolve(spec)?;
            train_refine(&cfg, spec, log)
        }
        ModelKind::MultiResGnet => {
            let cfg: MultiResGnetRun = resolve(spec)?;
            train_refine(&cfg, spec, log)
        }
        ModelKind::GarFitNet => {
            let cfg: GarFitRun = resolve(spec)?;
            train_garfit(&cfg, spec, log)
        }
        ModelKind::Hood => {
            let cfg: HoodRun = resolve(spec)?;
            train_hood(&cfg, spec, log)
        }
    }
}

/// The dataset directory of `spec`, which every model but HOOD trains on.
fn dataset(spec: &TrainSpec) -> Result<&Path, PipelineError> {
    spec.data.as_deref().ok_or_else(|| {
        PipelineError::Invalid(format!(
            "--data: {} trains on a dataset (`weft data generate`); give its directory",
            spec.model
        ))
    })
}

/// The loop's options of `spec`: resume, progress bar, the whole run in one session.
fn run_options(spec: &TrainSpec) -> RunOptions {
    RunOptions {
        resume: spec.resume,
        progress: spec.progress,
        session_steps: None,
    }
}

/// The Multilevel configuration of `spec` (see [`resolve`]).
pub fn resolve_multilevel(spec: &TrainSpec) -> Result<MultilevelRun, PipelineError> {
    resolve(spec)
}

/// The run configuration of `spec`: a resumed run's own config.toml when nothing else
/// is given, else the preset with the file and the flags laid over it.
pub fn resolve<M: ModelSettings, T: TaskSettings>(
    spec: &TrainSpec,
) -> Result<RunConfig<M, T>, PipelineError> {
    let explicit = spec.preset.is_some()
        || spec.config.is_some()
        || spec.steps.is_some()
        || spec.seed.is_some();
    let mut cfg = if spec.resume && !explicit {
        RunConfig::from_run_dir(&spec.out)?
    } else {
        RunConfig::resolve(spec.preset.as_deref(), spec.config.as_deref())?
    };
    if let Some(steps) = spec.steps {
        cfg.train.trainer.steps = steps;
    }
    if let Some(seed) = spec.seed {
        cfg.train.trainer.seed = seed;
    }
    cfg.train.trainer.validate()?;
    Ok(cfg)
}

/// Trains the Multilevel model of `cfg` on the dataset in `data` into `out`.
pub fn train_multilevel(
    cfg: &MultilevelRun,
    data: &Path,
    out: &Path,
    options: &RunOptions,
    log: &mut dyn FnMut(&str),
) -> Result<Outcome, PipelineError> {
    if !data.is_dir() {
        return Err(PipelineError::Invalid(format!(
            "{}: no such dataset directory (make one with `weft data generate`)",
            data.display()
        )));
    }
    let run = cfg.run_dir(out)?;
    let device = seeded(&cpu_autodiff(), cfg.train.trainer.seed);
    let mut task =
        MultilevelTask::from_dataset(data, &cfg.model, &cfg.train.task, &device).map_err(stage(
            &format!("loading the training data {}", data.display()),
        ))?;
    let model = Multilevel::new(&cfg.model, &device)?;
    log(&format!(
        "training multilevel ({} preset) on {} sequences ({} windows of {} frames per epoch), {} steps -> {}",
        cfg.preset,
        task.sequence_count(),
        task.item_count(),
        cfg.train.task.window,
        cfg.train.trainer.steps,
        out.display()
    ));
    let (_, outcome) = train(&mut task, model, &run, options)?;
    Ok(outcome)
}

/// Trains a refinement model (DenseGATs, MultiResGNet) of `cfg` on the character
/// dataset in `spec.data` into `spec.out`: loads the training and validation
/// characters, fits the feature normaliser on the training ones (saved in the run
/// directory before the first step), then runs the loop.
pub fn train_refine<M: ModelSettings + RefineConfig>(
    cfg: &RunConfig<M, RefineTraining>,
    spec: &TrainSpec,
    log: &mut dyn FnMut(&str),
) -> Result<Outcome, PipelineError> {
    let (inputs, influences) = (cfg.model.inputs(), cfg.model.influences());
    let data = dataset(spec)?;
    let set = CharacterSet::open(data).map_err(stage(&format!(
        "opening the character dataset {}",
        data.display()
    )))?;
    let mut train_chars = load_split(&set, Split::Train, influences)
        .map_err(stage("loading the training characters"))?;
    if cfg.train.task.characters > 0 {
        train_chars.truncate(cfg.train.task.characters);
    }
    let validation = load_split(&set, Split::Validation, influences)
        .map_err(stage("loading the validation characters"))?;
    let run = cfg.run_dir(&spec.out)?;
    let normalizer_path = spec.out.join(weft_train::tasks::refine::NORMALIZER_FILE);
    let normalizer = if spec.resume && normalizer_path.exists() {
        weft_models::refine::read_normalizer(&normalizer_path)?
    } else {
        let n = fit_normalizer(&train_chars, inputs)
            .map_err(stage("fitting the feature normaliser"))?;
        save_normalizer(&spec.out, &n)?;
        n
    };
    let device = seeded(&cpu_autodiff(), cfg.train.trainer.seed);
    let characters = train_chars.len();
    let mut task: RefineTask<M::Net> = RefineTask::new(
        &cfg.train.task,
        inputs,
        train_chars,
        validation,
        normalizer,
        cfg.train.trainer.seed,
        &device,
    )?;
    let model = cfg.model.build(&device)?;
    let per_step = match (cfg.train.task.patches, cfg.train.task.patch) {
        (1, 0) => "one whole mesh".to_string(),
        (k, 0) => format!("{k} whole meshes"),
        (k, n) => format!("{k} patches of {n} vertices"),
    };
    log(&format!(
        "training {} ({} preset) on {characters} characters ({} steps per epoch of {per_step}), {} steps -> {}",
        M::KIND,
        cfg.preset,
        task.item_count(),
        cfg.train.trainer.steps,
        spec.out.display()
    ));
    let (_, outcome) = train(&mut task, model, &run, &run_options(spec))?;
    Ok(outcome)
}

/// Trains GarFitNet of `cfg` on the fit dataset in `spec.data` into `spec.out`: loads the
/// training and validation pairs, fits α's factor model and the normalisers on the
/// training ones (saved as `garfit.json` before the first step; a resumed run keeps its
/// own), then runs the loop (coarse regressor, then refinement).
pub fn train_garfit(
    cfg: &GarFitRun,
    spec: &TrainSpec,
    log: &mut dyn FnMut(&str),
) -> Result<Outcome, PipelineError> {
    let data = dataset(spec)?;
    let set = weft_data::Dataset::open(data).map_err(stage(&format!(
        "opening the fit dataset {}",
        data.display()
    )))?;
    let (mut stats, mut splits) = load_fit_data(&set, &cfg.model, &[Split::Validation])
        .map_err(stage("loading the garment-body pairs"))?;
    let run = cfg.run_dir(&spec.out)?;
    if spec.resume && spec.out.join(weft_models::garfitnet::STATS_FILE).exists() {
        stats = weft_models::garfitnet::GarFitStats::read(&spec.out)?;
    } else {
        save_stats(&spec.out, &stats)?;
    }
    let (Some(validation), Some(training)) = (splits.pop(), splits.pop()) else {
        return Err(PipelineError::Invalid(
            "loading the garment-body pairs gave no training or validation split".into(),
        ));
    };
    let device = seeded(&cpu_autodiff(), cfg.train.trainer.seed);
    let mut task = GarFitTask::new(
        &cfg.train.task,
        stats,
        training,
        validation,
        cfg.train.trainer.seed,
        &device,
    )?;
    let (sequences, pairs, frames) = task.describe();
    log(&format!(
        "training garfitnet ({} preset) on {sequences} sequences of {pairs} garment-body pairs ({frames} frames, {} per step; coarse regressor for {} of {} steps) -> {}",
        cfg.preset,
        cfg.train.task.frames,
        cfg.train.task.coarse_steps(cfg.train.trainer.steps),
        cfg.train.trainer.steps,
        spec.out.display()
    ));
    let model = cfg.model.init(&device)?;
    let (_, outcome) = train(&mut task, model, &run, &run_options(spec))?;
    Ok(outcome)
}

/// Trains HOOD of `cfg` into `spec.out` from bodies, procedural garments and motions (no
/// dataset): builds the garment and motion pools, fits the normalisers on skinned
/// samples (saved as `hood.json` before the first step; a resumed run keeps its own),
/// then runs the loop with the rollout and collision curriculum.
pub fn train_hood(
    cfg: &HoodRun,
    spec: &TrainSpec,
    log: &mut dyn FnMut(&str),
) -> Result<Outcome, PipelineError> {
    if let Some(data) = &spec.data {
        return Err(PipelineError::Invalid(format!(
            "--data {}: hood trains from bodies, procedural garments and motions, not a dataset; leave --data out (motion files go in [train] motion_files)",
            data.display()
        )));
    }
    let body = weft_body::BodyModel::load_or_default(cfg.train.task.body.as_deref())
        .map_err(|e| PipelineError::Invalid(format!("[train] body: {e}")))?;
    let run = cfg.run_dir(&spec.out)?;
    let stats_file = spec.out.join(weft_models::hood::STATS_FILE);
    let stats = if spec.resume && stats_file.exists() {
        Some(weft_models::hood::HoodStats::read(&spec.out)?)
    } else {
        None
    };
    let device = seeded(&cpu_autodiff(), cfg.train.trainer.seed);
    let mut task = HoodTask::new(
        &cfg.model,
        &cfg.train.task,
        body,
        stats,
        cfg.train.trainer.seed,
        &device,
    )?;
    weft_train::tasks::hood::save_stats(&spec.out, task.stats())?;
    let (garments, motions, validation) = task.describe();
    log(&format!(
        "training hood ({} preset, propagation radius {} edges) on {garments} garments x {motions} motions, rollouts up to {} steps of 1/{} s; {validation} validation scenes -> {}",
        cfg.preset,
        cfg.model.propagation_radius()?,
        cfg.train.task.max_rollout,
        cfg.model.step_fps,
        spec.out.display()
    ));
    let model = cfg.model.init(&device)?;
    let (_, outcome) = train(&mut task, model, &run, &run_options(spec))?;
    Ok(outcome)
}
