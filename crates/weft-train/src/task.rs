//! What the training loop asks of a system ([`TrainTask`]): its items, its named and
//! weighted loss terms, its own stage (a curriculum the task owns and the loop
//! checkpoints) and its named validation metrics.
//!
//! The loop ([`crate::trainer`]) knows nothing of any system: Multilevel's two-step
//! schedule, HOOD's rollout-length curriculum or a single-stage task are all a
//! [`TrainTask::Stage`] that [`TrainTask::advance`] moves and [`TrainTask::enter_stage`]
//! applies to the model (freezing parameters, caching what frozen parameters make
//! constant).

use std::collections::BTreeMap;
use std::fmt::Debug;

use burn::module::Module;
use burn::tensor::Tensor;
use serde::{de::DeserializeOwned, Serialize};

use crate::error::Result;

/// A loss term of a task: a small copyable value with a name for logs.
pub trait LossTerm: Copy + PartialEq + Debug {
    /// The name in metrics.jsonl, the curves and error messages.
    fn name(self) -> &'static str;
}

/// Named validation metrics (lower is better for the task's primary one).
pub type Metrics = BTreeMap<String, f64>;

/// What happened at the end of one optimiser step, for [`TrainTask::advance`].
#[derive(Clone, Copy, Debug)]
pub struct StepEnd<'a, T> {
    /// Steps taken, this one included.
    pub step: usize,
    /// Steps of the whole run.
    pub total: usize,
    /// Whether this step finished an epoch of the training items.
    pub epoch_ended: bool,
    /// The unweighted mean of each evaluated term over the batch; `None` when the step
    /// was skipped for a non-finite loss.
    pub terms: Option<&'a [(T, f64)]>,
}

impl<T: LossTerm> StepEnd<'_, T> {
    /// The mean of `term` at this step, if it was evaluated and the step not skipped.
    pub fn term(&self, term: T) -> Option<f64> {
        self.terms?
            .iter()
            .find(|(t, _)| *t == term)
            .map(|&(_, v)| v)
    }
}

/// What the loop trains: a model, its training items, its losses and its stages.
pub trait TrainTask {
    /// The network (a burn module on an autodiff device).
    type Model: Module + Clone;
    /// The task's loss terms.
    type Term: LossTerm;
    /// Where the task's curriculum is, saved in every checkpoint so a resumed run goes
    /// on in the same stage (`Default`: where a fresh run starts).
    type Stage: Clone + Debug + PartialEq + Default + Serialize + DeserializeOwned;

    /// Training items per epoch.
    fn item_count(&self) -> usize;

    /// The terms evaluated in `stage`, each with its weight (a term left out is not
    /// evaluated at all).
    fn terms(&self, stage: &Self::Stage) -> Vec<(Self::Term, f64)>;

    /// The unweighted loss terms `terms` of item `item` under `model`, each a `[1]`
    /// tensor, in the order asked.
    fn losses(
        &mut self,
        model: &Self::Model,
        item: usize,
        terms: &[Self::Term],
    ) -> Result<Vec<Tensor<1>>>;

    /// The validation metrics of `model` (in validation mode); must contain
    /// [`TrainTask::primary_metric`].
    fn validate(&mut self, model: &Self::Model) -> Result<Metrics>;

    /// The metric a plateau schedule and the progress bar watch.
    fn primary_metric(&self) -> &'static str;

    /// The stage's name in logs.
    fn stage_name(&self, stage: &Self::Stage) -> String;

    /// Moves `stage` after a step; returns whether it changed (the loop then calls
    /// [`TrainTask::enter_stage`]).
    fn advance(&self, stage: &mut Self::Stage, end: &StepEnd<'_, Self::Term>) -> bool;

    /// Prepares `model` and the task for `stage`: called when a run starts or resumes
    /// and after every change.
    fn enter_stage(&mut self, model: Self::Model, stage: &Self::Stage) -> Self::Model;

    /// What the task carries from item to item besides the model and the stage (HOOD's
    /// kept rollouts), saved in every checkpoint so that a resumed run repeats the
    /// uninterrupted one; `None`: nothing.
    fn memory(&self) -> Option<serde_json::Value> {
        None
    }

    /// Takes back what [`TrainTask::memory`] saved; the error says what does not fit.
    fn restore_memory(&mut self, memory: serde_json::Value) -> std::result::Result<(), String> {
        let _ = memory;
        Ok(())
    }
}
