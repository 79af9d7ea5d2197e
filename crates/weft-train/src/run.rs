//! The trainer's side of a run directory: config.toml, checkpoints and resume.
//!
//! The layout, the header (`format_version`, `model_kind`, `preset`) and the `latest`
//! pointer belong to [`weft_models::run`], which every reader uses too; this module adds
//! what only training needs: the optimiser record and the trainer state of each
//! checkpoint, refusing a resume whose configuration differs, and the commit order.
//!
//! The model record is what `Module::save_file` writes, so weft-models' `Predictor`
//! reads it with `Module::try_load_file` without knowing about the rest. Every file is
//! written atomically (temporary file + rename, `weft_mesh::io::write_atomic`), the three
//! files of a checkpoint first and `latest` last: `latest` is the commit point, so a run
//! killed at any instant resumes from a complete checkpoint. Older checkpoints beyond
//! `keep_checkpoints` are deleted only after the new `latest` is written, never the one
//! it names.
//!
//! burnpack stores each parameter with its `ParamId`, and burn's optimizer record keys the
//! optimiser state by the same ids, so model, optimizer state and the learning-rate
//! schedule (whose state is in the trainer state) come back exactly: a resumed run on the
//! CPU continues bit for bit.

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::optim::ModuleOptimizer;
use burn::store::ModuleRecord;
use burn::tensor::Bytes;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use weft_mesh::io::lock::{remove_stale_temps, Access, DirLock, LOCK_FILE};
use weft_mesh::io::write_atomic;
pub use weft_models::run::FORMAT_VERSION;
use weft_models::run::{RunHeader, RunLayout};
use weft_models::ModelKind;

use crate::config::{TrainConfig, TrainTable};
use crate::error::{Result, TrainError};
use crate::optim::LrState;
use crate::sampler::Cursor;
use crate::task::Metrics;

/// Everything besides parameters and optimizer state that a resumed run needs; `S` is
/// the task's stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainerState<S> {
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
    /// The task's stage (`schedule` in checkpoints written before tasks owned it).
    #[serde(alias = "schedule")]
    pub stage: S,
    /// The learning-rate schedule's state (the plateau schedule's rate and patience;
    /// absent in checkpoints written before it existed).
    #[serde(default)]
    pub lr: LrState,
    /// Non-finite steps in a row at the time of the checkpoint.
    pub non_finite_in_a_row: usize,
    /// The last validation metrics (empty before the first, and in checkpoints written
    /// before metrics were named).
    #[serde(default)]
    pub validation: Metrics,
    /// The task's memory ([`crate::task::TrainTask::memory`]; absent when it keeps none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub memory: Option<serde_json::Value>,
}

/// A run directory; see the module documentation.
#[derive(Clone, Debug)]
pub struct RunDir {
    layout: RunLayout,
    header: RunHeader,
    model_toml: toml::Table,
    train: TrainConfig,
    train_toml: toml::Table,
}

