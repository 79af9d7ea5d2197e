//! A rigged character ready for learned refinement: rest mesh, skinning weights cut to
//! the model's influence count, skeleton, mesh graph, and the per-vertex inputs that do
//! not change with the pose (seed 001 §3.2.1's volumetric joint distances `x_i`).
//!
//! Per pose it gives the coarse mesh (LBS with the top-k influences renormalised, as
//! eq. 3.1, or DQS with the same influences) and the node features `[p_i | r_i(θ), n_i, x_i]` the networks read (§3.2.1, §3.3.1):
//! positions and normals of the coarse mesh (thesis-reference D8: the graph is built on
//! `M_coarse`), or in place of positions the relative skinning descriptor of eq. 3.9,
//! which is LBS without translations and so does not change when the character moves.
//!
//! Features and corrections are written in world axes (the thesis) or, with
//! [`Frame::Skinning`], in each vertex's DQS frame: see [`Frame`].

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use weft_body::features::body::descriptor_from_transforms;
use weft_body::features::weights::SkinningWeights;
use weft_body::kinematics::{Rigid, Skeleton};
use weft_body::skinning::{dqs, dqs_frames, lbs, SkinWeights};
use weft_body::{Pose, Skinning};
use weft_mesh::TriMesh;
use weft_nn::GraphBatch;

use super::CM_PER_M;
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

/// The frame in which a vertex's features are read and its correction predicted.
///
/// In world axes (the thesis) the correction of a bent elbow points another way for
/// every orientation of the upper arm, so the network must learn each joint's
/// correction once per orientation of its parent chain, which a few hundred poses
/// cannot teach. In the vertex's own DQS frame (the rigid transform dual quaternion
/// skinning gives it: smooth over the mesh, the bone's own transform where one bone
/// dominates) the correction depends only on how the neighbouring bones turn relative
/// to each other, as per-bone local offsets do in Bailey et al. 2018 (fast deep
/// deformation approximations). Position features then also ignore where the character
/// stands and how it is turned (Fig. 3.23's test).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// World axes: features and corrections as the thesis writes them (the default of a
    /// run whose config names no frame).
    #[default]
    World,
    /// Each vertex's DQS frame: positions `R_iᵀ (p_i − t_i)`, descriptors and normals
    /// `R_iᵀ v`, corrections predicted as `δ_i` and applied as `R_i δ_i`.
    Skinning,
}

/// How a model reads a pose: the coarse deformation it corrects, what stands in for
/// positions, and the frame (its config's `coarse`, `position` and `frame`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InputSpec {
    /// The coarse skinning, LBS (eq. 3.1) or DQS.
    pub coarse: Skinning,
    /// What stands in for positions in the node features.
    pub position: PositionFeature,
    /// The frame of the features and corrections.
    pub frame: Frame,
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
    /// Each vertex's frame rotation `R_i` ([`Frame::Skinning`]); empty in world axes.
    pub rotations: Vec<Matrix3<f64>>,
}

impl PoseInput {
    /// The correction from the coarse mesh to `truth` in centimetres, row-major
    /// `N × 3`, in the frame the features are in (the network's target).
    pub fn target_cm(&self, truth: &[[f32; 3]]) -> Vec<f32> {
        let mut out = Vec::with_capacity(3 * self.coarse.len());
        for (i, (t, c)) in truth.iter().zip(&self.coarse).enumerate() {
            let d = Vector3::from(std::array::from_fn(|k| f64::from(t[k]) - c[k])) * CM_PER_M;
            let d = match self.rotations.get(i) {
                Some(r) => r.transpose() * d,
                None => d,
            };
            out.extend(d.iter().map(|&x| x as f32));
        }
        out
    }

    /// The coarse mesh plus the network's corrections `delta_cm` (centimetres, row-major
    /// `N × 3`, in the features' frame).
    pub fn corrected(&self, delta_cm: &[f32]) -> Vec<[f64; 3]> {
        self.coarse
            .iter()
            .zip(delta_cm.chunks_exact(3))
            .enumerate()
            .map(|(i, (c, d))| {
                let d = Vector3::new(f64::from(d[0]), f64::from(d[1]), f64::from(d[2])) / CM_PER_M;
                let d = match self.rotations.get(i) {
                    Some(r) => r * d,
                    None => d,
                };
                std::array::from_fn(|k| c[k] + d[k])
            })
            .collect()
    }
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

