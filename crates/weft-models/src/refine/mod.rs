//! Learned refinement of skinning (seed 001 ch. 3, case 1): a character whose body and
//! tight clothes are one mesh is skinned coarsely (LBS with a few influences) and a
//! graph network on the coarse mesh predicts each vertex's correction to a nonlinear
//! deformation, `M = M_coarse + W(G; Ψ)` (eq. 3.1). Per frame, no history.
//!
//! - [`character`]: the rig, the coarse deformation and the node features;
//! - [`RefineNet`]: what DenseGATs ([`crate::densegats`]) and MultiResGNet implement;
//! - [`predictor`]: a trained run for inference, and as a [`crate::Deformer`].

pub mod character;
pub mod predictor;

use std::path::Path;
use std::sync::Arc;

use burn::tensor::Tensor;
use weft_nn::{Adjacency, FeatureNormalizer};

use crate::error::ModelError;

pub use character::{Character, CharacterRig, PoseInput, PositionFeature};
pub use predictor::RefinePredictor;

/// The feature normaliser's file in a run directory (fitted on the training characters
/// before the first step, read by every consumer of the run).
pub const NORMALIZER_FILE: &str = "normalizer.json";

/// Reads a run's feature normaliser (`normalizer.json`).
pub fn read_normalizer(path: &Path) -> Result<FeatureNormalizer, ModelError> {
    let run = |message: String| ModelError::Run {
        path: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| run(format!("cannot read the feature normaliser: {e}")))?;
    let n: FeatureNormalizer =
        serde_json::from_str(&text).map_err(|e| run(format!("not a feature normaliser: {e}")))?;
    n.validate().map_err(|e| run(e.to_string()))?;
    Ok(n)
}

/// Centimetres per metre: refinement networks predict corrections in centimetres.
pub const CM_PER_M: f64 = 100.0;

/// A refinement network: normalised node features `[N, 6 + S]` on the graph of
/// `adjacency` to per-vertex corrections `[N, 3]` in centimetres.
pub trait RefineNet {
    /// The corrections of every node.
    fn forward(&self, x: Tensor<2>, adjacency: &Arc<Adjacency>) -> Result<Tensor<2>, ModelError>;
}