/// `value` as a TOML table.
pub fn to_table<T: Serialize>(what: &str, value: &T) -> Result<toml::Table> {
    toml::Table::try_from(value).map_err(|e| TrainError::Write {
        what: what.to_string(),
        source: Box::new(e),
    })
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
    /// The run of model `kind` at `root` for `preset`, model configuration `model` and
    /// training configuration `train` (the loop's and the task's; nothing is written
    /// yet).
    pub fn new<M: Serialize, C: Serialize>(
        root: &Path,
        kind: ModelKind,
        preset: &str,
        model: &M,
        train: &TrainTable<C>,
    ) -> Result<Self> {
        train.trainer.validate()?;
        Ok(RunDir {
            layout: RunLayout::new(root),
            header: RunHeader::new(kind, preset),
            model_toml: to_table("model config", model)?,
            train: train.trainer.clone(),
            train_toml: to_table("train config", train)?,
        })
    }

    /// The directory.
    pub fn root(&self) -> &Path {
        self.layout.root()
    }

    /// Its paths.
    pub fn layout(&self) -> &RunLayout {
        &self.layout
    }

    /// The loop's configuration.
    pub fn train(&self) -> &TrainConfig {
        &self.train
    }

    /// The preset name.
    pub fn preset(&self) -> &str {
        &self.header.preset
    }

    /// `RUN/checkpoints`.
    pub fn checkpoints(&self) -> PathBuf {
        self.layout.checkpoints()
    }

    /// `RUN/config.toml`.
    pub fn config_path(&self) -> PathBuf {
        self.layout.config()
    }

    /// The config.toml text of this run.
    pub fn config_text(&self) -> Result<String> {
        config_text(&self.header, &self.model_toml, &self.train_toml)
    }

    /// Takes the run directory for this process (created if missing): a second `weft
    /// train` into it is refused naming this one, until this one ends however it ends.
    /// Temporary files that an interrupted write left are removed.
    pub fn lock(&self) -> Result<DirLock> {
        let lock = DirLock::acquire(self.root(), LOCK_FILE, Access::Exclusive, "weft train")?;
        remove_stale_temps(self.root(), 1).map_err(|e| TrainError::io(self.root(), e))?;
        Ok(lock)
    }

    /// Starts a fresh run: refuses a directory that already holds a checkpoint, with or
    /// without `latest` (resume it or choose another), writes config.toml.
    pub fn start(&self) -> Result<()> {
        if self.layout.latest().exists() {
            return Err(TrainError::RunDir {
                path: self.root().to_path_buf(),
                message: "already holds a trained run (checkpoints/latest); pass --resume to \
                          continue it or choose another --out directory"
                    .into(),
            });
        }
        let dir = self.checkpoints();
        if dir.is_dir() {
            if let Some(&step) = self.layout.checkpoint_steps()?.last() {
                return Err(TrainError::RunDir {
                    path: self.root().to_path_buf(),
                    message: format!(
                        "holds checkpoints up to step {step} but no checkpoints/latest (an \
                         interrupted run); pass --resume to continue from the newest complete \
                         one, or choose another --out directory; nothing was overwritten"
                    ),
                });
            }
        }
        std::fs::create_dir_all(&dir).map_err(|e| TrainError::io(dir, e))?;
        let text = self.config_text()?;
        write_file(&self.config_path(), text.as_bytes())
    }

    /// Checks that the run on disk is this configuration: config.toml's header (format
    /// version, model kind, preset), `[model]` and `[train]` tables; errors name the
    /// first field that differs. A config.toml written before `model_kind` existed is a
    /// Multilevel run.
    pub fn check_existing(&self) -> Result<()> {
        let (found_header, mut found) = weft_models::run::read_run_config(self.root())?;
        let path = self.config_path();
        // Version, model and preset first: they explain every other difference.
        let show = |v: &dyn std::fmt::Display| v.to_string();
        for (field, f, e) in [
            (
                "model_kind",
                show(&found_header.model),
                show(&self.header.model),
            ),
            (
                "preset",
                format!("{:?}", found_header.preset),
                format!("{:?}", self.header.preset),
            ),
        ] {
            if f != e {
                return Err(TrainError::Mismatch {
                    path,
                    field: field.into(),
                    found: f,
                    expected: e,
                });
            }
        }
        let mut expected = self.tables()?;
        for key in RunHeader::KEYS {
            found.remove(key);
            expected.remove(key);
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

    /// The config.toml of this run as a table.
    fn tables(&self) -> Result<toml::Table> {
        Ok(config_table(
            &self.header,
            &self.model_toml,
            &self.train_toml,
        ))
    }

    /// The file name stem of the checkpoint at `step`.
    pub fn stem(step: usize) -> String {
        RunLayout::stem(step)
    }

    /// Writes the checkpoint of `state.step`: model record, optimizer record, state, then
    /// `latest`.
    pub fn save<M: Module + Clone, S: Serialize>(
        &self,
        model: &M,
        optim: &ModuleOptimizer,
        state: &TrainerState<S>,
    ) -> Result<PathBuf> {
        let dir = self.checkpoints();
        std::fs::create_dir_all(&dir).map_err(|e| TrainError::io(&dir, e))?;
        let stem = Self::stem(state.step);
        let model_path = self.layout.model_record(&stem);
        let bytes = model
            .clone()
            .into_record()
            .into_bytes()
            .map_err(|e| record_err(&model_path, e))?;
        write_file(&model_path, &bytes)?;
        let optim_path = self.layout.optimizer_record(&stem);
        let bytes = optim.into_bytes().map_err(|e| record_err(&optim_path, e))?;
        write_file(&optim_path, &bytes)?;
        let state_path = self.layout.state(&stem);
        let json = serde_json::to_vec_pretty(state).map_err(|e| TrainError::Write {
            what: "trainer state".into(),
            source: Box::new(e),
        })?;
        write_file(&state_path, &json)?;
        write_file(
            &self.layout.latest(),
            RunLayout::latest_text(&stem).as_bytes(),
        )?;
        self.prune(&stem)?;
        Ok(model_path)
    }

    /// Deletes all but the `keep_checkpoints` newest checkpoints (0: keeps every one),
    /// never `latest`'s (`latest` names `kept`, already written).
    fn prune(&self, kept: &str) -> Result<()> {
        let keep = self.train.keep_checkpoints;
        if keep == 0 {
            return Ok(());
        }
        let steps = self.layout.checkpoint_steps()?;
        let old = steps.len().saturating_sub(keep);
        for &step in &steps[..old] {
            let stem = Self::stem(step);
            if stem == kept {
                continue;
            }
            for path in [
                self.layout.state(&stem),
                self.layout.optimizer_record(&stem),
                self.layout.model_record(&stem),
            ] {
                match std::fs::remove_file(&path) {
                    Ok(()) => {}
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                    Err(e) => return Err(TrainError::io(path, e)),
                }
            }
        }
        Ok(())
    }

    /// The stem `latest` names, if any.
    pub fn latest(&self) -> Result<Option<String>> {
        Ok(self.layout.latest_stem()?)
    }

    /// The checkpoint a resume starts from: `latest`'s, or when `latest` is missing (a run
    /// interrupted before its first pointer, or the file lost) the newest checkpoint whose
    /// three files are all there.
    pub fn resume_point(&self) -> Result<Option<String>> {
        if let Some(stem) = self.latest()? {
            return Ok(Some(stem));
        }
        if !self.checkpoints().is_dir() {
            return Ok(None);
        }
        let steps = self.layout.checkpoint_steps()?;
        Ok(steps.iter().rev().map(|&s| Self::stem(s)).find(|stem| {
            [
                self.layout.model_record(stem),
                self.layout.optimizer_record(stem),
                self.layout.state(stem),
            ]
            .iter()
            .all(|p| p.is_file())
        }))
    }

    /// Loads the latest checkpoint into `fresh` (a model of this run's configuration) and
    /// `optim` (a fresh optimiser); checks the state's version, preset and model table.
    pub fn load<M: Module, S: DeserializeOwned>(
        &self,
        fresh: M,
        optim: ModuleOptimizer,
    ) -> Result<(M, ModuleOptimizer, TrainerState<S>)> {
        let stem = self.resume_point()?.ok_or_else(|| TrainError::RunDir {
            path: self.root().to_path_buf(),
            message: "no checkpoint to resume (no checkpoints/latest and no complete \
                      checkpoint); start without --resume"
                .into(),
        })?;
        let state_path = self.layout.state(&stem);
        let state: TrainerState<S> = read_json(&state_path)?;
        if state.format_version != FORMAT_VERSION {
            return Err(TrainError::Mismatch {
                path: state_path,
                field: "format_version".into(),
                found: state.format_version.to_string(),
                expected: FORMAT_VERSION.to_string(),
            });
        }
        if state.preset != self.header.preset {
            return Err(TrainError::Mismatch {
                path: state_path,
                field: "preset".into(),
                found: state.preset.clone(),
                expected: self.header.preset.clone(),
            });
        }
        let model_table =
            weft_config::parse_table(&state.model).map_err(|message| TrainError::Toml {
                path: state_path.clone(),
                message,
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
        let model_path = self.layout.model_record(&stem);
        let model = load_model_record(fresh, read_file(&model_path)?, &model_path)?;
        let optim_path = self.layout.optimizer_record(&stem);
        let optim = load_optimizer_record(optim, read_file(&optim_path)?, &optim_path)?;
        Ok((model, optim, state))
    }

    /// The `[model]` table as TOML text (for [`TrainerState::model`]).
    pub fn model_text(&self) -> Result<String> {
        toml::to_string(&self.model_toml).map_err(|e| TrainError::Write {
            what: "model config".into(),
            source: Box::new(e),
        })
    }
}

/// `fresh` with the parameters of the model record `bytes` (a checkpoint's `.bpk`, read
/// from `path`, which errors name).
pub fn load_model_record<M: Module>(fresh: M, bytes: Vec<u8>, path: &Path) -> Result<M> {
    let record =
        ModuleRecord::from_bytes(Bytes::from_bytes_vec(bytes)).map_err(|e| record_err(path, e))?;
    fresh
        .try_load_record(record)
        .map_err(|e| record_err(path, e))
}

/// `optim` with the state of the optimiser record `bytes` (a checkpoint's `.optim.bpk`,
/// read from `path`, which errors name).
///
/// burn 0.22.1 panics on some damaged optimiser records instead of returning an error (a
/// state tensor without a parameter id, an unsupported rank; found by fuzzing, see
/// docs/fuzzing.md); such a panic is caught here and reported as a damaged record.
pub fn load_optimizer_record(
    optim: ModuleOptimizer,
    bytes: Vec<u8>,
    path: &Path,
) -> Result<ModuleOptimizer> {
    let bytes = Bytes::from_bytes_vec(bytes);
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| optim.from_bytes(bytes)));
    match loaded {
        Ok(r) => r.map_err(|e| record_err(path, e)),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "burn panicked".into());
            Err(record_err(
                path,
                burn::store::RecordError::Validation(format!(
                    "the optimiser record is damaged ({what})"
                )),
            ))
        }
    }
}

