//! Evaluation as the CLI and the demo run it: any run directory, whatever system trained
//! it, against the no-learning baselines (LBS and DQS with transferred weights) on one
//! split, in one loop, with its report in RUN/report/.

use std::path::Path;

use weft_data::Dataset;
use weft_eval::evaluate::{evaluate, write_report, EvalOptions, Evaluation};
use weft_models::garfitnet::GarFitPredictor;
use weft_models::hood::{HoodPredictor, RolloutOptions, OUTSIDE_MATERIAL_SPACE};
use weft_models::run::read_run_config;
use weft_models::{load_deformer, Deformer, ModelKind, SkinningBaseline, StepJudge};

use crate::error::{stage, PipelineError};

/// Evaluates the run in `run` and the baselines on `data`, writes `RUN/report/`
/// (eval.json, eval.md, eval.html and pictures) and returns the evaluation and the
/// report's HTML path. `progress` gets one line per sequence. A HOOD run rolls out with
/// `hood` (its run-time corrections), and with `objective` its objective is scored
/// beside it (the same rollout by implicit Euler steps, [`RolloutOptions::objective`]);
/// other kinds ignore both.
pub fn evaluate_run(
    run: &Path,
    data: &Path,
    opts: &EvalOptions,
    hood: &RolloutOptions,
    objective: bool,
    progress: &mut dyn FnMut(&str),
) -> Result<(Evaluation, std::path::PathBuf), PipelineError> {
    let loading = || format!("loading run {}", run.display());
    // GarFitNet is scored twice: its coarse regressor alone and the refined output
    // (Tables 4.1–4.2).
    let kind = read_run_config(run).map_err(stage(&loading()))?.0.model;
    let garfit = match kind {
        ModelKind::GarFitNet => Some(GarFitPredictor::load(run).map_err(stage(&loading()))?),
        _ => None,
    };
    // A HOOD run is kept as itself: its objective also judges every method's steps.
    let hood_model = match kind {
        ModelKind::Hood => {
            let mut h = HoodPredictor::load(run).map_err(stage(&loading()))?;
            h.options = *hood;
            Some(h)
        }
        _ => None,
    };
    let model: Option<Box<dyn Deformer + Send>> = match kind {
        ModelKind::GarFitNet | ModelKind::Hood => None,
        _ => Some(load_deformer(run).map_err(stage(&loading()))?),
    };
    let objective = match (kind, objective) {
        (ModelKind::Hood, true) => {
            let mut h = HoodPredictor::load(run).map_err(stage(&loading()))?;
            h.options = RolloutOptions {
                objective: true,
                ..*hood
            };
            Some(h)
        }
        _ => None,
    };
    let dataset =
        Dataset::open(data).map_err(stage(&format!("opening dataset {}", data.display())))?;
    if let Some(h) = &hood_model {
        let mut names: Vec<&str> = dataset
            .records()
            .iter()
            .map(|r| r.material.as_str())
            .collect();
        names.sort_unstable();
        names.dedup();
        for note in h.presets_outside(&names) {
            progress(&format!(
                "warning: {note} ({}): {OUTSIDE_MATERIAL_SPACE}",
                run.display()
            ));
        }
    }
    let coarse = garfit.as_ref().map(GarFitPredictor::coarse_stage);
    let mut methods: Vec<&dyn Deformer> = Vec::new();
    if let Some(g) = &garfit {
        methods.push(g);
    }
    if let Some(c) = &coarse {
        methods.push(c);
    }
    if let Some(m) = &model {
        methods.push(m.as_ref());
    }
    if let Some(h) = &hood_model {
        methods.push(h);
    }
    if let Some(o) = &objective {
        methods.push(o);
    }
    methods.extend([
        &SkinningBaseline::LBS as &dyn Deformer,
        &SkinningBaseline::DQS,
    ]);
    // A HOOD run's objective scores every method's steps (issue 12 item 8).
    let judge = hood_model.as_ref().map(|h| h as &dyn StepJudge);
    let eval = evaluate(&methods, judge, run, &dataset, opts, progress)?;
    let html = write_report(&eval, &run.join("report"))?;
    Ok((eval, html))
}
