//! [`RefinePredictor`]: a trained refinement run (DenseGATs, MultiResGNet) opened for
//! inference: the network at its latest checkpoint, the feature normaliser fitted at
//! training, and what the model reads (position feature, influence count).
//!
//! As a [`Deformer`] it animates any character mesh dressed on a body: the mesh is bound
//! to the body at the clip's shape (skinning weights from the closest skin point,
//! volumetric joint distances through the body), skinned coarsely per frame, and
//! corrected by the network, whole mesh at once (§3.2.3.2: "whole meshes at
//! evaluation").

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::store::ModuleRecord;
use burn::tensor::{Bytes, Device, Tensor, TensorData};
use weft_body::{BodyModel, Pose};
use weft_garment::FitBody;
use weft_mesh::TriMesh;
use weft_nn::FeatureNormalizer;

use super::character::{Character, CharacterRig, InputSpec};
use super::{read_normalizer, RefineConfig, RefineNet, NORMALIZER_FILE};
use crate::deformer::{Clip, Deformer, Frames};
use crate::densegats::DenseGatsConfig;
use crate::error::ModelError;
use crate::kind::ModelKind;
use crate::multiresgnet::MultiResGnetConfig;
use crate::run::{latest_checkpoint, read_run_config, RunLayout};

/// A trained refinement network ready to run; see the module documentation.
pub struct RefinePredictor {
    kind: ModelKind,
    net: Box<dyn RefineNet + Send + Sync>,
    normalizer: FeatureNormalizer,
    inputs: InputSpec,
    influences: usize,
    device: Device,
    checkpoint: PathBuf,
}

