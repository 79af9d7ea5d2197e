//! The run directory and its checkpoints.
//!
//! ```text
//! RUN/config.toml                      format_version, preset, [model], [train]
//! RUN/checkpoints/step-000250.bpk      model parameters (burn module record, burnpack)
//! RUN/checkpoints/step-000250.optim.bpk  Adamax state (burn optimizer record, burnpack)
//! RUN/checkpoints/step-000250.state.json step, data cursor, schedule, config fingerprint
//! RUN/checkpoints/latest               text: the file name of the newest model record
//! RUN/metrics.jsonl, RUN/curves.png    see crate::metrics
//! ```
//!
//! The model record is what `Module::save_file` writes, so weft-models' `Predictor`
//! reads it with `Module::try_load_file` without knowing about the rest. Every file is
//! written atomically (temporary file + rename, `weft_mesh::io::write_atomic`), the three
//! files of a checkpoint first and `latest` last: `latest` is the commit point, so a run
//! killed at any instant resumes from a complete checkpoint.
//!
//! burnpack stores each parameter with its `ParamId`, and burn's optimizer record keys the
//! Adamax state by the same ids, so model, optimizer state and the cosine schedule
//! (a pure function of the step) come back exactly: a resumed run on the CPU continues
//! bit for bit.

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::optim::ModuleOptimizer;
use burn::store::ModuleRecord;
use burn::tensor::Bytes;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use weft_mesh::io::write_atomic;

use crate::config::TrainConfig;
use crate::error::{Result, TrainError};
use crate::sampler::Cursor;
use crate::schedule::ScheduleState;

/// Version of the run directory format this crate writes (weft-models reads the same).
pub const FORMAT_VERSION: i64 = 1;

/// Everything besides parameters and optimizer state that a resumed run needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainerState {
    /// [`FORMAT_VERSION`] of the writer.
    pub format_version: i64,
    /// The preset of the run.
    pub preset: String,
    /// The `[model]` table of the run, as TOML text (to refuse a checkpoint of another
    /// model configuration by name).
    pub model: String,
    /// Optimiser steps taken.
    pub step: usize,
    /// The data cursor.
    pub cursor: Cursor,
    /// The two-step schedule.
    pub schedule: ScheduleState,
    /// Non-finite steps in a row at the time of the checkpoint.
    pub non_finite_in_a_row: usize,
    /// The last validation error, mm.
    pub validation_mm: Option<f64>,
}

/// A run directory; see the module documentation.
#[derive(Clone, Debug)]
pub struct RunDir {
    root: PathBuf,
    preset: String,
    model_toml: toml::Table,
    train: TrainConfig,
}

/// `value` as a TOML table.
pub fn to_table<T: Serialize>(what: &str, value: &T) -> Result<toml::Table> {
    toml::Table::try_from(value)
        .map_err(|e| TrainError::Model(format!("{what} as a TOML table: {e}")))
}

/// The first key (dotted path) where two tables differ, with both values.
fn first_difference(
    prefix: &str,
    a: &toml::Table,
    b: &toml::Table,
) -> Option<(String, String, String)> {
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    for k in keys {
        let path = format!("{prefix}{k}");
        match (a.get(k), b.get(k)) {
            (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) => {
                if let Some(d) = first_difference(&format!("{path}."), x, y) {
                    return Some(d);
                }
            }
            (x, y) if x != y => {
                let show =
                    |v: Option<&toml::Value>| v.map_or("absent".to_string(), ToString::to_string);
                return Some((path, show(x), show(y)));
            }
            _ => {}
        }
    }
    None
}

impl RunDir {
    /// The run at `root` for `preset`, model configuration `model` and training
    /// configuration `train` (nothing is written yet).
    pub fn new<M: Serialize>(
        root: &Path,
        preset: &str,
        model: &M,
        train: &TrainConfig,
    ) -> Result<Self> {
        train.validate()?;
        Ok(RunDir {
            root: root.to_path_buf(),
            preset: preset.to_string(),
            model_toml: to_table("model config", model)?,
            train: train.clone(),
        })
    }

    /// The directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The training configuration.
    pub fn train(&self) -> &TrainConfig {
        &self.train
    }

    /// The preset name.
    pub fn preset(&self) -> &str {
        &self.preset
    }

    /// `RUN/checkpoints`.
    pub fn checkpoints(&self) -> PathBuf {
        self.root.join("checkpoints")
    }