fn record_err(path: &Path, source: burn::store::RecordError) -> TrainError {
    TrainError::Record {
        path: path.to_path_buf(),
        source,
    }
}

/// config.toml as a table: the header, `[model]`, `[train]`.
fn config_table(header: &RunHeader, model: &toml::Table, train: &toml::Table) -> toml::Table {
    let mut t = toml::Table::new();
    header.insert_into(&mut t);
    t.insert("model".into(), toml::Value::Table(model.clone()));
    t.insert("train".into(), toml::Value::Table(train.clone()));
    t
}

/// The text of a run's config.toml: the header (format version, model kind, preset),
/// `[model]`, `[train]` (what `weft config show` prints and `weft train --config` reads
/// back).
pub fn config_text(header: &RunHeader, model: &toml::Table, train: &toml::Table) -> Result<String> {
    toml::to_string(&config_table(header, model, train)).map_err(|e| TrainError::Write {
        what: "config.toml".into(),
        source: Box::new(e),
    })
}

/// Writes `value` as pretty JSON to `dir/file` atomically, creating `dir`: the
/// statistics a task fits before the first step (feature normalisers, GarFitNet's factor
/// model), which inference reads beside the checkpoints.
pub fn save_json<T: Serialize>(dir: &Path, file: &str, value: &T) -> Result<()> {
    let path = dir.join(file);
    let text = serde_json::to_string_pretty(value).map_err(|e| TrainError::Write {
        what: format!("{}: {e}", path.display()),
        source: Box::new(e),
    })?;
    std::fs::create_dir_all(dir).map_err(|e| TrainError::io(dir, e))?;
    write_file(&path, text.as_bytes())
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes)).map_err(|e| TrainError::io(path, e))
}

fn read_file(path: &Path) -> Result<Vec<u8>> {
    weft_mesh::io::read_input(path).map_err(|e| TrainError::io(path, e))
}

fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let bytes = read_file(path)?;
    serde_json::from_slice(&bytes).map_err(|source| TrainError::Json {
        path: path.to_path_buf(),
        source,
    })
}
