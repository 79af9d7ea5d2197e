//! Optimisers and learning-rate schedules chosen in the config (`[train.optimizer]`,
//! `[train.lr_schedule]`), so each model trains with what its paper used: Multilevel with
//! Adamax and cosine annealing (seed 000 supp. §4), DenseGATs with Adam and a plateau
//! decay, HOOD with Adam and exponential decay.
//!
//! The rate starts at `train.learning_rate`; every decaying schedule stops at
//! `train.min_learning_rate` (the floor). The schedules that are a function of the step
//! (constant, cosine, step, exponential) are fast-forwarded on resume; the plateau
//! schedule depends on the validations seen, so its state ([`LrState`]) is saved with
//! each checkpoint and a resumed run continues bit for bit.

use burn::grad_clipping::GradientClippingConfig;
use burn::lr_scheduler::module_lr_scheduler::ModuleLrScheduler;
use burn::optim::decay::WeightDecayConfig;
use burn::optim::{AdamConfig, AdamWConfig, ModuleOptimizer};
use serde::{Deserialize, Serialize};

use crate::error::{Result, TrainError};

/// Adam's and AdamW's moment parameters (burn's defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdamParams {
    /// β₁, decay of the first moment.
    pub beta_1: f32,
    /// β₂, decay of the second moment.
    pub beta_2: f32,
    /// ε added to the root of the second moment.
    pub epsilon: f32,
    /// Weight decay: L2 added to the gradient (Adam) or decoupled (AdamW); 0: none.
    pub weight_decay: f32,
}

impl AdamParams {
    /// burn's Adam defaults (no weight decay).
    fn adam() -> Self {
        AdamParams {
            beta_1: 0.9,
            beta_2: 0.999,
            epsilon: 1e-5,
            weight_decay: 0.0,
        }
    }
}

impl Default for AdamParams {
    fn default() -> Self {
        AdamParams::adam()
    }
}

/// AdamW's parameters (burn's defaults: weight decay 1e-4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdamWParams {
    /// β₁, decay of the first moment.
    pub beta_1: f32,
    /// β₂, decay of the second moment.
    pub beta_2: f32,
    /// ε added to the root of the second moment.
    pub epsilon: f32,
    /// Decoupled weight decay λ.
    pub weight_decay: f32,
}

impl Default for AdamWParams {
    fn default() -> Self {
        AdamWParams {
            weight_decay: 1e-4,
            ..AdamWParams::from(AdamParams::adam())
        }
    }
}

impl From<AdamParams> for AdamWParams {
    fn from(p: AdamParams) -> Self {
        AdamWParams {
            beta_1: p.beta_1,
            beta_2: p.beta_2,
            epsilon: p.epsilon,
            weight_decay: p.weight_decay,
        }
    }
}

/// Adamax's parameters (seed 000 supp. §4; weft-nn's defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdamaxParams {
    /// β₁, decay of the first moment.
    pub beta_1: f64,
    /// β₂, decay of the infinity norm.
    pub beta_2: f64,
    /// ε, floor of the infinity norm.
    pub epsilon: f64,
    /// L2 weight decay λ (added to the gradient).
    pub weight_decay: f64,
}

impl Default for AdamaxParams {
    fn default() -> Self {
        let c = weft_nn::AdamaxConfig::new();
        AdamaxParams {
            beta_1: c.beta_1,
            beta_2: c.beta_2,
            epsilon: c.epsilon,
            weight_decay: c.weight_decay,
        }
    }
}

/// The optimiser (`[train.optimizer]`, `kind = "adam" | "adamw" | "adamax"`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum OptimizerConfig {
    /// Adam (burn's).
    Adam(AdamParams),
    /// AdamW (burn's), decoupled weight decay.
    AdamW(AdamWParams),
    /// Adamax (weft-nn's; burn has none).
    Adamax(AdamaxParams),
}

impl Default for OptimizerConfig {
    fn default() -> Self {
        OptimizerConfig::Adamax(AdamaxParams::default())
    }
}

