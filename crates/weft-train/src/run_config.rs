//! A run's configuration, whatever the model: the preset name, the model's table
//! (`[model]`) and the training table (`[train]`: the loop's settings beside the task's),
//! from a preset overlaid by a config file. A system supplies its model and task
//! settings through [`ModelSettings`] and [`TaskSettings`].

use std::path::{Path, PathBuf};

use serde::{de::DeserializeOwned, Serialize};
use weft_models::run::RunHeader;
use weft_models::ModelKind;

use crate::config::{TrainConfig, TrainTable};
use crate::error::{Result, TrainError};
use crate::run::RunDir;

/// A model's configuration as a run holds it in `[model]`.
pub trait ModelSettings:
    Clone + PartialEq + std::fmt::Debug + Serialize + DeserializeOwned
{
    /// The model kind the run trains.
    const KIND: ModelKind;
    /// The preset `name` (`cpu` or `paper`).
    fn preset(name: &str) -> Result<Self>;
    /// Checks the values; the message names the field.
    fn check(&self) -> std::result::Result<(), String>;
    /// The loop's settings of the preset `name` for this model (default: the shared
    /// [`TrainConfig::preset`]).
    fn trainer(name: &str) -> Result<TrainConfig> {
        TrainConfig::preset(name)
    }
}

/// A task's settings as a run holds them in `[train]`, beside the loop's.
pub trait TaskSettings: Clone + PartialEq + std::fmt::Debug + Serialize + DeserializeOwned {
    /// The preset `name` (`cpu` or `paper`).
    fn preset(name: &str) -> Result<Self>;
    /// The preset `name` for training `model`, for a task several models share with
    /// different settings (default: [`TaskSettings::preset`]).
    fn preset_for(name: &str, model: ModelKind) -> Result<Self> {
        let _ = model;
        Self::preset(name)
    }
    /// Checks the values; errors name the field as in config.toml.
    fn validate(&self) -> Result<()>;
}

/// A run's configuration: preset name, model and training tables.
#[derive(Clone, Debug, PartialEq)]
pub struct RunConfig<M, T> {
    /// The preset the run started from (`cpu` or `paper`).
    pub preset: String,
    /// The model (`[model]`).
    pub model: M,
    /// The training (`[train]`: the loop's settings and the task's).
    pub train: TrainTable<T>,
}

impl<M: ModelSettings, T: TaskSettings> RunConfig<M, T> {
    /// The preset `name` (model and training sides).
    pub fn preset(name: &str) -> Result<Self> {
        Ok(RunConfig {
            preset: name.to_string(),
            model: M::preset(name)?,
            train: TrainTable {
                trainer: M::trainer(name)?,
                task: T::preset_for(name, M::KIND)?,
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
            if v.as_str() != Some(M::KIND.name()) {
                return Err(TrainError::Mismatch {
                    path: path.to_path_buf(),
                    field: "model_kind".into(),
                    found: v.to_string(),
                    expected: M::KIND.name().into(),
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
            run.model.check().map_err(|e| TrainError::Parse {
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
        RunDir::new(dir, M::KIND, &self.preset, &self.model, &self.train)
    }

    /// The full configuration as config.toml text (every default written out).
    pub fn to_toml(&self) -> Result<String> {
        crate::run::config_text(
            &RunHeader::new(M::KIND, &self.preset),
            &crate::run::to_table("model config", &self.model)?,
            &crate::run::to_table("train config", &self.train)?,
        )
    }
}
