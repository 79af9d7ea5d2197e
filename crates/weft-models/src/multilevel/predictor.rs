//! [`Predictor`]: a trained run directory loaded for inference.
//!
//! Run directory layout (written by weft-train, read here and by weft-eval):
//! `RUN/config.toml` holds `format_version` (= [`RUN_FORMAT_VERSION`]), `preset`, and the
//! model configuration as a `[model]` table ([`MultilevelConfig`]; other tables, such as
//! the training configuration, are ignored here); `RUN/checkpoints/latest` is a text file
//! naming the newest checkpoint in `RUN/checkpoints/`, a burn module record file
//! (`Module::save_file`, burn's burnpack format).

use std::ops::Range;
use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::tensor::Device;
use weft_body::BodyModel;
use weft_mesh::TriMesh;

use super::config::MultilevelConfig;
use super::frames::FrameInputs;
use super::garment::GarmentInput;
use super::model::Multilevel;
use crate::error::ModelError;

/// Version of the run directory format this crate reads.
pub const RUN_FORMAT_VERSION: i64 = 1;

/// Frames inferred together by [`Predictor::animate`] (batch 16, as in seed 000's timing).
pub const ANIMATE_WINDOW: usize = 16;

/// A trained model ready for inference on the CPU.
#[derive(Debug)]
pub struct Predictor {
    model: Multilevel,
    config: MultilevelConfig,
    checkpoint: PathBuf,
}

fn run_err(path: &Path, message: impl Into<String>) -> ModelError {
    ModelError::Run {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Reads `RUN/config.toml`: checks the format version and returns the model config.
pub fn read_run_config(run_dir: &Path) -> Result<MultilevelConfig, ModelError> {
    let path = run_dir.join("config.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| run_err(&path, e.to_string()))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| run_err(&path, e.to_string()))?;
    match table
        .get("format_version")
        .and_then(toml::Value::as_integer)
    {
        Some(RUN_FORMAT_VERSION) => {}
        Some(v) => {
            return Err(run_err(
                &path,
                format!("format_version {v}; this build reads version {RUN_FORMAT_VERSION}"),
            ))
        }
        None => {
            return Err(run_err(
                &path,
                format!("no integer format_version (expected {RUN_FORMAT_VERSION})"),
            ))
        }
    }
    let model = match table.get("model") {
        Some(toml::Value::Table(t)) => t.clone(),
        _ => return Err(run_err(&path, "no [model] table")),
    };
    let cfg =
        MultilevelConfig::from_table(model).map_err(|e| run_err(&path, format!("[model]: {e}")))?;
    if let Some(preset) = table.get("preset").and_then(toml::Value::as_str) {
        if preset != cfg.preset {
            return Err(run_err(
                &path,
                format!(
                    "preset {preset:?} but the [model] table says {:?}",
                    cfg.preset
                ),
            ));
        }
    }
    Ok(cfg)
}

/// The checkpoint `RUN/checkpoints/latest` names.
pub fn latest_checkpoint(run_dir: &Path) -> Result<PathBuf, ModelError> {
    let dir = run_dir.join("checkpoints");
    let latest = dir.join("latest");
    let name = std::fs::read_to_string(&latest).map_err(|e| run_err(&latest, e.to_string()))?;
    let name = name.trim();
    if name.is_empty() || name.contains(['/', '\\']) {
        return Err(run_err(
            &latest,
            format!("expected a checkpoint file name in checkpoints/, got {name:?}"),
        ));
    }
    Ok(dir.join(name))
}

impl Predictor {
    /// Loads the model config and the latest checkpoint of `run_dir` on the CPU.
    ///
    /// Errors name the file: a missing or unreadable config, a format version this build
    /// does not read, a `[model]` table that does not validate, a checkpoint whose tensors
    /// do not fit the config (a checkpoint of another preset).
    pub fn load(run_dir: &Path) -> Result<Self, ModelError> {
        let config = read_run_config(run_dir)?;
        let checkpoint = latest_checkpoint(run_dir)?;
        Self::from_checkpoint(config, &checkpoint, &weft_nn::backend::cpu())
    }

    /// A model of `config` with the parameters of `checkpoint`, on `device`.
    pub fn from_checkpoint(
        config: MultilevelConfig,
        checkpoint: &Path,
        device: &Device,
    ) -> Result<Self, ModelError> {
        let fresh = Multilevel::new(&config, device)?;
        let model = fresh.try_load_file(checkpoint).map_err(|e| {
            run_err(
                checkpoint,
                format!(
                    "does not fit the model of preset {:?} in config.toml: {e}",
                    config.preset
                ),
            )
        })?;
        Ok(Predictor {
            model,
            config,
            checkpoint: checkpoint.to_path_buf(),
        })
    }

    /// A predictor around an in-memory model (tests, evaluation right after training).
    pub fn from_model(model: Multilevel) -> Self {
        Predictor {
            config: model.config().clone(),
            model,
            checkpoint: PathBuf::new(),
        }
    }

    /// The model.
    pub fn model(&self) -> &Multilevel {
        &self.model
    }

    /// Its configuration.
    pub fn config(&self) -> &MultilevelConfig {
        &self.config
    }

    /// The checkpoint it was loaded from (empty for [`Predictor::from_model`]).
    pub fn checkpoint(&self) -> &Path {
        &self.checkpoint
    }

    /// Garment vertices of every frame of a motion: `garment` in the rest pose of `body`
    /// at shape `betas`, animated by `poses`/`trans` at `fps`. The pair is encoded once;
    /// frames run in windows of [`ANIMATE_WINDOW`].
    pub fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        betas: &[f32],
        poses: &[[f32; 72]],
        trans: &[[f32; 3]],
        fps: f64,
    ) -> Result<Vec<Vec<[f32; 3]>>, ModelError> {
        let g = GarmentInput::new(garment, body, betas, &self.config)?;
        let pair = self.model.encode_pair(&g)?;
        let mut out = Vec::with_capacity(poses.len());
        let windows: Vec<Range<usize>> = (0..poses.len())
            .step_by(ANIMATE_WINDOW)
            .map(|a| a..(a + ANIMATE_WINDOW).min(poses.len()))
            .collect();
        for range in windows {
            let f = FrameInputs::new(body, betas, poses, trans, fps, range, &self.config)?;
            let p = self.model.forward(&pair, &g, &f)?;
            let [t, n, _] = p.vertices.dims();
            let data = p
                .vertices
                .into_data()
                .convert::<f32>()
                .try_into_vec::<f32>()
                .map_err(|e| ModelError::Config(format!("reading the prediction: {e:?}")))?;
            for k in 0..t {
                out.push(
                    (0..n)
                        .map(|i| {
                            let o = (k * n + i) * 3;
                            [data[o], data[o + 1], data[o + 2]]
                        })
                        .collect(),
                );
            }
        }
        Ok(out)
    }
}