impl OptimizerConfig {
    /// The optimiser for a whole module, clipping gradients to `clip_norm` when given.
    pub fn init(&self, clip_norm: Option<f64>) -> ModuleOptimizer {
        let optim = match self {
            OptimizerConfig::Adam(p) => AdamConfig::new()
                .with_beta_1(p.beta_1)
                .with_beta_2(p.beta_2)
                .with_epsilon(p.epsilon)
                .with_weight_decay(
                    (p.weight_decay != 0.0).then(|| WeightDecayConfig::new(p.weight_decay)),
                )
                .init(),
            OptimizerConfig::AdamW(p) => AdamWConfig::new()
                .with_beta_1(p.beta_1)
                .with_beta_2(p.beta_2)
                .with_epsilon(p.epsilon)
                .with_weight_decay(p.weight_decay)
                .init(),
            OptimizerConfig::Adamax(p) => weft_nn::AdamaxConfig::new()
                .with_beta_1(p.beta_1)
                .with_beta_2(p.beta_2)
                .with_epsilon(p.epsilon)
                .with_weight_decay(p.weight_decay)
                .init(),
        };
        match clip_norm {
            Some(norm) => {
                optim.with_grad_clipping(GradientClippingConfig::Norm(norm as f32).init())
            }
            None => optim,
        }
    }

    /// Checks the parameters; errors name the field as in config.toml.
    pub fn validate(&self) -> Result<()> {
        let (b1, b2, eps, wd) = match self {
            OptimizerConfig::Adam(p) => (
                f64::from(p.beta_1),
                f64::from(p.beta_2),
                f64::from(p.epsilon),
                f64::from(p.weight_decay),
            ),
            OptimizerConfig::AdamW(p) => (
                f64::from(p.beta_1),
                f64::from(p.beta_2),
                f64::from(p.epsilon),
                f64::from(p.weight_decay),
            ),
            OptimizerConfig::Adamax(p) => (p.beta_1, p.beta_2, p.epsilon, p.weight_decay),
        };
        for (field, v) in [("beta_1", b1), ("beta_2", b2)] {
            if !(0.0..1.0).contains(&v) {
                return Err(TrainError::config(
                    &format!("train.optimizer.{field}"),
                    v,
                    "a value in [0, 1)",
                ));
            }
        }
        if !(eps.is_finite() && eps > 0.0) {
            return Err(TrainError::config(
                "train.optimizer.epsilon",
                eps,
                "a finite value > 0",
            ));
        }
        if !(wd.is_finite() && wd >= 0.0) {
            return Err(TrainError::config(
                "train.optimizer.weight_decay",
                wd,
                "a finite value >= 0",
            ));
        }
        Ok(())
    }
}

/// How the learning rate moves (`[train.lr_schedule]`, `kind = ...`), from
/// `train.learning_rate` down to no less than `train.min_learning_rate`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LrScheduleConfig {
    /// The initial rate throughout (the floor is not used).
    Constant,
    /// Cosine annealing from the initial rate to the floor over the run's steps.
    #[default]
    Cosine,
    /// Multiplied by `factor` every `every` steps.
    Step {
        /// Steps between decays.
        every: usize,
        /// The multiplier, in (0, 1).
        factor: f64,
    },
    /// Multiplied by `gamma` every step.
    Exponential {
        /// The per-step multiplier, in (0, 1].
        gamma: f64,
    },
    /// Multiplied by `factor` after `patience` validations in a row without a new best
    /// value of the validation metric (lower is better).
    Plateau {
        /// The multiplier, in (0, 1).
        factor: f64,
        /// Validations (not epochs) without improvement before a decay.
        patience: usize,
    },
}

impl LrScheduleConfig {
    /// Checks the parameters; errors name the field as in config.toml.
    pub fn validate(&self) -> Result<()> {
        let factor = |field: &str, f: f64, closed: bool| {
            let ok = f.is_finite() && f > 0.0 && (f < 1.0 || (closed && f == 1.0));
            if ok {
                Ok(())
            } else {
                Err(TrainError::config(
                    &format!("train.lr_schedule.{field}"),
                    f,
                    if closed {
                        "a value in (0, 1]"
                    } else {
                        "a value in (0, 1)"
                    },
                ))
            }
        };
        match *self {
            LrScheduleConfig::Constant | LrScheduleConfig::Cosine => Ok(()),
            LrScheduleConfig::Step { every, factor: f } => {
                if every == 0 {
                    return Err(TrainError::config(
                        "train.lr_schedule.every",
                        every,
                        "at least 1",
                    ));
                }
                factor("factor", f, false)
            }
            LrScheduleConfig::Exponential { gamma } => factor("gamma", gamma, true),
            LrScheduleConfig::Plateau {
                factor: f,
                patience,
            } => {
                if patience == 0 {
                    return Err(TrainError::config(
                        "train.lr_schedule.patience",
                        patience,
                        "at least 1",
                    ));
                }
                factor("factor", f, false)
            }
        }
    }
}

