//! The run directory: its layout, its header and its `latest` pointer, owned here so that
//! the trainer that writes a run and every reader (inference, evaluation, the CLI) agree
//! on one format version and one parser.
//!
//! ```text
//! RUN/config.toml                         format_version, model_kind, preset, [model], [train]
//! RUN/checkpoints/step-000250.bpk         model parameters (burn module record, burnpack)
//! RUN/checkpoints/step-000250.optim.bpk   optimiser state (burn optimizer record)
//! RUN/checkpoints/step-000250.state.json  the trainer's state (step, data cursor, stage, ...)
//! RUN/checkpoints/latest                  text: the file name of the newest model record
//! RUN/metrics.jsonl, RUN/curves.png       the training log and its plot
//! ```
//!
//! `latest` is the commit point of a checkpoint: it is written last, so a reader that
//! follows it always finds a complete checkpoint. A config.toml without `model_kind` was
//! written before the key existed, when Multilevel was the only model: it reads as
//! [`ModelKind::Multilevel`].

use std::path::{Path, PathBuf};

use crate::error::ModelError;
use crate::kind::ModelKind;

/// Version of the run directory format (written by weft-train, read by everyone).
pub const FORMAT_VERSION: i64 = 1;

/// The top-level keys of a run's config.toml: which format, which model, which preset.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunHeader {
    /// [`FORMAT_VERSION`] of the writer.
    pub format_version: i64,
    /// The model the run trains (key `model_kind`; `[model]` is that model's table).
    pub model: ModelKind,
    /// The preset the run's configuration started from.
    pub preset: String,
}

impl RunHeader {
    /// The keys the header occupies at the top of config.toml (a config file may hold
    /// them besides its tables).
    pub const KEYS: [&'static str; 3] = ["format_version", "model_kind", "preset"];

    /// The header of a run of `model` from `preset`, in this build's format.
    pub fn new(model: ModelKind, preset: &str) -> Self {
        RunHeader {
            format_version: FORMAT_VERSION,
            model,
            preset: preset.to_string(),
        }
    }

    /// Reads the header keys of `table` (the config.toml at `path`, named in errors).
    /// Refuses another format version; a table without `model_kind` is Multilevel.
    pub fn from_table(table: &toml::Table, path: &Path) -> Result<Self, ModelError> {
        let format_version = match table.get("format_version") {
            Some(toml::Value::Integer(FORMAT_VERSION)) => FORMAT_VERSION,
            Some(v) => {
                return Err(run_err(
                    path,
                    format!("format_version {v}; this build reads version {FORMAT_VERSION}"),
                ))
            }
            None => {
                return Err(run_err(
                    path,
                    format!("no integer format_version (expected {FORMAT_VERSION})"),
                ))
            }
        };
        let model = match table.get("model_kind") {
            None => ModelKind::Multilevel,
            Some(toml::Value::String(name)) => {
                name.parse().map_err(|source| ModelError::RunKind {
                    path: path.to_path_buf(),
                    source,
                })?
            }
            Some(v) => {
                return Err(run_err(
                    path,
                    format!("model_kind = {v}: expected a model name in quotes"),
                ))
            }
        };
        let preset = match table.get("preset") {
            Some(toml::Value::String(p)) => p.clone(),
            _ => return Err(run_err(path, "no preset = \"...\" line")),
        };
        Ok(RunHeader {
            format_version,
            model,
            preset,
        })
    }

    /// Writes the header keys into `table` (config.toml's top level).
    pub fn insert_into(&self, table: &mut toml::Table) {
        table.insert(
            "format_version".into(),
            toml::Value::Integer(self.format_version),
        );
        table.insert(
            "model_kind".into(),
            toml::Value::String(self.model.name().into()),
        );
        table.insert("preset".into(), toml::Value::String(self.preset.clone()));
    }
}

/// The paths of a run directory; nothing is read or written by building one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunLayout {
    root: PathBuf,
}

impl RunLayout {
    /// The layout of the run at `root`.
    pub fn new(root: impl Into<PathBuf>) -> Self {
        RunLayout { root: root.into() }
    }

    /// The run directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// `RUN/config.toml`.
    pub fn config(&self) -> PathBuf {
        self.root.join("config.toml")
    }

    /// `RUN/checkpoints`.
    pub fn checkpoints(&self) -> PathBuf {
        self.root.join("checkpoints")
    }

