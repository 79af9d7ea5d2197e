//! The training loop, generic over what is trained ([`TrainTask`]): the configured
//! optimiser and learning-rate schedule ([`crate::optim`]), the two-step schedule,
//! checkpoints (the newest `keep_checkpoints` kept), the metrics log, the progress bar and
//! the non-finite guard.
//!
//! One step: take `batch` items from the sampler, evaluate the phase's loss terms for
//! each, check every term is finite on the host, back-propagate the weighted mean, step
//! the optimizer. When a term is not finite the step is skipped and reported (step,
//! term), the model and optimizer go back to the last state whose loss was finite, and
//! training goes on with the next items; after `max_non_finite` such steps in a row it
//! stops with [`TrainError::NonFinite`].

use std::collections::BTreeMap;
use std::time::Instant;

use burn::module::{Module, ParamGroup};
use burn::optim::{GradientsParams, ModuleOptimizer};
use burn::tensor::Tensor;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::config::TrainConfig;
use crate::error::{Result, TrainError};
use crate::loss::Term;
use crate::metrics::{MetricsLog, Record};
use crate::optim::{LrSchedule, LrState};
use crate::run::{RunDir, TrainerState, FORMAT_VERSION};
use crate::sampler::{Cursor, Sampler};
use crate::schedule::{Phase, ScheduleState};

/// What the loop trains: a model, its training items and its losses.
pub trait TrainTask {
    /// The network (a burn module on an autodiff device).
    type Model: Module + Clone;

    /// Training items (windows of frames) per epoch.
    fn item_count(&self) -> usize;

    /// The unweighted loss terms `terms` of item `item` under `model`, each a `[1]`
    /// tensor, in the order asked.
    fn losses(
        &mut self,
        model: &Self::Model,
        item: usize,
        terms: &[Term],
    ) -> Result<Vec<Tensor<1>>>;

    /// Mean vertex error on the validation split, mm (`model` is in validation mode).
    fn validate(&mut self, model: &Self::Model) -> Result<f64>;

    /// The parameters step 2 trains (the second M^mp submodule for Multilevel).
    fn physics_group(&self, model: &Self::Model) -> ParamGroup;

    /// Called when the phase changes, before the next step (e.g. to cache encodings that
    /// frozen parameters make constant).
    fn on_phase(&mut self, _phase: Phase) {}
}

/// How to run (not part of the run's configuration).
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Continue the run in the directory from its latest checkpoint.
    pub resume: bool,
    /// Draw a progress bar on stderr (when it is a terminal).
    pub progress: bool,
    /// Stop after this many steps in this session (a checkpoint is written), e.g. to
    /// split a long run into jobs; none: run to the configured step count.
    pub session_steps: Option<usize>,
}

/// What a finished (or paused) run reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Steps taken in total.
    pub steps: usize,
    /// Steps skipped for a non-finite loss.
    pub skipped: usize,
    /// The phase at the end.
    pub phase: Phase,
    /// The last validation error, mm.
    pub validation_mm: Option<f64>,
    /// Mean step time of this session, ms.
    pub mean_step_ms: f64,
    /// The last checkpoint written.
    pub checkpoint: std::path::PathBuf,
}

/// Freezes everything but the step-2 group when `phase` asks for it.
fn apply_phase<T: TrainTask>(task: &T, model: T::Model, phase: Phase) -> T::Model {
    if phase.is_frozen() {
        let group = task.physics_group(&model);
        model.no_grad().set_require_grad_group(group, true)
    } else {
        model
    }
}

fn optimizer(cfg: &TrainConfig) -> ModuleOptimizer {
    cfg.optimizer.init(cfg.grad_clip_norm)
}

fn host_scalar(t: &Tensor<1>) -> f64 {
    t.to_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .ok()
        .and_then(|v| v.first().copied())
        .unwrap_or(f64::NAN)
}