    /// `RUN/config.toml`.
    pub fn config_path(&self) -> PathBuf {
        self.root.join("config.toml")
    }

    /// The config.toml text of this run.
    pub fn config_text(&self) -> Result<String> {
        let mut t = toml::Table::new();
        t.insert(
            "format_version".into(),
            toml::Value::Integer(FORMAT_VERSION),
        );
        t.insert("preset".into(), toml::Value::String(self.preset.clone()));
        t.insert("model".into(), toml::Value::Table(self.model_toml.clone()));
        t.insert(
            "train".into(),
            toml::Value::Table(to_table("train config", &self.train)?),
        );
        toml::to_string(&t).map_err(|e| TrainError::Model(format!("config.toml: {e}")))
    }

    /// Starts a fresh run: refuses a directory that already holds a checkpoint (resume it
    /// or choose another), writes config.toml.
    pub fn start(&self) -> Result<()> {
        if self.checkpoints().join("latest").exists() {
            return Err(TrainError::RunDir {
                path: self.root.clone(),
                message: "already holds a trained run (checkpoints/latest); pass --resume to \
                          continue it or choose another --out directory"
                    .into(),
            });
        }
        std::fs::create_dir_all(self.checkpoints())
            .map_err(|e| TrainError::io(self.checkpoints(), e))?;
        let text = self.config_text()?;
        let path = self.config_path();
        write_atomic(&path, |w| w.write_all(text.as_bytes())).map_err(|e| TrainError::io(path, e))
    }

    /// Checks that the run on disk is this configuration: config.toml's format version,
    /// preset, `[model]` and `[train]` tables; errors name the first field that differs.
    pub fn check_existing(&self) -> Result<()> {
        let path = self.config_path();
        let text = std::fs::read_to_string(&path).map_err(|e| TrainError::io(&path, e))?;
        let found: toml::Table = toml::from_str(&text).map_err(|e| TrainError::Parse {
            path: path.clone(),
            message: e.to_string(),
        })?;
        let expected: toml::Table = toml::from_str(&self.config_text()?)
            .map_err(|e| TrainError::Model(format!("config.toml: {e}")))?;
        // Version and preset first: they explain every other difference.
        for key in ["format_version", "preset"] {
            if found.get(key) != expected.get(key) {
                return Err(self.mismatch(&path, key, found.get(key), expected.get(key)));
            }
        }
        if let Some((field, f, e)) = first_difference("", &found, &expected) {
            return Err(TrainError::Mismatch {
                path,
                field,
                found: f,
                expected: e,
            });
        }
        Ok(())
    }

    fn mismatch(
        &self,
        path: &Path,
        field: &str,
        found: Option<&toml::Value>,
        expected: Option<&toml::Value>,
    ) -> TrainError {
        let show = |v: Option<&toml::Value>| v.map_or("absent".to_string(), ToString::to_string);
        TrainError::Mismatch {
            path: path.to_path_buf(),
            field: field.into(),
            found: show(found),
            expected: show(expected),
        }
    }

    /// The file name stem of the checkpoint at `step`.
    pub fn stem(step: usize) -> String {
        format!("step-{step:06}")
    }

