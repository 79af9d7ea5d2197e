//! The configuration of a refinement run: the task's settings (`[train]` beside the
//! loop's) and the run types of DenseGATs and MultiResGNet.

use serde::{Deserialize, Serialize};
use weft_models::densegats::DenseGatsConfig;
use weft_models::multiresgnet::MultiResGnetConfig;
use weft_models::ModelKind;

use crate::config::TrainConfig;
use crate::error::{Result, TrainError};
use crate::optim::{AdamParams, LrScheduleConfig, OptimizerConfig};
use crate::run_config::{ModelSettings, RunConfig, TaskSettings};

/// A refinement task's settings, in the `[train]` table beside the loop's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RefineTraining {
    /// Vertices per training patch (§3.2.3.2: 1 000; §3.3.3.2: 1 024, the `paper`
    /// preset's for MultiResGNet), or 0: whole meshes (the `cpu` preset's: on a few
    /// characters, a patch's batch statistics describe one limb, and whole meshes
    /// fitted the joints better, docs/characters.md).
    pub patch: usize,
    /// Patches per forward pass, as one disjoint graph (§3.2.3.2's batch of 8). Batch
    /// normalisation then takes its statistics over several body regions of several
    /// poses: over one patch they describe one limb and differ from the running
    /// statistics used on whole meshes at evaluation, which showed as noise on the
    /// vertices LBS gets right.
    pub patches: usize,
    /// Train on at most this many training characters (Table 3.4's 25 / 50 / 75 rows);
    /// 0: all.
    pub characters: usize,
}

impl Default for RefineTraining {
    fn default() -> Self {
        RefineTraining {
            patch: 1000,
            patches: 8,
            characters: 0,
        }
    }
}

impl RefineTraining {
    /// Vertices per patch on a mesh of `n` vertices.
    pub fn patch_size(&self, n: usize) -> usize {
        if self.patch == 0 {
            n
        } else {
            self.patch
        }
    }

    /// Checks every range; errors name the field as in config.toml.
    pub fn validate_values(&self) -> Result<()> {
        if self.patches == 0 {
            return Err(TrainError::config(
                "train.patches",
                self.patches,
                "at least 1",
            ));
        }
        Ok(())
    }
}

impl TaskSettings for RefineTraining {
    fn preset(name: &str) -> Result<Self> {
        match name {
            "paper" => Ok(RefineTraining::default()),
            "cpu" => Ok(RefineTraining {
                patch: 0,
                patches: 1,
                ..RefineTraining::default()
            }),
            other => Err(TrainError::config("preset", other, "one of cpu, paper")),
        }
    }

    fn preset_for(name: &str, model: ModelKind) -> Result<Self> {
        let preset = Self::preset(name)?;
        Ok(match model {
            ModelKind::MultiResGnet if preset.patch != 0 => RefineTraining {
                patch: MultiResGnetConfig::PATCH,
                ..preset
            },
            _ => preset,
        })
    }

    fn validate(&self) -> Result<()> {
        self.validate_values()
    }
}

/// Adam's rate of both `cpu` presets: whole meshes, one pose per step, fitted the tiny
/// set's joints at 3e-3 where 1e-2 on patches had left them at LBS's (docs/characters.md).
const CPU_LEARNING_RATE: f64 = 3e-3;

/// The loop's settings of the thesis (§3.2.3.2): Adam from `learning_rate`, the rate
/// times 0.75 when validation has not improved for 8 measurements, floor 5e-7, batch 8
/// patches. `cpu` validates every 50 steps so the plateau rule acts within a short run.
pub fn refine_trainer(name: &str, learning_rate: f64) -> Result<TrainConfig> {
    let base = TrainConfig::preset(name)?;
    let (steps, validate_every) = if name == "paper" {
        (40_000, 500)
    } else {
        (600, 50)
    };
    Ok(TrainConfig {
        steps,
        learning_rate,
        min_learning_rate: 5e-7,
        optimizer: OptimizerConfig::Adam(AdamParams::default()),
        lr_schedule: LrScheduleConfig::Plateau {
            factor: 0.75,
            patience: 8,
        },
        // One item is already a batch of patches ([`RefineTraining::patches`]).
        batch: 1,
        checkpoint_every: validate_every,
        validate_every,
        ..base
    })
}

impl ModelSettings for DenseGatsConfig {
    const KIND: ModelKind = ModelKind::DenseGats;

    fn preset(name: &str) -> Result<Self> {
        Ok(DenseGatsConfig::preset(name)?)
    }

    fn check(&self) -> std::result::Result<(), String> {
        self.validate().map_err(|e| e.to_string())
    }

    fn trainer(name: &str) -> Result<TrainConfig> {
        refine_trainer(
            name,
            if name == "cpu" {
                CPU_LEARNING_RATE
            } else {
                1e-3
            },
        )
    }
}

/// A DenseGATs run's configuration.
pub type DenseGatsRun = RunConfig<DenseGatsConfig, RefineTraining>;

impl ModelSettings for MultiResGnetConfig {
    const KIND: ModelKind = ModelKind::MultiResGnet;

    fn preset(name: &str) -> Result<Self> {
        Ok(MultiResGnetConfig::preset(name)?)
    }

    fn check(&self) -> std::result::Result<(), String> {
        self.validate().map_err(|e| e.to_string())
    }

    /// §3.3.3.2: Adam from 0.01 (`paper`).
    fn trainer(name: &str) -> Result<TrainConfig> {
        refine_trainer(
            name,
            if name == "cpu" {
                CPU_LEARNING_RATE
            } else {
                1e-2
            },
        )
    }
}

/// A MultiResGNet run's configuration.
pub type MultiResGnetRun = RunConfig<MultiResGnetConfig, RefineTraining>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_follow_each_model_of_the_thesis() {
        // §3.2.3.2: Adam 1e-3, patches of 1 000; §3.3.3.2: Adam 0.01, patches of 1 024.
        let dense = DenseGatsRun::preset("paper").unwrap();
        assert_eq!(dense.train.task.patch, 1000);
        assert_eq!(dense.train.trainer.learning_rate, 1e-3);
        let multires = MultiResGnetRun::preset("paper").unwrap();
        assert_eq!(multires.train.task.patch, 1024);
        assert_eq!(multires.train.trainer.learning_rate, 1e-2);
        assert_eq!(multires.model, MultiResGnetConfig::new());
        // `cpu`: whole meshes, one pose per step, in the skinning frame.
        let cpu = MultiResGnetRun::preset("cpu").unwrap();
        assert_eq!((cpu.train.task.patch, cpu.train.task.patches), (0, 1));
        assert_eq!(cpu.train.task.patch_size(14_606), 14_606);
        assert_eq!(multires.train.task.patch_size(14_606), 1024);
        assert!(cpu.to_toml().unwrap().contains("patch = 0"));
        assert_eq!(cpu.model.frame, weft_models::refine::Frame::Skinning);
        let cpu = DenseGatsRun::preset("cpu").unwrap();
        assert_eq!(cpu.train.trainer.learning_rate, CPU_LEARNING_RATE);
        assert_eq!(cpu.train.task.patch, 0);
        assert!(MultiResGnetRun::preset("huge").is_err());
    }
}