    /// The coarse mesh and node features of `pose` at `translation`, as `spec` reads
    /// them.
    pub fn pose_input(
        &self,
        pose: &Pose,
        translation: [f64; 3],
        spec: InputSpec,
    ) -> Result<PoseInput, ModelError> {
        let InputSpec {
            coarse,
            position,
            frame,
        } = spec;
        let transforms = self.transforms(pose, translation)?;
        let coarse = self.coarse(&transforms, coarse);
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
        let frames = match frame {
            Frame::World => Vec::new(),
            Frame::Skinning => dqs_frames(&self.skin, &transforms),
        };
        let s = self.joint_count();
        let w = 6 + s;
        let mut features = vec![0.0f32; self.vertex_count() * w];
        for (i, row) in features.chunks_exact_mut(w).enumerate() {
            let (mut p, mut n) = (Vector3::from(first[i]), Vector3::from(normals[i]));
            if let Some(f) = frames.get(i) {
                let rt = f.rotation.transpose();
                // Positions also lose the frame's translation; the descriptor has none.
                if position == PositionFeature::Position {
                    p -= f.translation;
                }
                p = rt * p;
                n = rt * n;
            }
            for k in 0..3 {
                row[k] = p[k] as f32;
                row[3 + k] = n[k] as f32;
            }
            row[6..].copy_from_slice(&self.rig.joint_distances[i * s..(i + 1) * s]);
        }
        Ok(PoseInput {
            coarse,
            features,
            rotations: frames.into_iter().map(|f| f.rotation).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LBS-coarse inputs reading `position` in `frame`.
    fn spec(position: PositionFeature, frame: Frame) -> InputSpec {
        InputSpec {
            coarse: Skinning::Lbs,
            position,
            frame,
        }
    }

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
            .pose_input(
                &pose,
                [0.0; 3],
                spec(PositionFeature::Position, Frame::World)
            )
            .is_err());
        let c = Character::new(strip24(), 4).unwrap();
        let a = c
            .pose_input(
                &pose,
                [0.0; 3],
                spec(PositionFeature::Descriptor, Frame::World),
            )
            .unwrap();
        let b = c
            .pose_input(
                &pose,
                [3.0, 1.0, 0.0],
                spec(PositionFeature::Descriptor, Frame::World),
            )
            .unwrap();
        assert_eq!(a.features, b.features);
        assert_ne!(a.coarse, b.coarse);
        let p = c
            .pose_input(
                &pose,
                [0.0; 3],
                spec(PositionFeature::Position, Frame::World),
            )
            .unwrap();
        let q = c
            .pose_input(
                &pose,
                [3.0, 1.0, 0.0],
                spec(PositionFeature::Position, Frame::World),
            )
            .unwrap();
        assert_ne!(p.features, q.features);
        assert_eq!(p.features.len(), 4 * 30);
        // A DQS-coarse model corrects (and reads the positions and normals of) DQS.
        let d = c
            .pose_input(
                &pose,
                [0.0; 3],
                InputSpec {
                    coarse: Skinning::Dqs,
                    ..spec(PositionFeature::Position, Frame::World)
                },
            )
            .unwrap();
        let transforms = c.transforms(&pose, [0.0; 3]).unwrap();
        assert_eq!(d.coarse, c.coarse(&transforms, Skinning::Dqs));
        assert_ne!(d.coarse, p.coarse);
        for (row, x) in d.features.chunks_exact(30).zip(&d.coarse) {
            assert!((0..3).all(|k| (row[k] - x[k] as f32).abs() < 1e-6));
        }
    }

    /// The strip's rig on a 24-joint skeleton (joint 1 at x = 1), weights ramping from
    /// joint 0 to joint 1.
    fn strip24() -> CharacterRig {
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
        rig
    }

    #[test]
    fn skinning_frame_features_ignore_how_the_character_is_placed_and_round_trip() {
        let c = Character::new(strip24(), 4).unwrap();
        let mut pose = [[0.0f32; 3]; 24];
        pose[1] = [0.3, 0.0, 0.8];
        let mut turned = pose;
        turned[0] = [0.4, -1.1, 0.7];
        for position in [PositionFeature::Position, PositionFeature::Descriptor] {
            let a = c
                .pose_input(&pose, [0.0; 3], spec(position, Frame::Skinning))
                .unwrap();
            let b = c
                .pose_input(&turned, [3.0, 1.0, -2.0], spec(position, Frame::Skinning))
                .unwrap();
            for (x, y) in a.features.iter().zip(&b.features) {
                assert!((x - y).abs() < 1e-5, "{position:?}: {x} vs {y}");
            }
            // The world-axes features do change when the root turns.
            let w = c
                .pose_input(&pose, [0.0; 3], spec(position, Frame::World))
                .unwrap();
            let v = c
                .pose_input(&turned, [0.0; 3], spec(position, Frame::World))
                .unwrap();
            assert!(w
                .features
                .iter()
                .zip(&v.features)
                .any(|(x, y)| (x - y).abs() > 1e-2));
            // A vertex with one bone reads its rest position in its frame (the descriptor
            // too: it is that bone's rotation of the rest position).
            assert!(
                (0..3).all(|k| (a.features[k] - c.rig().mesh.positions[0][k] as f32).abs() < 1e-6),
                "{position:?}"
            );
        }
        // Targets and corrections: the same world offset whichever the frame, its length
        // kept, its direction turned into the vertex's frame.
        let targets: Vec<Vec<f32>> = [Frame::World, Frame::Skinning]
            .into_iter()
            .map(|frame| {
                let input = c
                    .pose_input(
                        &turned,
                        [3.0, 1.0, -2.0],
                        spec(PositionFeature::Position, frame),
                    )
                    .unwrap();
                let truth: Vec<[f32; 3]> = input
                    .coarse
                    .iter()
                    .enumerate()
                    .map(|(i, p)| {
                        std::array::from_fn(|k| (p[k] + 0.01 * (1 + i + k) as f64) as f32)
                    })
                    .collect();
                let target = input.target_cm(&truth);
                for (back, t) in input.corrected(&target).iter().zip(&truth) {
                    assert!(
                        (0..3).all(|k| (back[k] - f64::from(t[k])).abs() < 1e-5),
                        "{frame:?}"
                    );
                }
                target
            })
            .collect();
        for (w, s) in targets[0].chunks(3).zip(targets[1].chunks(3)) {
            let len = |v: &[f32]| v.iter().map(|x| x * x).sum::<f32>().sqrt();
            assert!((len(w) - len(s)).abs() < 1e-4);
            assert!(w.iter().zip(s).any(|(x, y)| (x - y).abs() > 1e-2));
        }
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
