//! The training loop, generic over what is trained ([`TrainTask`]): the configured
//! optimiser and learning-rate schedule ([`crate::optim`]), the task's stages,
//! checkpoints (the newest `keep_checkpoints` kept), the metrics log, the progress bar and
//! the non-finite guard.
//!
//! One step: take `batch` items from the sampler, evaluate the stage's loss terms for
//! each, check every term is finite on the host, back-propagate the weighted mean, step
//! the optimizer. When a term is not finite the step is skipped and reported (step,
//! term), the model and optimizer go back to the last state whose loss was finite, and
//! training goes on with the next items; after `max_non_finite` such steps in a row it
//! stops with [`TrainError::NonFinite`].

use std::collections::BTreeMap;
use std::time::Instant;

use burn::module::Module;
use burn::optim::{GradientsParams, ModuleOptimizer};
use burn::tensor::Tensor;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::config::TrainConfig;
use crate::error::{Result, TrainError};
use crate::metrics::{MetricsLog, Record};
use crate::optim::{LrSchedule, LrState};
use crate::run::{RunDir, TrainerState, FORMAT_VERSION};
use crate::sampler::{Cursor, Sampler};
use crate::task::{LossTerm, Metrics, StepEnd, TrainTask};

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
    /// The name of the task's stage at the end.
    pub stage: String,
    /// The last validation metrics (empty when validation is off).
    pub validation: Metrics,
    /// Mean step time of this session, ms.
    pub mean_step_ms: f64,
    /// The last checkpoint written.
    pub checkpoint: std::path::PathBuf,
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
    // Held until the run returns: no second writer, whatever happens to this one.
    let _lock = run.lock()?;
    let (mut model, mut optim, mut state, mut log) = if options.resume {
        run.check_existing()?;
        if run.latest()?.is_none() {
            if let Some(stem) = run.resume_point()? {
                eprintln!(
                    "{}: checkpoints/latest is missing; resuming from {stem}, the newest \
                     complete checkpoint",
                    run.root().display()
                );
            }
        }
        let (model, optim, mut state) = run.load(model, optimizer(&cfg))?;
        if let Some(memory) = state.memory.take() {
            task.restore_memory(memory)
                .map_err(|found| TrainError::Mismatch {
                    path: run.checkpoints(),
                    field: "memory".into(),
                    found,
                    expected: "the task's kept state for this run".into(),
                })?;
        }
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
            stage: T::Stage::default(),
            lr: LrState::default(),
            non_finite_in_a_row: 0,
            validation: Metrics::new(),
            memory: None,
        };
        (
            model,
            optimizer(&cfg),
            state,
            MetricsLog::create(&metrics_path)?,
        )
    };
    model = task.enter_stage(model, &state.stage);
    let primary = task.primary_metric();

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

    // The metrics before any training (for Multilevel: close to LBS with the
    // transferred weights, which the untrained model starts from), logged as step 0.
    if !options.resume && cfg.validate_every > 0 {
        let v = validate(task, &model)?;
        lr_schedule.observe_validation(primary_value(&v, primary));
        state.lr = lr_schedule.state().clone();
        log.push(Record {
            stage: task.stage_name(&state.stage),
            lr: cfg.learning_rate,
            validation: v.clone(),
            event: Some("start".into()),
            ..Record::default()
        })?;
        state.validation = v;
    }

    let mut good: (T::Model, ModuleOptimizer) = (model.clone(), optim.clone());
    let mut skipped = 0usize;
    let mut session_ms = 0.0;
    let mut session_steps = 0usize;
    let mut last_checkpoint = None;

    while state.step < end {
        let started = Instant::now();
        let lr = lr_schedule.next_rate();
        let weighted = task.terms(&state.stage);
        let terms: Vec<T::Term> = weighted.iter().map(|&(t, _)| t).collect();
        let mut sums: Vec<f64> = vec![0.0; terms.len()];
        let mut total_loss: Option<Tensor<1>> = None;
        let mut bad_term: Option<T::Term> = None;
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
            stage: task.stage_name(&state.stage),
            lr,
            ..Record::default()
        };

        let mut means_of_good_step: Option<Vec<(T::Term, f64)>> = None;
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
            record.terms = terms
                .iter()
                .zip(&means)
                .map(|(t, &v)| (t.name().to_string(), v))
                .collect::<BTreeMap<_, _>>();
            means_of_good_step = Some(terms.iter().copied().zip(means).collect());
        }

        let end_of_step = StepEnd {
            step: state.step,
            total,
            epoch_ended,
            terms: means_of_good_step.as_deref(),
        };
        if task.advance(&mut state.stage, &end_of_step) {
            model = task.enter_stage(model, &state.stage);
            good = (model.clone(), optim.clone());
            let name = task.stage_name(&state.stage);
            bar.println(format!("step {}: entering stage `{name}`", state.step));
            record.event.get_or_insert(format!("stage:{name}"));
        }

        let final_step = state.step == end;
        if cfg.validate_every > 0 && (state.step % cfg.validate_every == 0 || state.step == total) {
            let v = validate(task, &model)?;
            if let Some(rate) = lr_schedule.observe_validation(primary_value(&v, primary)) {
                bar.println(format!(
                    "step {}: no better validation for a while; learning rate {rate:.3e}",
                    state.step
                ));
            }
            state.lr = lr_schedule.state().clone();
            record.validation = v.clone();
            state.validation = v;
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
                .validation
                .get(primary)
                .map_or(String::new(), |v| format!(" {primary} {v:.4}"))
        ));
        if state.step % cfg.checkpoint_every == 0 || final_step {
            state.memory = task.memory();
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
            stage: task.stage_name(&state.stage),
            validation: state.validation,
            mean_step_ms: if session_steps > 0 {
                session_ms / session_steps as f64
            } else {
                0.0
            },
            checkpoint,
        },
    ))
}

/// The task's metrics of `model` in validation mode; the primary one must be there.
fn validate<T: TrainTask>(task: &mut T, model: &T::Model) -> Result<Metrics> {
    let v = task.validate(&model.valid())?;
    let primary = task.primary_metric();
    if !v.contains_key(primary) {
        return Err(TrainError::config(
            "validation",
            v.keys().cloned().collect::<Vec<_>>().join(", "),
            &format!("the task's primary metric `{primary}`"),
        ));
    }
    Ok(v)
}

fn primary_value(metrics: &Metrics, primary: &str) -> f64 {
    metrics.get(primary).copied().unwrap_or(f64::NAN)
}
