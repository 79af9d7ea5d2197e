//! The configuration of a Multilevel run: the model (`[model]`), the loop's settings and
//! Multilevel's own training settings (windows, loss weights, the two-step schedule),
//! from a preset overlaid by a config file.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use weft_models::multilevel::MultilevelConfig;
use weft_models::run::RunHeader;
use weft_models::ModelKind;

use super::schedule::ScheduleConfig;
use super::terms::TermWeights;
use crate::config::{TrainConfig, TrainTable};
use crate::error::{Result, TrainError};
use crate::run::RunDir;

/// Multilevel's training settings, in the `[train]` table beside the loop's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MultilevelTraining {
    /// Consecutive frames per training window (the frames of a window share one pair
    /// encoding and form one batch for the network; a window is one training item).
    pub window: usize,
    /// At most this many validation windows per measurement (spread over the split).
    pub validation_windows: usize,
    /// Loss weights of supplement §2.
    pub weights: TermWeights,
    /// The two-step schedule of supplement §4.
    pub schedule: ScheduleConfig,
}

impl Default for MultilevelTraining {
    fn default() -> Self {
        MultilevelTraining {
            window: 8,
            validation_windows: 12,
            weights: TermWeights::cpu(),
            schedule: ScheduleConfig::cpu(),
        }
    }
}

impl MultilevelTraining {
    /// The task side of a preset: `cpu` (the default above: short windows,
    /// [`TermWeights::cpu`], [`ScheduleConfig::cpu`]) or `paper` (windows of 16 frames, so
    /// that the loop's 4 per step make seed 000 supp. §4's batch of 64 frames, the printed
    /// loss weights and switching rules).
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "cpu" => Ok(MultilevelTraining::default()),
            "paper" => Ok(MultilevelTraining {
                window: 16,
                validation_windows: 64,
                weights: TermWeights::default(),
                schedule: ScheduleConfig::default(),
            }),
            other => Err(TrainError::config(
                "preset",
                other,
                &format!("one of {}", crate::config::PRESETS.join(", ")),
            )),
        }
    }

    /// Checks every range; errors name the field as in config.toml.
    pub fn validate(&self) -> Result<()> {
        if self.window == 0 {
            return Err(TrainError::config(
                "train.window",
                self.window,
                "at least 1",
            ));
        }
        self.weights.validate()?;
        self.schedule.validate()
    }
}

/// The configuration of a Multilevel run: preset name, model and training tables.
#[derive(Clone, Debug, PartialEq)]
pub struct MultilevelRun {
    /// The preset the run started from (`cpu` or `paper`).
    pub preset: String,
    /// The model (`[model]`).
    pub model: MultilevelConfig,
    /// The training (`[train]`: the loop's settings and the task's).
    pub train: TrainTable<MultilevelTraining>,
}

impl MultilevelRun {
    /// The preset `name` (model and training sides).
    pub fn preset(name: &str) -> Result<Self> {
        Ok(MultilevelRun {
            preset: name.to_string(),
            model: MultilevelConfig::preset(name)?,
            train: TrainTable {
                trainer: TrainConfig::preset(name)?,
                task: MultilevelTraining::preset(name)?,
            },
        })
    }