/// What a learning-rate schedule must carry across a resume (only the plateau schedule
/// has any).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LrState {
    /// The plateau schedule's current rate (none: not decayed yet).
    pub rate: Option<f64>,
    /// The best validation value seen.
    pub best: Option<f64>,
    /// Validations in a row without a new best.
    pub bad: usize,
}

/// A schedule running over a run of `steps` steps.
pub struct LrSchedule {
    cfg: LrScheduleConfig,
    initial: f64,
    floor: f64,
    /// burn's cosine annealing (the numbers Multilevel was trained with).
    cosine: Option<ModuleLrScheduler>,
    state: LrState,
    step: usize,
}

impl LrSchedule {
    /// The schedule `cfg` from `initial` down to `floor` over `steps` steps, resumed at
    /// step `step` with `state` (default for a fresh run).
    pub fn new(
        cfg: &LrScheduleConfig,
        initial: f64,
        floor: f64,
        steps: usize,
        step: usize,
        state: LrState,
    ) -> Result<Self> {
        let cosine = match cfg {
            LrScheduleConfig::Cosine => {
                // A pure function of the step: fast-forward it.
                let mut c = weft_nn::cosine_annealing(initial, floor, steps)?;
                for _ in 0..step {
                    c.step();
                }
                Some(c)
            }
            _ => None,
        };
        Ok(LrSchedule {
            cfg: cfg.clone(),
            initial,
            floor,
            cosine,
            state,
            step,
        })
    }

    /// The rate of the next step (advances the schedule by one step).
    pub fn next_rate(&mut self) -> f64 {
        let k = self.step;
        self.step += 1;
        let decayed = |r: f64| r.max(self.floor);
        match &self.cfg {
            LrScheduleConfig::Constant => self.initial,
            LrScheduleConfig::Cosine => self
                .cosine
                .as_mut()
                .map_or(self.initial, |c| c.step().base()),
            LrScheduleConfig::Step { every, factor } => {
                let times = (k / every.max(&1)) as i32;
                decayed(self.initial * factor.powi(times))
            }
            LrScheduleConfig::Exponential { gamma } => {
                decayed(self.initial * gamma.powi(k.min(i32::MAX as usize) as i32))
            }
            LrScheduleConfig::Plateau { .. } => self.state.rate.unwrap_or(self.initial),
        }
    }

    /// Feeds a validation value (lower is better); the plateau schedule decays after
    /// `patience` of them in a row without a new best. Returns the new rate when it
    /// decayed. Non-finite values are ignored.
    pub fn observe_validation(&mut self, value: f64) -> Option<f64> {
        let LrScheduleConfig::Plateau { factor, patience } = self.cfg else {
            return None;
        };
        if !value.is_finite() {
            return None;
        }
        if self.state.best.is_none_or(|b| value < b) {
            self.state.best = Some(value);
            self.state.bad = 0;
            return None;
        }
        self.state.bad += 1;
        if self.state.bad < patience {
            return None;
        }
        self.state.bad = 0;
        let rate = self.state.rate.unwrap_or(self.initial);
        let next = (rate * factor).max(self.floor);
        self.state.rate = Some(next);
        (next < rate).then_some(next)
    }

