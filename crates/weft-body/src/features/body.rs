//! Thin conveniences that compute the features from the body model's own types
//! ([`BodyModel`], [`ShapedBody`], [`SkinWeights`], forward-kinematics [`Rigid`]
//! transforms). Everything here is a few lines over the slice-based
//! functions of the sibling modules, which stay the reference.

use super::descriptor::{
    check_parents, mul, relative_rotations, relative_skinning_descriptor, transpose, Rotation,
};
use super::distances::joint_distances;
use super::error::FeatureError;
use super::matrix::FeatureMatrix;
use super::weights::SkinningWeights;
use crate::kinematics::Rigid;
use crate::query::{BodySurface, QueryError};
use crate::skinning::SkinWeights;
use crate::{BodyModel, ShapedBody};

impl TryFrom<&SkinWeights> for SkinningWeights {
    type Error = FeatureError;

    /// The dense, row-normalised form of the model's sparse weights.
    fn try_from(w: &SkinWeights) -> Result<Self, FeatureError> {
        SkinningWeights::new(w.to_dense(), w.joint_count())
    }
}

/// The rotation part of each transform, as a [`Rotation`].
pub fn rotations_of(transforms: &[Rigid]) -> Vec<Rotation> {
    transforms
        .iter()
        .map(|t| std::array::from_fn(|i| std::array::from_fn(|j| t.rotation[(i, j)])))
        .collect()
}

/// `r_i(θ)` (seed 001 eq. 3.9) from forward-kinematics transforms: global (or
/// skinning) joint transforms of the pose, and optionally of the rest pose `θ*`
/// (`None`: the rest rotations are the identity, as for SMPL). Only the rotations
/// are used, which is why the result ignores the root translation and the joint
/// positions the transforms carry.
pub fn descriptor_from_transforms(
    rest_positions: &[[f64; 3]],
    weights: &SkinningWeights,
    posed: &[Rigid],
    rest: Option<&[Rigid]>,
) -> Result<Vec<[f64; 3]>, FeatureError> {
    let g = rotations_of(posed);
    let relative = match rest {
        None => g,
        Some(rest) => {
            if rest.len() != posed.len() {
                return Err(FeatureError::CountMismatch {
                    what: "rest-pose transforms vs posed transforms",
                    expected: posed.len(),
                    found: rest.len(),
                });
            }
            g.iter()
                .zip(rotations_of(rest))
                .map(|(&a, b)| mul(a, transpose(b)))
                .collect()
        }
    };
    relative_skinning_descriptor(rest_positions, weights, &relative)
}

impl ShapedBody {
    /// Seed 000's body-shape input `D ∈ ℝ^{N_b × S}`: distances from every vertex of
    /// this shaped rest body to every joint `J(β)`.
    pub fn joint_vertex_distances(&self) -> Result<FeatureMatrix, FeatureError> {
        joint_distances(&self.vertices, &self.joints)
    }
}

impl BodyModel {
    /// The model's skinning weights in the dense form the features use.
    pub fn skinning_weights(&self) -> Result<SkinningWeights, FeatureError> {
        SkinningWeights::try_from(self.weights())
    }

    /// A query surface over `vertices` (a shaped or posed frame of this body) with the
    /// model's faces.
    pub fn body_surface(&self, vertices: &[[f64; 3]]) -> Result<BodySurface, QueryError> {
        BodySurface::new(vertices, self.faces())
    }

    /// `r_i(θ)` (seed 001 eq. 3.9) of every body vertex for a pose given as one local
    /// axis-angle per joint; the rest pose is SMPL's zero pose.
    pub fn relative_skinning_descriptor(
        &self,
        shaped: &ShapedBody,
        pose: &[[f64; 3]],
    ) -> Result<Vec<[f64; 3]>, FeatureError> {
        let parents = self.skeleton().parents();
        check_parents(parents)?;
        let relative = relative_rotations(parents, pose, None)?;
        relative_skinning_descriptor(&shaped.vertices, &self.skinning_weights()?, &relative)
    }
}
