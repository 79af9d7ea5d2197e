//! [`Predictor`]: a trained run directory loaded for inference.
//!
//! Run directory layout (written by weft-train, read here and by weft-eval):
//! `RUN/config.toml` holds `format_version` (= [`RUN_FORMAT_VERSION`]), `preset`, and the
//! model configuration as a `[model]` table ([`MultilevelConfig`]; other tables, such as
//! the training configuration, are ignored here); `RUN/checkpoints/latest` is a text file
//! naming the newest checkpoint in `RUN/checkpoints/`, a burn module record file
//! (`Module::save_file`, burn's burnpack format).

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::module::Module;
use burn::store::ModuleRecord;
use burn::tensor::{Bytes, Device};
use weft_body::BodyModel;
use weft_mesh::TriMesh;

use super::config::MultilevelConfig;
use super::frames::FrameInputs;
use super::garment::GarmentInput;
use super::model::Multilevel;
use crate::deformer::{Clip, Deformer, Frames, Timing};
use crate::error::ModelError;
use crate::kind::ModelKind;

pub use crate::run::FORMAT_VERSION as RUN_FORMAT_VERSION;

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

/// Reads `RUN/config.toml` ([`crate::run::read_run_config`]: header and format version)
/// and returns its `[model]` table as a Multilevel config.
pub fn read_run_config(run_dir: &Path) -> Result<MultilevelConfig, ModelError> {
    let (header, mut model) = crate::run::model_table(run_dir, ModelKind::Multilevel)?;
    // weft writes the whole [model] table, so a table without `body_contact` comes from a
    // build before it existed, whose models had none (the `cpu` default is now on).
    model
        .entry("body_contact")
        .or_insert(toml::Value::Boolean(false));
    let path = crate::run::RunLayout::new(run_dir).config();
    let cfg =
        MultilevelConfig::from_table(&model, &path.display().to_string()).map_err(|e| match e {
            ModelError::Config(m) => run_err(&path, format!("[model]: {m}")),
            other => other,
        })?;
    if header.preset != cfg.preset {
        return Err(run_err(
            &path,
            format!(
                "preset {:?} but the [model] table says {:?}",
                header.preset, cfg.preset
            ),
        ));
    }
    Ok(cfg)
}

impl Predictor {
    /// Loads the model config and the latest checkpoint of `run_dir` on the CPU.
    ///
    /// Errors name the file: a missing or unreadable config, a format version this build
    /// does not read, a `[model]` table that does not validate, a checkpoint whose tensors
    /// do not fit the config (a checkpoint of another preset).
    pub fn load(run_dir: &Path) -> Result<Self, ModelError> {
        let config = read_run_config(run_dir)?;
        let checkpoint = crate::run::latest_checkpoint(run_dir)?;
        Self::from_checkpoint(config, &checkpoint, &weft_nn::backend::cpu())
    }

    /// A model of `config` with the parameters of `checkpoint`, on `device`.
    pub fn from_checkpoint(
        config: MultilevelConfig,
        checkpoint: &Path,
        device: &Device,
    ) -> Result<Self, ModelError> {
        let fresh = Multilevel::new(&config, device)?;
        // Read as bytes (bounded by the file) rather than with `Module::try_load_file`:
        // burn's file reader allocates the metadata size the header claims (up to 100 MiB)
        // before reading it, whatever the file's length; its bytes reader first checks the
        // claim against the bytes present (found by fuzzing, docs/fuzzing.md).
        let bytes =
            weft_mesh::io::read_input(checkpoint).map_err(|source| ModelError::RunRead {
                path: checkpoint.to_path_buf(),
                source,
            })?;
        let model = ModuleRecord::from_bytes(Bytes::from_bytes_vec(bytes))
            .and_then(|record| fresh.try_load_record(record))
            .map_err(|e| {
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

    /// Garment vertices of every frame of `clip`: `garment` in the rest pose of `body`
    /// at shape `clip.betas`. The pair is encoded once; frames run in windows of
    /// [`ANIMATE_WINDOW`].
    pub fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError> {
        clip.check()?;
        let g = GarmentInput::new(garment, body, clip.betas, &self.config)?;
        let pair = self.model.encode_pair(&g)?;
        let mut out = Vec::with_capacity(clip.len());
        for range in windows(clip.len(), ANIMATE_WINDOW, clip.len()) {
            let f = FrameInputs::new(body, &g, clip, range, &self.config)?;
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

    /// Frames per second on `clip` per batch size: the pair encoded once (seed 000
    /// times it so), then windows of `batch` frames over `frames` frames (wrapping
    /// around the clip), network alone and with the per-frame inputs.
    pub fn time(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        batches: &[usize],
        frames: usize,
    ) -> Result<Vec<Timing>, ModelError> {
        clip.check()?;
        if clip.is_empty() {
            return Err(ModelError::mismatch("frames to time", "at least one", 0));
        }
        let g = GarmentInput::new(garment, body, clip.betas, &self.config)?;
        let pair = self.model.encode_pair(&g)?;
        let mut out = Vec::new();
        for &batch in batches {
            let batch = batch.clamp(1, clip.len());
            let windows = windows(frames.max(batch), batch, clip.len());
            // One untimed window: first-use allocations and the cached frame batch.
            let warm = FrameInputs::new(body, &g, clip, windows[0].clone(), &self.config)?;
            self.model.forward(&pair, &g, &warm)?;
            let (mut inputs_s, mut network_s, mut timed) = (0.0, 0.0, 0usize);
            for w in windows {
                let t0 = Instant::now();
                let f = FrameInputs::new(body, &g, clip, w.clone(), &self.config)?;
                let t1 = Instant::now();
                let p = self.model.forward(&pair, &g, &f)?;
                // Reading the result back is part of inference (it synchronises the device).
                let _ = p.vertices.into_data();
                network_s += t1.elapsed().as_secs_f64();
                inputs_s += (t1 - t0).as_secs_f64();
                timed += w.len();
            }
            out.push(Timing {
                batch,
                vertices: g.vertex_count(),
                network_fps: timed as f64 / network_s.max(1e-12),
                end_to_end_fps: timed as f64 / (network_s + inputs_s).max(1e-12),
                frames: timed,
            });
        }
        Ok(out)
    }
}

/// Windows of `batch` frames covering `frames` frames of a clip of `total` frames (a
/// window that would run past the clip's end starts again at its beginning).
fn windows(frames: usize, batch: usize, total: usize) -> Vec<Range<usize>> {
    (0..frames)
        .step_by(batch.max(1))
        .map(|a| {
            let a = a % total.max(1);
            a..(a + batch).min(total)
        })
        .collect()
}

impl Deformer for Predictor {
    fn name(&self) -> String {
        self.config.pooling.label().to_string()
    }

    fn kind(&self) -> Option<ModelKind> {
        Some(ModelKind::Multilevel)
    }

    fn variant(&self) -> BTreeMap<String, String> {
        let mut v = BTreeMap::from([
            ("preset".to_string(), self.config.preset.clone()),
            (
                "pooling".to_string(),
                self.config.pooling.name().to_string(),
            ),
        ]);
        if !self.checkpoint.as_os_str().is_empty() {
            v.insert("checkpoint".into(), self.checkpoint.display().to_string());
        }
        v
    }

    fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError> {
        Predictor::animate(self, garment, body, clip)
    }

    fn time(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        batches: &[usize],
        frames: usize,
    ) -> Result<Option<Vec<Timing>>, ModelError> {
        Predictor::time(self, garment, body, clip, batches, frames).map(Some)
    }
}
