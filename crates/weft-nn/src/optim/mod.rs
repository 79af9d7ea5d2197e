//! Optimisation: Adamax (seed 000 supplement §4 trains with it; burn has none) on burn's
//! per-tensor [`Optimizer`](burn::optim::Optimizer) trait, and the cosine annealing
//! learning-rate schedule, which burn has ([`cosine_annealing`]).

mod adamax;

pub use adamax::{Adamax, AdamaxConfig, AdamaxState};

use burn::lr_scheduler::cosine::CosineAnnealingLrSchedulerConfig;
use burn::lr_scheduler::module_lr_scheduler::ModuleLrScheduler;

use crate::error::{NnError, Result};

/// Cosine annealing from `initial_lr` to `min_lr` over `steps` steps (Loshchilov & Hutter,
/// without restarts), as seed 000 supplement §4 decays Adamax's rate (initial 3e-3).
pub fn cosine_annealing(initial_lr: f64, min_lr: f64, steps: usize) -> Result<ModuleLrScheduler> {
    CosineAnnealingLrSchedulerConfig::new(initial_lr, steps)
        .with_min_lr(min_lr)
        .init()
        .map_err(NnError::Config)
}
