//! The configuration of a GarFitNet run: the task's settings (`[train]` beside the
//! loop's) and the run type.

use serde::{Deserialize, Serialize};
use weft_models::garfitnet::GarFitConfig;
use weft_models::ModelKind;

use crate::config::TrainConfig;
use crate::error::{Result, TrainError};
use crate::run_config::{ModelSettings, RunConfig, TaskSettings};
use crate::tasks::refine::config::refine_trainer;

/// GarFitNet's task settings, in the `[train]` table beside the loop's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GarFitTraining {
    /// Frames per step, as one disjoint graph; at least 2 (G7: batch normalisation of
    /// the GarFit vector).
    pub frames: usize,
    /// The share of the run's steps that train the coarse regressor before it is frozen
    /// and the refinement trains (G4), in (0, 1).
    pub coarse_fraction: f64,
}

impl Default for GarFitTraining {
    /// The thesis-reference's batch of 8 frames; a third of the steps for the coarse
    /// regressor.
    fn default() -> Self {
        GarFitTraining {
            frames: 8,
            coarse_fraction: 0.3,
        }
    }
}

impl GarFitTraining {
    /// Steps of the coarse stage in a run of `total` steps (at least one, and at least
    /// one left for the refinement when there are two).
    pub fn coarse_steps(&self, total: usize) -> usize {
        let n = (self.coarse_fraction * total as f64).round() as usize;
        n.clamp(1, total.saturating_sub(1).max(1))
    }

    /// Checks every range; errors name the field as in config.toml.
    pub fn validate_values(&self) -> Result<()> {
        if self.frames < 2 {
            return Err(TrainError::config(
                "train.frames",
                self.frames,
                "at least 2 (batch normalisation of the GarFit parameters needs two rows)",
            ));
        }
        if !(self.coarse_fraction > 0.0 && self.coarse_fraction < 1.0) {
            return Err(TrainError::config(
                "train.coarse_fraction",
                self.coarse_fraction,
                "between 0 and 1 (exclusive)",
            ));
        }
        Ok(())
    }
}

impl TaskSettings for GarFitTraining {
    fn preset(name: &str) -> Result<Self> {
        match name {
            "paper" => Ok(GarFitTraining::default()),
            "cpu" => Ok(GarFitTraining {
                frames: 4,
                ..GarFitTraining::default()
            }),
            other => Err(TrainError::config("preset", other, "one of cpu, paper")),
        }
    }

    fn validate(&self) -> Result<()> {
        self.validate_values()
    }
}

impl ModelSettings for GarFitConfig {
    const KIND: ModelKind = ModelKind::GarFitNet;

    fn preset(name: &str) -> Result<Self> {
        Ok(GarFitConfig::preset(name)?)
    }

    fn check(&self) -> std::result::Result<(), String> {
        self.validate().map_err(|e| e.to_string())
    }

    /// G4: Adam 1e-3, plateau 0.75 / 8, floor 5e-7 (`paper`); `cpu` 3e-3.
    fn trainer(name: &str) -> Result<TrainConfig> {
        refine_trainer(name, if name == "cpu" { 3e-3 } else { 1e-3 })
    }
}

/// A GarFitNet run's configuration.
pub type GarFitRun = RunConfig<GarFitConfig, GarFitTraining>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_and_ranges() {
        let cpu = GarFitRun::preset("cpu").unwrap();
        assert_eq!(cpu.train.task.frames, 4);
        assert_eq!(GarFitRun::preset("paper").unwrap().train.task.frames, 8);
        assert_eq!(cpu.train.task.coarse_steps(600), 180);
        assert_eq!(cpu.train.task.coarse_steps(1), 1);
        assert_eq!(cpu.train.task.coarse_steps(2), 1);
        let one = GarFitTraining {
            frames: 1,
            ..GarFitTraining::default()
        };
        assert!(one
            .validate_values()
            .unwrap_err()
            .to_string()
            .contains("train.frames"));
        let all = GarFitTraining {
            coarse_fraction: 1.0,
            ..GarFitTraining::default()
        };
        let e = all.validate_values().unwrap_err().to_string();
        assert!(e.contains("train.coarse_fraction"), "{e}");
        assert!(cpu.to_toml().unwrap().contains("coarse_fraction"));
    }
}
