//! A rigged character ready for learned refinement: rest mesh, skinning weights cut to
//! the model's influence count, skeleton, mesh graph, and the per-vertex inputs that do
//! not change with the pose (seed 001 §3.2.1's volumetric joint distances `x_i`).
//!
//! Per pose it gives the coarse mesh (LBS with the top-k influences renormalised, or DQS)
//! and the node features `[p_i | r_i(θ), n_i, x_i]` the networks read (§3.2.1, §3.3.1):
//! positions and normals of the coarse mesh (thesis-reference D8: the graph is built on
//! `M_coarse`), or in place of positions the relative skinning descriptor of eq. 3.9,
//! which is LBS without translations and so does not change when the character moves.

use serde::{Deserialize, Serialize};
use weft_body::features::body::descriptor_from_transforms;
use weft_body::features::weights::SkinningWeights;
use weft_body::kinematics::{Rigid, Skeleton};
use weft_body::skinning::{dqs, lbs, SkinWeights};
use weft_body::{Pose, Skinning};
use weft_mesh::TriMesh;
use weft_nn::GraphBatch;

use crate::error::ModelError;

/// What stands in for a vertex's position in the node features.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionFeature {
    /// The coarse mesh's vertex positions (DenseGATs, §3.2.1).
    #[default]
    Position,
    /// The relative skinning descriptor `r_i(θ)` (MultiResGNet, eq. 3.7–3.9).
    Descriptor,
}

/// A character's rig and constant inputs as plain arrays (what a dataset file or a
/// user's rigged mesh provides).
#[derive(Clone, Debug, PartialEq)]
pub struct CharacterRig {
    /// The rest mesh.
    pub mesh: TriMesh,
    /// Skinning weights, row-major `N × S`.
    pub weights: Vec<f32>,
    /// Rest joint positions.
    pub joints: Vec<[f64; 3]>,
    /// Each joint's parent.
    pub parents: Vec<Option<usize>>,
    /// Volumetric vertex–joint distances, row-major `N × S`.
    pub joint_distances: Vec<f32>,
}

/// A [`CharacterRig`] prepared for one model (see the module documentation).
#[derive(Clone, Debug)]
pub struct Character {
    rig: CharacterRig,
    skeleton: Skeleton,
    skin: SkinWeights,
    descriptor_weights: SkinningWeights,
    graph: GraphBatch,
}

/// One pose's coarse mesh and node features.
#[derive(Clone, Debug)]
pub struct PoseInput {
    /// The coarse mesh, `[N]`.
    pub coarse: Vec<[f64; 3]>,
    /// Node features, row-major `N × (6 + S)`.
    pub features: Vec<f32>,
}