    /// Writes the checkpoint of `state.step`: model record, optimizer record, state, then
    /// `latest`.
    pub fn save<M: Module + Clone>(
        &self,
        model: &M,
        optim: &ModuleOptimizer,
        state: &TrainerState,
    ) -> Result<PathBuf> {
        let dir = self.checkpoints();
        std::fs::create_dir_all(&dir).map_err(|e| TrainError::io(&dir, e))?;
        let stem = Self::stem(state.step);
        let record_err = |path: &Path, e: burn::store::RecordError| TrainError::Record {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let model_path = dir.join(format!("{stem}.bpk"));
        let bytes = model
            .clone()
            .into_record()
            .into_bytes()
            .map_err(|e| record_err(&model_path, e))?;
        write_file(&model_path, &bytes)?;
        let optim_path = dir.join(format!("{stem}.optim.bpk"));
        let bytes = optim.into_bytes().map_err(|e| record_err(&optim_path, e))?;
        write_file(&optim_path, &bytes)?;
        let state_path = dir.join(format!("{stem}.state.json"));
        let json = serde_json::to_vec_pretty(state)
            .map_err(|e| TrainError::Model(format!("trainer state: {e}")))?;
        write_file(&state_path, &json)?;
        write_file(&dir.join("latest"), format!("{stem}.bpk\n").as_bytes())?;
        Ok(model_path)
    }

    /// The stem `latest` names, if any.
    pub fn latest(&self) -> Result<Option<String>> {
        let path = self.checkpoints().join("latest");
        match std::fs::read_to_string(&path) {
            Ok(text) => {
                let name = text.trim();
                let stem = name.strip_suffix(".bpk").filter(|s| {
                    s.starts_with("step-") && !s.contains(['/', '\\']) && !s.contains(".optim")
                });
                stem.map(|s| Some(s.to_string()))
                    .ok_or_else(|| TrainError::Parse {
                        path,
                        message: format!("expected a name like step-000100.bpk, found {name:?}"),
                    })
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(TrainError::io(path, e)),
        }
    }

    /// Loads the latest checkpoint into `fresh` (a model of this run's configuration) and
    /// `optim` (a fresh optimiser); checks the state's version, preset and model table.
    pub fn load<M: Module>(
        &self,
        fresh: M,
        optim: ModuleOptimizer,
    ) -> Result<(M, ModuleOptimizer, TrainerState)> {
        let stem = self.latest()?.ok_or_else(|| TrainError::RunDir {
            path: self.root.clone(),
            message:
                "no checkpoint to resume (checkpoints/latest is missing); start without --resume"
                    .into(),
        })?;
        let dir = self.checkpoints();
        let state_path = dir.join(format!("{stem}.state.json"));
        let state: TrainerState = read_json(&state_path)?;
        if state.format_version != FORMAT_VERSION {
            return Err(TrainError::Mismatch {
                path: state_path,
                field: "format_version".into(),
                found: state.format_version.to_string(),
                expected: FORMAT_VERSION.to_string(),
            });
        }
        if state.preset != self.preset {
            return Err(TrainError::Mismatch {
                path: state_path,
                field: "preset".into(),
                found: state.preset.clone(),
                expected: self.preset.clone(),
            });
        }
        let model_table: toml::Table =
            toml::from_str(&state.model).map_err(|e| TrainError::Parse {
                path: state_path.clone(),
                message: format!("model: {e}"),
            })?;
        if let Some((field, found, expected)) =
            first_difference("model.", &model_table, &self.model_toml)
        {
            return Err(TrainError::Mismatch {
                path: state_path,
                field,
                found,
                expected,
            });
        }
        let model_path = dir.join(format!("{stem}.bpk"));
        let record_err = |path: &Path, e: burn::store::RecordError| TrainError::Record {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let record = ModuleRecord::from_bytes(Bytes::from_bytes_vec(read_file(&model_path)?))
            .map_err(|e| record_err(&model_path, e))?;
        let model = fresh
            .try_load_record(record)
            .map_err(|e| record_err(&model_path, e))?;
        let optim_path = dir.join(format!("{stem}.optim.bpk"));
        let optim = optim
            .from_bytes(Bytes::from_bytes_vec(read_file(&optim_path)?))
            .map_err(|e| record_err(&optim_path, e))?;
        Ok((model, optim, state))
    }

    /// The `[model]` table as TOML text (for [`TrainerState::model`]).
    pub fn model_text(&self) -> Result<String> {
        toml::to_string(&self.model_toml)
            .map_err(|e| TrainError::Model(format!("model config: {e}")))
    }
}

/// The text of a run's config.toml: format version, preset, `[model]`, `[train]` (what
/// `weft config show` prints and `weft train --config` reads back).
pub fn config_text(preset: &str, model: &toml::Table, train: &TrainConfig) -> Result<String> {
    let mut t = toml::Table::new();
    t.insert(
        "format_version".into(),
        toml::Value::Integer(FORMAT_VERSION),
    );
    t.insert("preset".into(), toml::Value::String(preset.to_string()));
    t.insert("model".into(), toml::Value::Table(model.clone()));
    t.insert(
        "train".into(),
        toml::Value::Table(to_table("train config", train)?),
    );
    toml::to_string(&t).map_err(|e| TrainError::Model(format!("config.toml: {e}")))
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes)).map_err(|e| TrainError::io(path, e))
}

fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| TrainError::io(path, e))
}

fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let bytes = read_file(path)?;
    serde_json::from_slice(&bytes).map_err(|e| TrainError::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}