fn run_err(path: &Path, message: impl Into<String>) -> ModelError {
    ModelError::Run {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// The parameters of `checkpoint` loaded into `fresh`.
pub(crate) fn load_record<M: Module>(fresh: M, checkpoint: &Path) -> Result<M, ModelError> {
    let bytes = weft_mesh::io::read_input(checkpoint).map_err(|source| ModelError::RunRead {
        path: checkpoint.to_path_buf(),
        source,
    })?;
    ModuleRecord::from_bytes(Bytes::from_bytes_vec(bytes))
        .and_then(|record| fresh.try_load_record(record))
        .map_err(|e| {
            run_err(
                checkpoint,
                format!("does not fit the model in config.toml: {e}"),
            )
        })
}

/// What a loaded refinement network reads.
struct Reads {
    inputs: InputSpec,
    influences: usize,
    joints: usize,
}

/// A run's `[model]` table (`path` names config.toml in errors), checked. Keys added
/// since the run was made (`frame`, `coarse`) read as their defaults, which are what
/// the model did before the key existed; unknown keys are refused by name.
fn model_config<C: RefineConfig>(model: &toml::Table, path: &Path) -> Result<C, ModelError> {
    let cfg: C = weft_config::overlay(&C::defaults(), model, &path.display().to_string(), "model")?;
    cfg.check()
        .map_err(|e| run_err(path, format!("[model]: {e}")))?;
    Ok(cfg)
}

/// The network of `[model]` (`path` names config.toml in errors) with the parameters
/// of `checkpoint`, and what it reads.
fn load_net<C: RefineConfig>(
    model: &toml::Table,
    path: &Path,
    checkpoint: &Path,
    device: &Device,
) -> Result<(Box<dyn RefineNet + Send + Sync>, Reads), ModelError> {
    let cfg: C = model_config(model, path)?;
    let net = load_record(cfg.build(device)?, checkpoint)?;
    Ok((
        cfg.inference(net),
        Reads {
            inputs: cfg.inputs(),
            influences: cfg.influences(),
            joints: cfg.joints(),
        },
    ))
}

impl RefinePredictor {
    /// Loads the run in `dir` on the CPU. Errors name the file: a run of another model
    /// kind, a `[model]` table that does not validate, a checkpoint that does not fit, a
    /// missing or foreign normaliser.
    pub fn load(dir: &Path) -> Result<Self, ModelError> {
        let (header, mut table) = read_run_config(dir)?;
        let path = RunLayout::new(dir).config();
        let model = match table.remove("model") {
            Some(toml::Value::Table(t)) => t,
            _ => return Err(run_err(&path, "no [model] table")),
        };
        let device = weft_nn::backend::cpu();
        let checkpoint = latest_checkpoint(dir)?;
        let (net, reads) = match header.model {
            ModelKind::DenseGats => {
                load_net::<DenseGatsConfig>(&model, &path, &checkpoint, &device)?
            }
            ModelKind::MultiResGnet => {
                load_net::<MultiResGnetConfig>(&model, &path, &checkpoint, &device)?
            }
            other => {
                return Err(run_err(
                    &path,
                    format!(
                    "a run of model `{other}`, not a refinement model (densegats, multiresgnet)"
                ),
                ))
            }
        };
        let normalizer = read_normalizer(&dir.join(NORMALIZER_FILE))?;
        let joints = reads.joints;
        if normalizer.width() != 6 + joints {
            return Err(run_err(
                &dir.join(NORMALIZER_FILE),
                format!(
                    "normalises {} features; the model reads {} (6 + {joints} joints)",
                    normalizer.width(),
                    6 + joints
                ),
            ));
        }
        Ok(RefinePredictor {
            kind: header.model,
            net,
            normalizer,
            inputs: reads.inputs,
            influences: reads.influences,
            device,
            checkpoint,
        })
    }

    /// Influences per vertex of the coarse skinning the model was trained on.
    pub fn influences(&self) -> usize {
        self.influences
    }

    /// How the model reads a pose.
    pub fn inputs(&self) -> InputSpec {
        self.inputs
    }

    /// `character` (prepared with [`Self::influences`]) in `pose` with the root at
    /// `translation`: the coarse mesh plus the network's correction.
    pub fn predict(
        &self,
        character: &Character,
        pose: &Pose,
        translation: [f64; 3],
    ) -> Result<Vec<[f64; 3]>, ModelError> {
        let mut input = character.pose_input(pose, translation, self.inputs)?;
        let mut features = std::mem::take(&mut input.features);
        self.normalizer
            .apply(&mut features)
            .map_err(|e| ModelError::Config(format!("feature normaliser: {e}")))?;
        let n = character.vertex_count();
        let x = Tensor::<2>::from_data(
            TensorData::new(features, [n, character.feature_width()]),
            &self.device,
        );
        let delta: Vec<f32> = self
            .net
            .forward(x, character.batch())?
            .into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .map_err(|e| ModelError::Config(format!("network output: {e:?}")))?;
        Ok(input.corrected(&delta))
    }

    /// Binds `mesh` (in the rest pose of `body` at `betas`) to the body: weights from the
    /// closest skin point, volumetric joint distances through the body.
    pub fn bind(
        &self,
        mesh: &TriMesh,
        body: &BodyModel,
        betas: &[f64],
    ) -> Result<Character, ModelError> {
        let fit = FitBody::new(body, betas).map_err(|e| ModelError::Body(e.to_string()))?;
        let weights = fit
            .weights_at(body, &mesh.positions)
            .map_err(|e| ModelError::Body(e.to_string()))?;
        let joints = body
            .joints(betas)
            .map_err(|e| ModelError::Body(e.to_string()))?;
        let parents = body.skeleton().parents().to_vec();
        let joint_distances = fit
            .joint_distances(&joints, &parents, &mesh.positions)
            .map_err(|e| ModelError::Body(e.to_string()))?;
        Character::new(
            CharacterRig {
                mesh: mesh.clone(),
                weights: weights.to_f32(),
                joints,
                parents,
                joint_distances,
            },
            self.influences,
        )
    }
}

impl Deformer for RefinePredictor {
    fn name(&self) -> String {
        match self.kind {
            ModelKind::MultiResGnet => "MultiResGNet".into(),
            _ => "DenseGATs".into(),
        }
    }

    fn kind(&self) -> Option<ModelKind> {
        Some(self.kind)
    }

    fn variant(&self) -> BTreeMap<String, String> {
        BTreeMap::from([
            ("checkpoint".into(), self.checkpoint.display().to_string()),
            ("influences".into(), self.influences.to_string()),
            ("coarse".into(), self.inputs.coarse.to_string()),
            (
                "position feature".into(),
                format!("{:?}", self.inputs.position).to_lowercase(),
            ),
            (
                "frame".into(),
                format!("{:?}", self.inputs.frame).to_lowercase(),
            ),
        ])
    }

    fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError> {
        clip.check()?;
        let betas: Vec<f64> = clip.betas.iter().map(|&b| f64::from(b)).collect();
        let character = self.bind(garment, body, &betas)?;
        clip.poses
            .iter()
            .zip(clip.trans)
            .map(|(pose, t)| {
                let x = self.predict(&character, pose, t.map(f64::from))?;
                Ok(x.into_iter().map(|p| p.map(|v| v as f32)).collect())
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use weft_body::Skinning;

    use super::*;
    use crate::refine::{Frame, PositionFeature};

    #[test]
    fn a_run_made_before_a_key_existed_reads_its_default_and_unknown_keys_are_refused() {
        let path = Path::new("run/config.toml");
        // The [model] table of a DenseGATs run of 2026-11-25: no `frame`, no `coarse`.
        let old: toml::Table = toml::from_str(
            "activation = \"tanhshrink\"\nbatch_norm = true\nblocks = 3\nchannels = 4\n\
             dense = true\nheads = 4\ninfluences = 8\ninput_widths = [32, 32]\njoints = 24\n\
             modules = 2\noutput_widths = [128, 64]\nposition = \"position\"\n\
             self_reinforced = 0.125\n",
        )
        .unwrap();
        let cfg: DenseGatsConfig = model_config(&old, path).unwrap();
        assert_eq!(
            cfg.inputs(),
            InputSpec {
                coarse: Skinning::Lbs,
                position: PositionFeature::Position,
                frame: Frame::World,
            }
        );
        assert_eq!((cfg.blocks, cfg.channels, cfg.modules), (3, 4, 2));
        let mut new = old.clone();
        new.insert("coarse".into(), "dqs".into());
        new.insert("frame".into(), "skinning".into());
        let cfg: MultiResGnetConfig = {
            let mut t = new.clone();
            for k in ["blocks", "modules", "dense"] {
                t.remove(k);
            }
            model_config(&t, path).unwrap()
        };
        assert_eq!((cfg.coarse, cfg.frame), (Skinning::Dqs, Frame::Skinning));
        new.insert("coarse".into(), "cubic".into());
        let e = model_config::<DenseGatsConfig>(&new, path)
            .unwrap_err()
            .to_string();
        assert!(e.contains("run/config.toml") && e.contains("cubic"), "{e}");
        new.remove("coarse");
        new.insert("corse".into(), "dqs".into());
        let e = model_config::<DenseGatsConfig>(&new, path)
            .unwrap_err()
            .to_string();
        assert!(e.contains("corse"), "{e}");
    }
}