impl Character {
    /// Checks `rig` and prepares it with at most `influences` weights per vertex.
    pub fn new(rig: CharacterRig, influences: usize) -> Result<Self, ModelError> {
        let n = rig.mesh.positions.len();
        let s = rig.joints.len();
        let mismatch = |what: &str, expected: String, found: usize| {
            ModelError::mismatch(what, expected, found)
        };
        if n == 0 || rig.mesh.faces.is_empty() {
            return Err(ModelError::Garment(
                "the character mesh has no vertices or faces".into(),
            ));
        }
        if rig.weights.len() != n * s {
            return Err(mismatch(
                "character skinning weights",
                format!("{n} vertices × {s} joints = {}", n * s),
                rig.weights.len(),
            ));
        }
        if rig.joint_distances.len() != n * s {
            return Err(mismatch(
                "character joint distances",
                format!("{n} vertices × {s} joints = {}", n * s),
                rig.joint_distances.len(),
            ));
        }
        if rig.parents.len() != s {
            return Err(mismatch(
                "skeleton parents",
                format!("one per joint ({s})"),
                rig.parents.len(),
            ));
        }
        if let Some(i) = rig.weights.iter().position(|w| !w.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "character skinning weights",
                index: i,
            });
        }
        if let Some(f) = rig
            .mesh
            .faces
            .iter()
            .position(|f| f.iter().any(|&v| v as usize >= n))
        {
            return Err(mismatch(
                "character face vertex indices",
                format!("below {n}"),
                f,
            ));
        }
        let skeleton =
            Skeleton::new(rig.parents.clone()).map_err(|e| ModelError::Body(e.to_string()))?;
        let dense: Vec<f64> = rig.weights.iter().map(|&w| f64::from(w)).collect();
        let skin = SkinWeights::from_dense(&dense, s).truncated(influences);
        let descriptor_weights = SkinningWeights::new(skin.to_dense(), s)
            .map_err(|e| ModelError::Body(format!("skinning weights: {e}")))?;
        let graph = GraphBatch::single(&rig.mesh.graph());
        Ok(Character {
            rig,
            skeleton,
            skin,
            descriptor_weights,
            graph,
        })
    }

    /// Vertices N.
    pub fn vertex_count(&self) -> usize {
        self.rig.mesh.positions.len()
    }

    /// Joints S.
    pub fn joint_count(&self) -> usize {
        self.rig.joints.len()
    }

    /// Node feature width `6 + S`.
    pub fn feature_width(&self) -> usize {
        6 + self.joint_count()
    }

    /// The rig.
    pub fn rig(&self) -> &CharacterRig {
        &self.rig
    }

    /// The whole mesh as a one-graph batch (what [`super::RefineNet`] runs on).
    pub fn batch(&self) -> &GraphBatch {
        &self.graph
    }

    /// The mesh graph (for patches).
    pub fn graph(&self) -> &weft_mesh::Graph {
        self.graph.graph()
    }

    /// The skinning transforms of `pose` with the root at `translation`.
    pub fn transforms(&self, pose: &Pose, translation: [f64; 3]) -> Result<Vec<Rigid>, ModelError> {
        if pose.len() != self.joint_count() {
            return Err(ModelError::mismatch(
                "pose joints",
                self.joint_count().to_string(),
                pose.len(),
            ));
        }
        if let Some(i) = pose.iter().flatten().position(|x| !x.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "pose",
                index: i,
            });
        }
        let pose: Vec<[f64; 3]> = pose.iter().map(|r| r.map(f64::from)).collect();
        self.skeleton
            .skinning_transforms_axis_angle(&self.rig.joints, &pose, translation)
            .map_err(|e| ModelError::Body(e.to_string()))
    }

    /// The rest mesh skinned by `transforms` with the model's influences.
    pub fn coarse(&self, transforms: &[Rigid], method: Skinning) -> Vec<[f64; 3]> {
        match method {
            Skinning::Lbs => lbs(&self.rig.mesh.positions, &self.skin, transforms),
            Skinning::Dqs => dqs(&self.rig.mesh.positions, &self.skin, transforms),
        }
    }

    /// The LBS coarse mesh and node features of `pose` at `translation`.
    pub fn pose_input(
        &self,
        pose: &Pose,
        translation: [f64; 3],
        position: PositionFeature,
    ) -> Result<PoseInput, ModelError> {
        let transforms = self.transforms(pose, translation)?;
        let coarse = self.coarse(&transforms, Skinning::Lbs);
        let first: Vec<[f64; 3]> = match position {
            PositionFeature::Position => coarse.clone(),
            PositionFeature::Descriptor => descriptor_from_transforms(
                &self.rig.mesh.positions,
                &self.descriptor_weights,
                &transforms,
                None,
            )
            .map_err(|e| ModelError::Body(format!("skinning descriptor: {e}")))?,
        };
        let normals = TriMesh {
            positions: coarse.clone(),
            faces: self.rig.mesh.faces.clone(),
        }
        .vertex_normals();
        let s = self.joint_count();
        let w = 6 + s;
        let mut features = vec![0.0f32; self.vertex_count() * w];
        for (i, row) in features.chunks_exact_mut(w).enumerate() {
            for k in 0..3 {
                row[k] = first[i][k] as f32;
                row[3 + k] = normals[i][k] as f32;
            }
            row[6..].copy_from_slice(&self.rig.joint_distances[i * s..(i + 1) * s]);
        }
        Ok(PoseInput { coarse, features })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-triangle strip skinned to two joints.
    pub(crate) fn strip() -> CharacterRig {
        CharacterRig {
            mesh: TriMesh {
                positions: vec![
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [1.0, 1.0, 0.0],
                ],
                faces: vec![[0, 1, 2], [1, 3, 2]],
            },
            weights: vec![1.0, 0.0, 0.7, 0.3, 0.6, 0.4, 0.0, 1.0],
            joints: vec![[0.0; 3], [1.0, 0.0, 0.0]],
            parents: vec![None, Some(0)],
            joint_distances: vec![0.1; 8],
        }
    }

    #[test]
    fn descriptor_ignores_translation_and_positions_do_not() {
        let c = Character::new(strip(), 4).unwrap();
        let pose: Pose = {
            let mut p = [[0.0f32; 3]; 24];
            p[1] = [0.0, 0.0, 0.8];
            p
        };
        // The test rig has 2 joints: a 24-joint pose is refused by name.
        assert!(c
            .pose_input(&pose, [0.0; 3], PositionFeature::Position)
            .is_err());
        let mut rig = strip();
        rig.joints = vec![[0.0; 3]; 24];
        rig.joints[1] = [1.0, 0.0, 0.0];
        rig.parents = std::iter::once(None)
            .chain((1..24).map(|_| Some(0)))
            .collect();
        rig.weights = (0..4)
            .flat_map(|v| {
                let mut row = vec![0.0f32; 24];
                let w1 = [0.0, 0.3, 0.4, 1.0][v];
                row[0] = 1.0 - w1;
                row[1] = w1;
                row
            })
            .collect();
        rig.joint_distances = vec![0.2; 4 * 24];
        let c = Character::new(rig, 4).unwrap();
        let a = c
            .pose_input(&pose, [0.0; 3], PositionFeature::Descriptor)
            .unwrap();
        let b = c
            .pose_input(&pose, [3.0, 1.0, 0.0], PositionFeature::Descriptor)
            .unwrap();
        assert_eq!(a.features, b.features);
        assert_ne!(a.coarse, b.coarse);
        let p = c
            .pose_input(&pose, [0.0; 3], PositionFeature::Position)
            .unwrap();
        let q = c
            .pose_input(&pose, [3.0, 1.0, 0.0], PositionFeature::Position)
            .unwrap();
        assert_ne!(p.features, q.features);
        assert_eq!(p.features.len(), 4 * 30);
    }

    #[test]
    fn bad_rigs_are_refused_by_name() {
        let mut r = strip();
        r.weights.pop();
        assert!(Character::new(r, 4)
            .unwrap_err()
            .to_string()
            .contains("skinning weights"));
        let mut r = strip();
        r.weights[0] = f32::NAN;
        assert!(Character::new(r, 4)
            .unwrap_err()
            .to_string()
            .contains("non-finite"));
        let mut r = strip();
        r.mesh.faces[0][0] = 9;
        assert!(Character::new(r, 4).is_err());
    }
}
