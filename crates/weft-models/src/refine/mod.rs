//! Learned refinement of skinning (seed 001 ch. 3, case 1): a character whose body and
//! tight clothes are one mesh is skinned coarsely (LBS with a few influences) and a
//! graph network on the coarse mesh predicts each vertex's correction to a nonlinear
//! deformation, `M = M_coarse + W(G; Ψ)` (eq. 3.1; DQS as the coarse mesh is an
//! option). Per frame, no history.
//!
//! - [`character`]: the rig, the coarse deformation and the node features;
//! - [`RefineNet`]: what DenseGATs ([`crate::densegats`]) and MultiResGNet
//!   ([`crate::multiresgnet`]) implement, and [`tanh_mlp`], the feature transforms both
//!   put before and after their graph layers;
//! - [`predictor`]: a trained run for inference, and as a [`crate::Deformer`].

pub mod character;
pub mod predictor;

use std::path::Path;

use burn::tensor::{Device, Tensor};
use weft_nn::{Activation, FeatureNormalizer, GraphBatch, Mlp, MlpConfig};

use crate::error::ModelError;

pub use character::{Character, CharacterRig, Frame, InputSpec, PoseInput, PositionFeature};
pub use predictor::RefinePredictor;

/// The feature normaliser's file in a run directory (fitted on the training characters
/// before the first step, read by every consumer of the run).
pub const NORMALIZER_FILE: &str = "normalizer.json";

/// Reads a run's feature normaliser (`normalizer.json`).
pub fn read_normalizer(path: &Path) -> Result<FeatureNormalizer, ModelError> {
    let n: FeatureNormalizer = crate::run::read_json(path, "a feature normaliser")?;
    n.validate().map_err(|e| ModelError::Run {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    Ok(n)
}

/// Centimetres per metre: refinement networks predict corrections in centimetres.
pub const CM_PER_M: f64 = 100.0;

/// A refinement model's configuration: what building, loading and feeding its network
/// needs, so the predictor, the training pipeline and the benches treat DenseGATs and
/// MultiResGNet alike.
pub trait RefineConfig: serde::Serialize + serde::de::DeserializeOwned {
    /// The network.
    type Net: burn::module::Module + Clone + RefineNet + Send + Sync + 'static;
    /// Every key at its default: what a run's config.toml made before a key existed
    /// means for that key.
    fn defaults() -> Self;
    /// Checks the values; errors name the field.
    fn check(&self) -> Result<(), ModelError>;
    /// Builds the network on `device`.
    fn build(&self, device: &Device) -> Result<Self::Net, ModelError>;
    /// How the model reads a pose: coarse skinning, position feature, frame.
    fn inputs(&self) -> InputSpec;
    /// Influences per vertex of the coarse skinning.
    fn influences(&self) -> usize;
    /// Joints of the skeleton (node features are `6 + S` wide).
    fn joints(&self) -> usize;
    /// The network as evaluation and animation run it: a faster form with the same
    /// values where the model has one (DenseGATs), else the network itself.
    fn inference(&self, net: Self::Net) -> Box<dyn RefineNet + Send + Sync> {
        Box::new(net)
    }
}

/// A refinement network: normalised node features `[N, 6 + S]` on the graph `graph` (a
/// whole mesh or a patch, as a one-graph [`GraphBatch`]: its adjacency for the GAT
/// blocks, the graph itself for MultiResGNet's pooling) to per-vertex corrections
/// `[N, 3]` in centimetres.
pub trait RefineNet {
    /// The corrections of every node.
    fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> Result<Tensor<2>, ModelError>;
}

/// The feature transforms of seed 001 (§3.2.3.2, §3.3.3.2): linear layers of `widths`
/// from `d_input`, tanh after every one, batch normalisation before every tanh when
/// `batch_norm` (decision D6).
pub fn tanh_mlp(
    d_input: usize,
    widths: &[usize],
    batch_norm: bool,
    device: &Device,
) -> Result<Mlp, ModelError> {
    MlpConfig::new(d_input, widths.to_vec())
        .with_activation(Activation::Tanh)
        .with_output_activation(Activation::Tanh)
        .with_batch_norm(batch_norm)
        .init(device)
        .map_err(nn_error)
}

/// The hidden layers of an output transform (a [`tanh_mlp`] of `widths`, or none when
/// `widths` is empty) and the width the last linear layer after them reads.
pub fn output_transform(
    d_input: usize,
    widths: &[usize],
    batch_norm: bool,
    device: &Device,
) -> Result<(Option<Mlp>, usize), ModelError> {
    if widths.is_empty() {
        return Ok((None, d_input));
    }
    let mlp = tanh_mlp(d_input, widths, batch_norm, device)?;
    let d = mlp.output_width();
    Ok((Some(mlp), d))
}

/// A layer's error as a model error (shapes and sizes the config should have caught).
pub(crate) fn nn_error(e: weft_nn::NnError) -> ModelError {
    ModelError::Config(e.to_string())
}
