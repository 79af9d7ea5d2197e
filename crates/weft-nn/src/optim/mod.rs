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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_annealing_runs_from_the_initial_to_the_minimum_rate() {
        let mut schedule = cosine_annealing(3e-3, 1e-5, 4).unwrap();
        let rates: Vec<f64> = (0..5).map(|_| schedule.step().base()).collect();
        assert!((rates[0] - 3e-3).abs() < 1e-12);
        assert!((rates[2] - (1e-5 + 0.5 * (3e-3 - 1e-5))).abs() < 1e-12);
        assert!((rates[4] - 1e-5).abs() < 1e-12);
        assert!(rates.windows(2).all(|w| w[1] <= w[0]));
        assert!(matches!(
            cosine_annealing(3e-3, 0.0, 0),
            Err(NnError::Config(_))
        ));
    }
}
