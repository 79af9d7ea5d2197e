//! Evaluation as the CLI and the demo run it: any run directory, whatever system trained
//! it, against the no-learning baselines (LBS and DQS with transferred weights) on one
//! split, in one loop, with its report in RUN/report/.

use std::path::Path;

use weft_data::Dataset;
use weft_eval::evaluate::{evaluate, write_report, EvalOptions, Evaluation};
use weft_models::{load_deformer, Deformer, SkinningBaseline};

use crate::error::{stage, PipelineError};

/// Evaluates the run in `run` and the baselines on `data`, writes `RUN/report/`
/// (eval.json, eval.md, eval.html and pictures) and returns the evaluation and the
/// report's HTML path. `progress` gets one line per sequence.
pub fn evaluate_run(
    run: &Path,
    data: &Path,
    opts: &EvalOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<(Evaluation, std::path::PathBuf), PipelineError> {
    let model = load_deformer(run).map_err(stage(&format!("loading run {}", run.display())))?;
    let dataset =
        Dataset::open(data).map_err(stage(&format!("opening dataset {}", data.display())))?;
    let methods: [&dyn Deformer; 3] = [
        model.as_ref(),
        &SkinningBaseline::LBS,
        &SkinningBaseline::DQS,
    ];
    let eval = evaluate(&methods, run, &dataset, opts, progress)?;
    let html = write_report(&eval, &run.join("report"))?;
    Ok((eval, html))
}