    /// `RUN/checkpoints/latest`.
    pub fn latest(&self) -> PathBuf {
        self.checkpoints().join("latest")
    }

    /// `RUN/metrics.jsonl`.
    pub fn metrics(&self) -> PathBuf {
        self.root.join("metrics.jsonl")
    }

    /// `RUN/curves.png`.
    pub fn curves(&self) -> PathBuf {
        self.root.join("curves.png")
    }

    /// The file stem of the checkpoint at `step` (`step-000250`).
    pub fn stem(step: usize) -> String {
        format!("step-{step:06}")
    }

    /// The model record of checkpoint `stem`.
    pub fn model_record(&self, stem: &str) -> PathBuf {
        self.checkpoints().join(format!("{stem}.bpk"))
    }

    /// The optimiser record of checkpoint `stem`.
    pub fn optimizer_record(&self, stem: &str) -> PathBuf {
        self.checkpoints().join(format!("{stem}.optim.bpk"))
    }

    /// The trainer state of checkpoint `stem`.
    pub fn state(&self, stem: &str) -> PathBuf {
        self.checkpoints().join(format!("{stem}.state.json"))
    }

    /// The text `latest` holds for checkpoint `stem`.
    pub fn latest_text(stem: &str) -> String {
        format!("{stem}.bpk\n")
    }

    /// The stem `latest` names; none when there is no `latest` (no checkpoint yet).
    pub fn latest_stem(&self) -> Result<Option<String>, ModelError> {
        let path = self.latest();
        let text = match weft_mesh::io::read_input_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(ModelError::RunRead { path, source }),
        };
        let name = text.trim();
        match name.strip_suffix(".bpk").filter(|s| is_stem(s)) {
            Some(stem) => Ok(Some(stem.to_string())),
            None => Err(run_err(
                &path,
                format!("expected a name like step-000100.bpk, found {name:?}"),
            )),
        }
    }

    /// The steps of the checkpoints whose model record is in `checkpoints/`, ascending.
    pub fn checkpoint_steps(&self) -> Result<Vec<usize>, ModelError> {
        let dir = self.checkpoints();
        let entries = std::fs::read_dir(&dir).map_err(|source| ModelError::RunRead {
            path: dir.clone(),
            source,
        })?;
        let mut steps = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|source| ModelError::RunRead {
                path: dir.clone(),
                source,
            })?;
            let name = entry.file_name();
            let step = name
                .to_str()
                .and_then(|n| n.strip_suffix(".bpk"))
                .filter(|s| is_stem(s))
                .and_then(|s| s["step-".len()..].parse::<usize>().ok());
            steps.extend(step);
        }
        steps.sort_unstable();
        Ok(steps)
    }
}

/// Whether `s` is a checkpoint stem (`step-` and digits).
fn is_stem(s: &str) -> bool {
    s.strip_prefix("step-")
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

fn run_err(path: &Path, message: impl Into<String>) -> ModelError {
    ModelError::Run {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Reads `RUN/config.toml`: its header (the format version checked) and the whole table
/// (the model's and the trainer's tables included, for their owners to parse).
pub fn read_run_config(run_dir: &Path) -> Result<(RunHeader, toml::Table), ModelError> {
    let path = RunLayout::new(run_dir).config();
    let text =
        weft_mesh::io::read_input_to_string(&path).map_err(|source| ModelError::RunRead {
            path: path.clone(),
            source,
        })?;
    let table = weft_config::parse_table(&text).map_err(|message| ModelError::RunToml {
        path: path.clone(),
        message,
    })?;
    let header = RunHeader::from_table(&table, &path)?;
    Ok((header, table))
}

/// The header and `[model]` table of the run in `run_dir`, which must be a run of
/// `kind`; errors name its config.toml.
pub fn model_table(
    run_dir: &Path,
    kind: ModelKind,
) -> Result<(RunHeader, toml::Table), ModelError> {
    let (header, mut table) = read_run_config(run_dir)?;
    let path = RunLayout::new(run_dir).config();
    if header.model != kind {
        return Err(run_err(
            &path,
            format!("a run of model `{}`, not {kind}", header.model),
        ));
    }
    match table.remove("model") {
        Some(toml::Value::Table(model)) => Ok((header, model)),
        _ => Err(run_err(&path, "no [model] table")),
    }
}

/// The `[model]` of the run of `kind` in `run_dir`, laid over `defaults` (keys added
/// since the run was made read as their defaults; unknown keys are refused by name), and
/// checked by `check`; errors name the run's config.toml.
pub fn model_config<C: serde::Serialize + serde::de::DeserializeOwned>(
    run_dir: &Path,
    kind: ModelKind,
    defaults: &C,
    check: impl FnOnce(&C) -> Result<(), ModelError>,
) -> Result<C, ModelError> {
    let (_, model) = model_table(run_dir, kind)?;
    let path = RunLayout::new(run_dir).config();
    let config: C = weft_config::overlay(defaults, &model, &path.display().to_string(), "model")?;
    check(&config).map_err(|e| run_err(&path, format!("[model]: {e}")))?;
    Ok(config)
}

/// A JSON file a run keeps beside its checkpoints (normalisers, fitted statistics),
/// parsed as `T`; errors name the file and say what it should have held (`what`).
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path, what: &str) -> Result<T, ModelError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| run_err(path, format!("cannot read {what}: {e}")))?;
    serde_json::from_str(&text).map_err(|e| run_err(path, format!("not {what}: {e}")))
}

