//! Training a learned refinement of skinning (seed 001 ch. 3: DenseGATs, MultiResGNet)
//! on a character dataset (`weft data characters`).
//!
//! - Each pose of each training character is cut into `ceil(N / patch)` connected
//!   patches grown from seeded vertices (thesis-reference D5/M5: "the surrounding 1024
//!   consecutive vertices each time until traversing the entire meshes"), so an epoch
//!   covers every mesh about once per pose; the patches are shuffled by the run seed and
//!   grouped `patches` to an item, one forward pass over their disjoint union (the
//!   thesis's batch). Seed vertices and groups are functions of the run seed, so a
//!   resumed run sees the same patches.
//! - The node features of a pose are computed on the whole coarse mesh (normals need
//!   every neighbour) and gathered for the patch; a z-score normaliser fitted on the
//!   training characters before the first step (§3.3: "normalized using the mean and
//!   variance for each dimension") is saved in the run directory as `normalizer.json`.
//! - Loss: mean squared error of the correction in centimetres (§3.2.3.2).
//! - Validation: whole meshes (§3.2.3.2: "whole meshes at evaluation"), the mean
//!   per-vertex distance to the truth in centimetres over every validation pose.

pub mod config;

use std::path::Path;

use burn::module::Module;
use burn::tensor::{Device, Tensor, TensorData};
use weft_data::characters::{CharacterData, CharacterSet};
use weft_data::Split;
use weft_mesh::rng::SplitMix64;
use weft_models::refine::{Character, CharacterRig, InputSpec, RefineNet};
use weft_nn::{FeatureNormalizer, GraphBatch, NormalizerFit, Patch};

pub use config::RefineTraining;

use crate::error::{Result, TrainError};
use crate::task::{LossTerm, Metrics, StepEnd, TrainTask};

/// The validation metric: mean per-vertex error, cm.
pub const MEAN_ERROR_CM: &str = "mean_error_cm";

pub use weft_models::refine::NORMALIZER_FILE;

/// The one loss term.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Term {
    /// Mean squared error of the corrections, cm².
    Mse,
}

impl LossTerm for Term {
    fn name(self) -> &'static str {
        "mse"
    }
}

/// A pose's normalised features (row-major `N × (6 + S)`), coarse mesh and target
/// corrections (cm, row-major `N × 3`).
pub type PoseTensors = (Vec<f32>, Vec<[f64; 3]>, Vec<f32>);

/// One character of the dataset, prepared for the model.
pub struct Posed {
    /// Its id.
    pub id: String,
    /// The rig, features and coarse deformation.
    pub character: Character,
    /// Its poses and their ground truth.
    pub data: CharacterData,
}

/// The rig of a character file, as the models read it.
pub fn rig_of(data: &CharacterData) -> CharacterRig {
    CharacterRig {
        mesh: weft_mesh::TriMesh {
            positions: data
                .rest_positions
                .iter()
                .map(|p| p.map(f64::from))
                .collect(),
            faces: data.faces.clone(),
        },
        weights: data.weights.clone(),
        joints: data.joints.iter().map(|j| j.map(f64::from)).collect(),
        parents: data.parents.clone(),
        joint_distances: data.joint_distances.clone(),
    }
}

impl Posed {
    /// Prepares `data` for a model with `influences` weights per vertex.
    pub fn new(id: &str, data: CharacterData, influences: usize) -> Result<Self> {
        let character = Character::new(rig_of(&data), influences)?;
        Ok(Posed {
            id: id.to_string(),
            character,
            data,
        })
    }

    /// Normalised features `[N, 6 + S]`, the coarse mesh and the target corrections (cm,
    /// `[N, 3]`, in the spec's frame) of pose `p`, read as `spec` says.
    pub fn inputs(
        &self,
        p: usize,
        spec: InputSpec,
        normalizer: &FeatureNormalizer,
    ) -> Result<PoseTensors> {
        let mut input = self
            .character
            .pose_input(&self.data.poses[p], [0.0; 3], spec)?;
        let targets = input.target_cm(&self.data.truth[p]);
        let mut features = std::mem::take(&mut input.features);
        normalizer.apply(&mut features).map_err(nn)?;
        Ok((features, input.coarse, targets))
    }
}

fn nn(e: weft_nn::NnError) -> TrainError {
    TrainError::Nn(e)
}

/// Loads the characters of `split`, prepared for `influences`.
pub fn load_split(set: &CharacterSet, split: Split, influences: usize) -> Result<Vec<Posed>> {
    set.records(split)
        .into_iter()
        .map(|r| {
            let data = set.load(r)?;
            Posed::new(&r.id, data, influences)
        })
        .collect()
}

/// The normaliser fitted on every pose of `characters`.
pub fn fit_normalizer(characters: &[Posed], spec: InputSpec) -> Result<FeatureNormalizer> {
    let width = characters
        .first()
        .map(|c| c.character.feature_width())
        .ok_or_else(|| TrainError::config("data", "no training characters", "at least one"))?;
    let mut fit = NormalizerFit::new(width).map_err(nn)?;
    for c in characters {
        for pose in &c.data.poses {
            let input = c.character.pose_input(pose, [0.0; 3], spec)?;
            fit.observe(&input.features).map_err(nn)?;
        }
    }
    fit.finish().map_err(nn)
}

/// The refinement task of a model `M`; see the module documentation.
pub struct RefineTask<M> {
    training: RefineTraining,
    spec: InputSpec,
    normalizer: FeatureNormalizer,
    device: Device,
    seed: u64,
    train: Vec<Posed>,
    validation: Vec<Posed>,
    /// `(character, pose, patch)` of every patch of an epoch, in a seeded order, grouped
    /// `patches` to an item.
    groups: Vec<Vec<(usize, usize, usize)>>,
    _model: std::marker::PhantomData<M>,
}