    /// The state to save with a checkpoint.
    pub fn state(&self) -> &LrState {
        &self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rates(s: &mut LrSchedule, n: usize) -> Vec<f64> {
        (0..n).map(|_| s.next_rate()).collect()
    }

    #[test]
    fn step_functions_decay_to_the_floor_and_fast_forward() {
        for cfg in [
            LrScheduleConfig::Constant,
            LrScheduleConfig::Cosine,
            LrScheduleConfig::Step {
                every: 3,
                factor: 0.5,
            },
            LrScheduleConfig::Exponential { gamma: 0.7 },
        ] {
            cfg.validate().unwrap();
            let mut s = LrSchedule::new(&cfg, 1.0, 0.1, 10, 0, LrState::default()).unwrap();
            let all = rates(&mut s, 10);
            assert!(all.windows(2).all(|w| w[1] <= w[0]), "{cfg:?}: {all:?}");
            assert!(all.iter().all(|&r| (0.1..=1.0).contains(&r)), "{cfg:?}");
            // Resumed at step 4: the same rates from there on.
            let mut r = LrSchedule::new(&cfg, 1.0, 0.1, 10, 4, LrState::default()).unwrap();
            assert_eq!(rates(&mut r, 6), all[4..], "{cfg:?}");
            match cfg {
                LrScheduleConfig::Constant => assert!(all.iter().all(|&r| r == 1.0)),
                LrScheduleConfig::Step { .. } => {
                    assert_eq!(all[..4], [1.0, 1.0, 1.0, 0.5]);
                    assert_eq!(all[9], 0.125);
                }
                LrScheduleConfig::Exponential { .. } => {
                    assert!((all[1] - 0.7).abs() < 1e-15);
                    assert_eq!(all[9], 0.1, "held at the floor");
                }
                _ => {}
            }
        }
        // Cosine is burn's, as Multilevel trained with.
        let mut s = LrSchedule::new(
            &LrScheduleConfig::Cosine,
            3e-3,
            3e-5,
            7,
            0,
            LrState::default(),
        )
        .unwrap();
        let mut burn = weft_nn::cosine_annealing(3e-3, 3e-5, 7).unwrap();
        for _ in 0..7 {
            assert_eq!(s.next_rate(), burn.step().base());
        }
    }

    #[test]
    fn plateau_decays_after_patience_respects_the_floor_and_resumes() {
        let cfg = LrScheduleConfig::Plateau {
            factor: 0.5,
            patience: 2,
        };
        cfg.validate().unwrap();
        let mut s = LrSchedule::new(&cfg, 1.0, 0.3, 100, 0, LrState::default()).unwrap();
        assert_eq!(s.next_rate(), 1.0);
        assert_eq!(s.observe_validation(10.0), None); // first: the best
        assert_eq!(s.observe_validation(9.0), None); // better
        assert_eq!(s.observe_validation(9.5), None); // 1 without improvement
        assert_eq!(s.observe_validation(f64::NAN), None); // ignored
        assert_eq!(s.observe_validation(9.0), Some(0.5)); // 2 (equal is no better)
        assert_eq!(s.next_rate(), 0.5);
        // Resume from the saved state: the same decisions.
        let saved = s.state().clone();
        let mut r = LrSchedule::new(&cfg, 1.0, 0.3, 100, 1, saved).unwrap();
        for v in [9.1, 9.2] {
            assert_eq!(s.observe_validation(v), r.observe_validation(v));
        }
        assert_eq!(s.next_rate(), 0.3, "0.25 is below the floor");
        assert_eq!(r.next_rate(), 0.3);
        // At the floor: no further decay is reported.
        assert_eq!(s.observe_validation(9.3), None);
        assert_eq!(s.observe_validation(9.3), None);
        assert_eq!(s.next_rate(), 0.3);
        assert!(LrScheduleConfig::Plateau {
            factor: 1.0,
            patience: 2
        }
        .validate()
        .is_err());
    }

    #[test]
    fn optimizers_parse_from_toml_and_refuse_unknown_keys() {
        #[derive(Debug, Deserialize)]
        struct T {
            optimizer: OptimizerConfig,
        }
        for (text, want) in [
            (
                "[optimizer]\nkind = \"adam\"\nbeta_1 = 0.8\n",
                OptimizerConfig::Adam(AdamParams {
                    beta_1: 0.8,
                    ..AdamParams::default()
                }),
            ),
            (
                "[optimizer]\nkind = \"adamw\"\n",
                OptimizerConfig::AdamW(AdamWParams::default()),
            ),
            (
                "[optimizer]\nkind = \"adamax\"\n",
                OptimizerConfig::default(),
            ),
        ] {
            let t: T = toml::from_str(text).unwrap();
            assert_eq!(t.optimizer, want);
            t.optimizer.validate().unwrap();
            let _ = t.optimizer.init(Some(1.0));
        }
        let e = toml::from_str::<T>("[optimizer]\nkind = \"adam\"\nbeta1 = 0.8\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("beta1"), "{e}");
        let bad = OptimizerConfig::Adam(AdamParams {
            beta_2: 1.0,
            ..AdamParams::default()
        });
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("train.optimizer.beta_2"));
    }
}