    /// A preset with a config file's `[model]` and `[train]` fields laid over it. The
    /// preset is `preset`, else the file's `preset`, else `cpu`. Unknown fields and
    /// values out of range are errors naming the file and the field.
    pub fn resolve(preset: Option<&str>, file: Option<&Path>) -> Result<Self> {
        let table: Option<toml::Table> = match file {
            Some(path) => {
                let text = weft_mesh::io::read_input_to_string(path)
                    .map_err(|e| TrainError::io(path, e))?;
                Some(
                    weft_config::parse_table(&text).map_err(|message| TrainError::Toml {
                        path: path.to_path_buf(),
                        message,
                    })?,
                )
            }
            None => None,
        };
        let from_file = table
            .as_ref()
            .and_then(|t| t.get("preset"))
            .and_then(toml::Value::as_str)
            .map(str::to_string);
        let name = preset
            .map(str::to_string)
            .or_else(|| from_file.clone())
            .unwrap_or_else(|| "cpu".to_string());
        // An unknown preset names where it came from: the flag or the file's key.
        let mut run = Self::preset(&name).map_err(|e| {
            let origin = match (preset, file) {
                (Some(_), _) | (None, None) => "--preset".to_string(),
                (None, Some(path)) => format!("{}: preset", path.display()),
            };
            TrainError::Parse {
                path: PathBuf::from(origin),
                message: e.to_string(),
            }
        })?;
        let Some(table) = table else {
            return Ok(run);
        };
        let path = file.unwrap_or(Path::new("config"));
        let origin = path.display().to_string();
        weft_config::check_keys(
            &table,
            &["format_version", "model_kind", "preset", "model", "train"],
            &origin,
        )?;
        if let Some(v) = table.get("model_kind") {
            if v.as_str() != Some(ModelKind::Multilevel.name()) {
                return Err(TrainError::Mismatch {
                    path: path.to_path_buf(),
                    field: "model_kind".into(),
                    found: v.to_string(),
                    expected: ModelKind::Multilevel.name().into(),
                });
            }
        }
        if let Some(v) = table.get("format_version") {
            if v.as_integer() != Some(crate::run::FORMAT_VERSION) {
                return Err(TrainError::Mismatch {
                    path: path.to_path_buf(),
                    field: "format_version".into(),
                    found: v.to_string(),
                    expected: crate::run::FORMAT_VERSION.to_string(),
                });
            }
        }
        let section = |name: &str| match table.get(name) {
            None => Ok(None),
            Some(toml::Value::Table(t)) => Ok(Some(t)),
            Some(other) => Err(TrainError::Parse {
                path: path.to_path_buf(),
                message: format!(
                    "`{name}` must be a table ([{name}]), found {}",
                    other.type_str()
                ),
            }),
        };
        if let Some(m) = section("model")? {
            run.model = weft_config::overlay(&run.model, m, &origin, "model")?;
            run.model.validate().map_err(|e| TrainError::Parse {
                path: path.to_path_buf(),
                message: format!("[model]: {e}"),
            })?;
        }
        if let Some(t) = section("train")? {
            run.train = weft_config::overlay(&run.train, t, &origin, "train")?;
        }
        // Values out of range name the file they came from.
        let in_file = |e: TrainError| TrainError::Parse {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        run.train.trainer.validate().map_err(in_file)?;
        run.train.task.validate().map_err(in_file)?;
        Ok(run)
    }

    /// The configuration of the run in `dir` (its config.toml).
    pub fn from_run_dir(dir: &Path) -> Result<Self> {
        let path = dir.join("config.toml");
        if !path.exists() {
            return Err(TrainError::RunDir {
                path: dir.to_path_buf(),
                message: "no config.toml: not a training run directory".into(),
            });
        }
        Self::resolve(None, Some(&path))
    }

    /// The run directory `dir` for this configuration.
    pub fn run_dir(&self, dir: &Path) -> Result<RunDir> {
        RunDir::new(
            dir,
            ModelKind::Multilevel,
            &self.preset,
            &self.model,
            &self.train,
        )
    }

    /// The full configuration as config.toml text (every default written out).
    pub fn to_toml(&self) -> Result<String> {
        crate::run::config_text(
            &RunHeader::new(ModelKind::Multilevel, &self.preset),
            &crate::run::to_table("model config", &self.model)?,
            &crate::run::to_table("train config", &self.train)?,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_configs_resolve_from_presets_and_files() {
        let cpu = MultilevelRun::resolve(None, None).unwrap();
        assert_eq!(cpu, MultilevelRun::preset("cpu").unwrap());
        // What `weft config show` prints reads back to the same configuration.
        let dir = std::env::temp_dir().join(format!("weft-train-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("paper.toml");
        let paper = MultilevelRun::preset("paper").unwrap();
        std::fs::write(&path, paper.to_toml().unwrap()).unwrap();
        assert_eq!(MultilevelRun::resolve(None, Some(&path)).unwrap(), paper);
        // A partial file over a preset.
        std::fs::write(&path, "[train]\nsteps = 9\n[model]\nmp_channels = 4\n").unwrap();
        let r = MultilevelRun::resolve(Some("cpu"), Some(&path)).unwrap();
        assert_eq!((r.train.trainer.steps, r.model.mp_channels), (9, 4));
        assert_eq!(r.model.gg_widths, MultilevelConfig::cpu().gg_widths);
        // Unknown or out-of-range fields are named.
        std::fs::write(&path, "[train]\nstepz = 9\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(e.contains("stepz"), "{e}");
        // The typo the platform issue found silently dropped: refused, dotted and with
        // the file, though MultilevelConfig (burn's Config derive) does not deny unknown
        // fields itself.
        std::fs::write(&path, "[model]\nmp_chanels = 4\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("model.mp_chanels") && e.contains("paper.toml"),
            "{e}"
        );
        // Switching the optimiser replaces its table: Adamax's fields do not leak in.
        std::fs::write(&path, "[train.optimizer]\nkind = \"adam\"\n").unwrap();
        let r = MultilevelRun::resolve(None, Some(&path)).unwrap();
        assert!(
            matches!(
                r.train.trainer.optimizer,
                crate::optim::OptimizerConfig::Adam(_)
            ),
            "{:?}",
            r.train.trainer.optimizer
        );
        std::fs::write(&path, "[train]\nwindow = 0\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(e.contains("train.window"), "{e}");
        std::fs::write(&path, "format_version = 7\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(e.contains("format_version"), "{e}");
        assert!(MultilevelRun::resolve(Some("huge"), None).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn task_fields_share_the_train_table() {
        let dir = std::env::temp_dir().join(format!("weft-train-task-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("partial.toml");
        std::fs::write(&path, "[train]\nsteps = 7\n[train.weights]\nvertex = 2.0\n").unwrap();
        let r = MultilevelRun::resolve(None, Some(&path)).unwrap();
        assert_eq!(r.train.trainer.steps, 7);
        assert_eq!(r.train.task.weights.vertex, 2.0);
        assert_eq!(r.train.task.weights.edge, 15.0);
        std::fs::write(&path, "[train.weights]\nvertexx = 2.0\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(e.contains("train.weights.vertexx"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