/// The model record `RUN/checkpoints/latest` names; an error naming `latest` when the run
/// has no checkpoint.
pub fn latest_checkpoint(run_dir: &Path) -> Result<PathBuf, ModelError> {
    let layout = RunLayout::new(run_dir);
    match layout.latest_stem()? {
        Some(stem) => Ok(layout.model_record(&stem)),
        None => Err(run_err(
            &layout.latest(),
            "missing: the run has no checkpoint yet (train it first)",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("weft-models-run-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("checkpoints")).unwrap();
        dir
    }

    #[test]
    fn header_round_trips_and_old_runs_are_multilevel() {
        let dir = scratch("header");
        let mut t = toml::Table::new();
        RunHeader::new(ModelKind::Hood, "cpu").insert_into(&mut t);
        t.insert("model".into(), toml::Value::Table(toml::Table::new()));
        std::fs::write(dir.join("config.toml"), toml::to_string(&t).unwrap()).unwrap();
        let (h, table) = read_run_config(&dir).unwrap();
        assert_eq!(h, RunHeader::new(ModelKind::Hood, "cpu"));
        assert!(table.contains_key("model"));
        // Written before `model_kind` existed.
        std::fs::write(
            dir.join("config.toml"),
            "format_version = 1\npreset = \"paper\"\n",
        )
        .unwrap();
        assert_eq!(
            read_run_config(&dir).unwrap().0.model,
            ModelKind::Multilevel
        );
        for (text, needle) in [
            ("format_version = 2\npreset = \"cpu\"\n", "format_version"),
            (
                "format_version = 1\nmodel_kind = \"gnn\"\npreset = \"cpu\"\n",
                "model_kind",
            ),
            ("format_version = 1\n", "preset"),
            ("format_version = \n", "config.toml"),
        ] {
            std::fs::write(dir.join("config.toml"), text).unwrap();
            let e = read_run_config(&dir).unwrap_err().to_string();
            assert!(e.contains(needle) && e.contains("config.toml"), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn latest_names_a_step_record() {
        let dir = scratch("latest");
        let layout = RunLayout::new(&dir);
        assert_eq!(layout.latest_stem().unwrap(), None);
        assert!(latest_checkpoint(&dir)
            .unwrap_err()
            .to_string()
            .contains("latest"));
        std::fs::write(
            layout.latest(),
            RunLayout::latest_text(&RunLayout::stem(250)),
        )
        .unwrap();
        assert_eq!(
            latest_checkpoint(&dir).unwrap(),
            dir.join("checkpoints/step-000250.bpk")
        );
        for bad in ["../x.bpk", "step-000250.optim.bpk", "", "step-.bpk"] {
            std::fs::write(layout.latest(), bad).unwrap();
            assert!(layout.latest_stem().is_err(), "{bad:?}");
        }
        for step in [30, 4, 100] {
            std::fs::write(layout.model_record(&RunLayout::stem(step)), b"").unwrap();
            std::fs::write(layout.optimizer_record(&RunLayout::stem(step)), b"").unwrap();
        }
        assert_eq!(layout.checkpoint_steps().unwrap(), [4, 30, 100]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