/// Trains `model` (fresh, built from the run's seed) on `task` in `run`; returns the
/// trained model and the outcome. With `options.resume` the latest checkpoint replaces
/// `model`'s parameters and the loop continues where it stopped.
pub fn train<T: TrainTask>(
    task: &mut T,
    model: T::Model,
    run: &RunDir,
    options: &RunOptions,
) -> Result<(T::Model, Outcome)> {
    let cfg = run.train().clone();
    let items = task.item_count();
    if items == 0 {
        return Err(TrainError::config(
            "data",
            "no training windows",
            "at least one training window",
        ));
    }
    let metrics_path = run.root().join("metrics.jsonl");
    let (mut model, mut optim, mut state, mut log) = if options.resume {
        run.check_existing()?;
        let (model, optim, state) = run.load(model, optimizer(&cfg))?;
        let log = MetricsLog::resume(&metrics_path, state.step)?;
        (model, optim, state, log)
    } else {
        run.start()?;
        let state = TrainerState {
            format_version: FORMAT_VERSION,
            preset: run.preset().to_string(),
            model: run.model_text()?,
            step: 0,
            cursor: Cursor::default(),
            schedule: ScheduleState::default(),
            lr: LrState::default(),
            non_finite_in_a_row: 0,
            validation_mm: None,
        };
        (
            model,
            optimizer(&cfg),
            state,
            MetricsLog::create(&metrics_path)?,
        )
    };
    model = apply_phase(task, model, state.schedule.phase);
    task.on_phase(state.schedule.phase);

    let mut lr_schedule = LrSchedule::new(
        &cfg.lr_schedule,
        cfg.learning_rate,
        cfg.min_learning_rate,
        cfg.steps,
        state.step,
        state.lr.clone(),
    )?;
    let mut sampler = Sampler::new(cfg.seed, items, state.cursor);
    let total = cfg.steps;
    let end = options
        .session_steps
        .map_or(total, |s| (state.step + s).min(total));

    let bar = if options.progress {
        ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {pos}/{len} ETA {eta} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_position(state.step as u64);

    // The error before any training (for Multilevel: close to LBS with the transferred
    // weights, which the untrained model starts from), logged as step 0.
    if !options.resume && cfg.validate_every > 0 {
        let v = task.validate(&model.valid())?;
        state.validation_mm = Some(v);
        lr_schedule.observe_validation(v);
        state.lr = lr_schedule.state().clone();
        log.push(Record {
            phase: state.schedule.phase.name().into(),
            lr: cfg.learning_rate,
            validation_mm: Some(v),
            event: Some("start".into()),
            ..Record::default()
        })?;
    }

    let mut good: (T::Model, ModuleOptimizer) = (model.clone(), optim.clone());
    let mut skipped = 0usize;
    let mut session_ms = 0.0;
    let mut session_steps = 0usize;
    let mut last_checkpoint = None;

    while state.step < end {
        let started = Instant::now();
        let lr = lr_schedule.next_rate();
        let phase = state.schedule.phase;
        let weighted = phase.weighted_terms(&cfg.weights, &cfg.schedule);
        let terms: Vec<Term> = weighted.iter().map(|&(t, _)| t).collect();
        let mut sums: Vec<f64> = vec![0.0; terms.len()];
        let mut total_loss: Option<Tensor<1>> = None;
        let mut bad_term: Option<Term> = None;
        let mut epoch_ended = false;
        for _ in 0..cfg.batch {
            let (item, last) = sampler.next_item();
            epoch_ended |= last;
            let values = task.losses(&model, item, &terms)?;
            for (k, ((term, weight), value)) in weighted.iter().zip(&values).enumerate() {
                let v = host_scalar(value);
                if !v.is_finite() && bad_term.is_none() {
                    bad_term = Some(*term);
                }
                sums[k] += v;
                let w = value.clone().mul_scalar(*weight / cfg.batch as f64);
                total_loss = Some(match total_loss {
                    Some(acc) => acc + w,
                    None => w,
                });
            }
        }
        state.step += 1;
        state.cursor = sampler.cursor();
        let means: Vec<f64> = sums.iter().map(|s| s / cfg.batch as f64).collect();
        let mut record = Record {
            step: state.step,
            epoch: state.cursor.epoch,
            phase: phase.name().into(),
            lr,
            ..Record::default()
        };

        if let Some(term) = bad_term {
            // Skip: back to the last state whose loss was finite.
            skipped += 1;
            state.non_finite_in_a_row += 1;
            (model, optim) = good.clone();
            record.event = Some("non_finite".into());
            record.term = Some(term.name().into());
            record.step_ms = started.elapsed().as_secs_f64() * 1e3;
            log.push(record.clone())?;
            bar.println(format!(
                "step {}: loss term `{}` is not finite; step skipped, last good state restored",
                state.step,
                term.name()
            ));
            if state.non_finite_in_a_row >= cfg.max_non_finite {
                return Err(TrainError::NonFinite {
                    term: term.name().into(),
                    step: state.step,
                    consecutive: state.non_finite_in_a_row,
                    limit: cfg.max_non_finite,
                });
            }
        } else if let Some(loss) = total_loss {
            state.non_finite_in_a_row = 0;
            good = (model.clone(), optim.clone());
            record.loss = host_scalar(&loss);
            let grads = GradientsParams::from_grads(loss.backward(), &model);
            model = optim.step(lr, model, grads);
            if let Some(monitored) = state.schedule.monitored() {
                if let Some(k) = terms.iter().position(|&t| t == monitored) {
                    state.schedule.observe(means[k]);
                }
            }
            record.terms = terms
                .iter()
                .zip(&means)
                .map(|(t, &v)| (t.name().to_string(), v))
                .collect::<BTreeMap<_, _>>();
        }

        // Schedule: rules at epoch ends, caps every step.
        let switched = if epoch_ended {
            state.schedule.end_epoch(&cfg.schedule, state.step, total)
        } else {
            None
        }
        .or_else(|| state.schedule.check_caps(&cfg.schedule, state.step, total));
        if let Some(next) = switched {
            model = apply_phase(task, model, next);
            good = (model.clone(), optim.clone());
            task.on_phase(next);
            record
                .event
                .get_or_insert_with(|| format!("phase:{}", next.name()));
            bar.println(format!(
                "step {}: schedule enters phase `{}`",
                state.step,
                next.name()
            ));
        }

        let final_step = state.step == end;
        if cfg.validate_every > 0 && (state.step % cfg.validate_every == 0 || state.step == total) {
            let v = task.validate(&model.valid())?;
            state.validation_mm = Some(v);
            record.validation_mm = Some(v);
            if let Some(rate) = lr_schedule.observe_validation(v) {
                bar.println(format!(
                    "step {}: no better validation for a while; learning rate {rate:.3e}",
                    state.step
                ));
            }
            state.lr = lr_schedule.state().clone();
        }
        let ms = started.elapsed().as_secs_f64() * 1e3;
        if record.event.as_deref() != Some("non_finite") {
            record.step_ms = ms;
            log.push(record.clone())?;
        }
        session_ms += ms;
        session_steps += 1;
        bar.set_position(state.step as u64);
        bar.set_message(format!(
            "loss {:.4}{}",
            record.loss,
            state
                .validation_mm
                .map_or(String::new(), |v| format!(" val {v:.1} mm"))
        ));
        if state.step % cfg.checkpoint_every == 0 || final_step {
            last_checkpoint = Some(run.save(&model, &optim, &state)?);
            log.write_curves(
                &run.root().join("curves.png"),
                items.div_ceil(cfg.batch).clamp(1, 50),
            )?;
        }
    }
    bar.finish_and_clear();
    let checkpoint = match last_checkpoint {
        Some(p) => p,
        // Nothing left to do (resumed a finished run): the latest checkpoint stands.
        None => run.checkpoints().join(format!(
            "{}.bpk",
            run.latest()?.unwrap_or_else(|| RunDir::stem(state.step))
        )),
    };
    Ok((
        model,
        Outcome {
            steps: state.step,
            skipped,
            phase: state.schedule.phase,
            validation_mm: state.validation_mm,
            mean_step_ms: if session_steps > 0 {
                session_ms / session_steps as f64
            } else {
                0.0
            },
            checkpoint,
        },
    ))
}
