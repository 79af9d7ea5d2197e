//! The training loop's configuration, the same for every system, with every default
//! written here and printed by `weft config show`; and [`TrainTable`], the `[train]` table
//! of a run's config.toml, which holds it beside the task's own settings.

use serde::{Deserialize, Serialize};

use crate::error::{Result, TrainError};
use crate::optim::{LrScheduleConfig, OptimizerConfig};

/// The loop's hyper-parameters; [`TrainConfig::preset`] gives the `cpu` and `paper` ones.
///
/// It does not refuse unknown fields itself: it shares the `[train]` table with the
/// task's settings ([`TrainTable`]), and unknown keys are refused on the whole table by
/// `weft_config::overlay`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrainConfig {
    /// Seeds parameter initialisation and the order of the training windows.
    pub seed: u64,
    /// Optimiser steps of the whole run.
    pub steps: usize,
    /// Initial learning rate (seed 000 supp. §4: 3e-3).
    pub learning_rate: f64,
    /// The floor of the learning rate: where cosine annealing ends, and below which no
    /// decaying schedule goes.
    pub min_learning_rate: f64,
    /// The optimiser (seed 000 supp. §4: Adamax).
    pub optimizer: OptimizerConfig,
    /// How the learning rate moves (seed 000 supp. §4: cosine annealing).
    pub lr_schedule: LrScheduleConfig,
    /// Keep this many newest checkpoints (the one `latest` names always stays); 0: keep
    /// every checkpoint.
    pub keep_checkpoints: usize,
    /// Training items per optimiser step (their losses are averaged).
    pub batch: usize,
    /// Write a checkpoint every this many steps (and always at the end).
    pub checkpoint_every: usize,
    /// Measure the validation error every this many steps (and at the end); 0: never.
    pub validate_every: usize,
    /// Stop when this many steps in a row had a non-finite loss.
    pub max_non_finite: usize,
    /// Clip gradients to this global L2 norm (none: no clipping; the paper names none).
    pub grad_clip_norm: Option<f64>,
}

impl Default for TrainConfig {
    fn default() -> Self {
        TrainConfig {
            seed: 0,
            steps: 10_000,
            learning_rate: 3e-3,
            min_learning_rate: 3e-5,
            optimizer: OptimizerConfig::default(),
            lr_schedule: LrScheduleConfig::default(),
            keep_checkpoints: 3,
            batch: 1,
            checkpoint_every: 1000,
            validate_every: 1000,
            max_non_finite: 20,
            grad_clip_norm: None,
        }
    }
}

/// The preset names [`TrainConfig::preset`] knows.
pub const PRESETS: [&str; 2] = ["cpu", "paper"];

impl TrainConfig {
    /// The loop side of a preset: `cpu` (the default above: one item per step, sized to
    /// train the tiny dataset in minutes on two cores: 10 000 steps of Multilevel's
    /// 2-frame windows, docs/multilevel.md "Short windows, more steps") or `paper` (4
    /// items per step, seed 000 supp. §4, and a longer run).
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "cpu" => Ok(TrainConfig::default()),
            "paper" => Ok(TrainConfig {
                steps: 20_000,
                batch: 4,
                checkpoint_every: 1000,
                validate_every: 1000,
                ..TrainConfig::default()
            }),
            other => Err(TrainError::config(
                "preset",
                other,
                &format!("one of {}", PRESETS.join(", ")),
            )),
        }
    }

    /// Checks every range; errors name the field as in config.toml.
    pub fn validate(&self) -> Result<()> {
        for (field, v) in [
            ("train.steps", self.steps),
            ("train.batch", self.batch),
            ("train.checkpoint_every", self.checkpoint_every),
            ("train.max_non_finite", self.max_non_finite),
        ] {
            if v == 0 {
                return Err(TrainError::config(field, v, "at least 1"));
            }
        }
        if !(self.learning_rate.is_finite() && self.learning_rate > 0.0) {
            return Err(TrainError::config(
                "train.learning_rate",
                self.learning_rate,
                "a finite rate > 0",
            ));
        }
        if !(self.min_learning_rate.is_finite()
            && self.min_learning_rate >= 0.0
            && self.min_learning_rate <= self.learning_rate)
        {
            return Err(TrainError::config(
                "train.min_learning_rate",
                self.min_learning_rate,
                "a finite rate in [0, learning_rate]",
            ));
        }
        if let Some(c) = self.grad_clip_norm {
            if !(c.is_finite() && c > 0.0) {
                return Err(TrainError::config(
                    "train.grad_clip_norm",
                    c,
                    "a finite norm > 0",
                ));
            }
        }
        self.optimizer.validate()?;
        self.lr_schedule.validate()
    }
}

/// The `[train]` table of a run: the loop's settings and the task's own (`C`, e.g.
/// Multilevel's windows, loss weights and schedule) side by side, as one flat table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainTable<C> {
    /// The loop's settings.
    #[serde(flatten)]
    pub trainer: TrainConfig,
    /// The task's settings.
    #[serde(flatten)]
    pub task: C,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_round_trip_through_toml() {
        for name in PRESETS {
            let c = TrainConfig::preset(name).unwrap();
            c.validate().unwrap();
            let text = toml::to_string(&c).unwrap();
            let back: TrainConfig = toml::from_str(&text).unwrap();
            assert_eq!(back, c);
        }
        assert!(TrainConfig::preset("gpu").is_err());
        // Missing fields take their defaults (unknown ones are refused on the whole
        // `[train]` table: tasks::multilevel's config tests).
        let partial: TrainConfig = toml::from_str("steps = 7\n").unwrap();
        assert_eq!(partial.steps, 7);
        assert_eq!(partial.batch, TrainConfig::default().batch);
        let e = toml::from_str::<TrainConfig>("[optimizer]\nkind = \"adam\"\nbeta_3 = 0.5\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("beta_3"), "{e}");
        let adam: TrainConfig =
            toml::from_str("[optimizer]\nkind = \"adam\"\n[lr_schedule]\nkind = \"plateau\"\nfactor = 0.5\npatience = 3\n")
                .unwrap();
        adam.validate().unwrap();
        assert_eq!(
            adam.lr_schedule,
            LrScheduleConfig::Plateau {
                factor: 0.5,
                patience: 3
            }
        );
        let bad = TrainConfig {
            min_learning_rate: 1.0,
            ..TrainConfig::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("train.min_learning_rate"));
    }
}