impl<M> RefineTask<M> {
    /// The task over `train` and `validation` characters, with the normaliser fitted on
    /// `train`; the model reads poses as `spec` says.
    pub fn new(
        training: &RefineTraining,
        spec: InputSpec,
        train: Vec<Posed>,
        validation: Vec<Posed>,
        normalizer: FeatureNormalizer,
        seed: u64,
        device: &Device,
    ) -> Result<Self> {
        training.validate_values()?;
        let mut items = Vec::new();
        for (c, posed) in train.iter().enumerate() {
            let n = posed.character.vertex_count();
            let patches = n.div_ceil(training.patch_size(n));
            for p in 0..posed.data.poses.len() {
                items.extend((0..patches).map(|k| (c, p, k)));
            }
        }
        // A seeded shuffle, so a group mixes characters, poses and regions.
        let mut rng = SplitMix64::new(seed ^ 0x5041_5443_4845_5321);
        for i in (1..items.len()).rev() {
            items.swap(i, rng.below(i + 1));
        }
        let groups = items.chunks(training.patches).map(<[_]>::to_vec).collect();
        Ok(RefineTask {
            training: training.clone(),
            spec,
            normalizer,
            device: device.clone(),
            seed,
            train,
            validation,
            groups,
            _model: std::marker::PhantomData,
        })
    }

    /// The fitted normaliser.
    pub fn normalizer(&self) -> &FeatureNormalizer {
        &self.normalizer
    }

    /// Training characters.
    pub fn character_count(&self) -> usize {
        self.train.len()
    }

    fn tensor(&self, rows: Vec<f32>, width: usize) -> Tensor<2> {
        let n = rows.len() / width;
        Tensor::from_data(TensorData::new(rows, [n, width]), &self.device)
    }
}

/// Writes `normalizer` into the run directory `dir` atomically.
pub fn save_normalizer(dir: &Path, normalizer: &FeatureNormalizer) -> Result<()> {
    crate::run::save_json(dir, NORMALIZER_FILE, normalizer)
}

impl<M> TrainTask for RefineTask<M>
where
    M: Module + Clone + RefineNet,
{
    type Model = M;
    type Term = Term;
    type Stage = ();

    fn item_count(&self) -> usize {
        self.groups.len()
    }

    fn terms(&self, _: &()) -> Vec<(Term, f64)> {
        vec![(Term::Mse, 1.0)]
    }

    fn losses(&mut self, model: &M, item: usize, _: &[Term]) -> Result<Vec<Tensor<1>>> {
        let (mut xs, mut ys, mut patches) = (Vec::new(), Vec::new(), Vec::new());
        for &(c, p, k) in &self.groups[item] {
            let posed = &self.train[c];
            let n = posed.character.vertex_count();
            let mut rng = SplitMix64::new(
                self.seed
                    ^ (((c as u64) << 40) | ((p as u64) << 20) | k as u64)
                        .wrapping_mul(0x9e37_79b9_7f4a_7c15),
            );
            let patch = Patch::grow(
                posed.character.graph(),
                rng.below(n),
                self.training.patch_size(n),
            )
            .map_err(nn)?;
            let (features, _, targets) = posed.inputs(p, self.spec, &self.normalizer)?;
            let width = posed.character.feature_width();
            xs.push(self.tensor(patch.gather(&features, width).map_err(nn)?, width));
            ys.push(self.tensor(patch.gather(&targets, 3).map_err(nn)?, 3));
            patches.push(patch);
        }
        let graphs: Vec<&weft_mesh::Graph> = patches.iter().map(Patch::graph).collect();
        let batch = GraphBatch::new(&graphs).map_err(nn)?;
        let pred = model.forward(Tensor::cat(xs, 0), &batch)?;
        Ok(vec![(pred - Tensor::cat(ys, 0)).powi_scalar(2).mean()])
    }

    fn validate(&mut self, model: &M) -> Result<Metrics> {
        let (mut sum, mut count) = (0.0f64, 0usize);
        for posed in &self.validation {
            let width = posed.character.feature_width();
            for p in 0..posed.data.poses.len() {
                let (features, _, targets) = posed.inputs(p, self.spec, &self.normalizer)?;
                let pred = model.forward(self.tensor(features, width), posed.character.batch())?;
                let pred: Vec<f32> = pred
                    .into_data()
                    .convert::<f32>()
                    .try_into_vec::<f32>()
                    .map_err(|e| TrainError::Shape {
                        what: "predicted corrections".into(),
                        expected: "f32 values".into(),
                        found: format!("{e:?}"),
                    })?;
                for (a, b) in pred.chunks_exact(3).zip(targets.chunks_exact(3)) {
                    let d2: f32 = (0..3).map(|k| (a[k] - b[k]).powi(2)).sum();
                    sum += f64::from(d2.sqrt());
                    count += 1;
                }
            }
        }
        let mean = if count == 0 {
            f64::NAN
        } else {
            sum / count as f64
        };
        Ok(Metrics::from([(MEAN_ERROR_CM.to_string(), mean)]))
    }

    fn primary_metric(&self) -> &'static str {
        MEAN_ERROR_CM
    }

    fn stage_name(&self, _: &()) -> String {
        "train".into()
    }

    fn advance(&self, _: &mut (), _: &StepEnd<'_, Term>) -> bool {
        false
    }

    fn enter_stage(&mut self, model: M, _: &()) -> M {
        model
    }
}
