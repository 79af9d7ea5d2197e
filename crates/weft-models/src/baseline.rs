//! The no-learning baselines of Table 1: the body's skinning weights transferred to the
//! garment (closest body surface point, barycentric; weft-body's `features::transfer`),
//! then linear blend skinning (LBS) or dual-quaternion skinning (DQS) with the body's
//! joint transforms, nothing else.
//!
//! This is what a game engine does with a garment and no learned model, so it is the
//! floor every learned method must beat: it follows the body exactly but has no dynamics,
//! no folds, and it tears loose garments between the legs. Posing uses the same
//! conventions as the simulator and the models (weft-body's
//! `skinning_transforms_axis_angle` about the shaped joints `J(β)`, root translation
//! added after the pelvis rotation), so any error it shows is the garment's, not a frame
//! mismatch.

use std::collections::BTreeMap;

use rayon::prelude::*;
use weft_body::features::{transfer_weights, transfer_weights_diffused, DiffusionParams};
use weft_body::skinning::{skin, SkinWeights};
use weft_body::{BodyModel, ShapedBody, Skinning};
use weft_mesh::TriMesh;

use crate::deformer::{Clip, Deformer, Frames};
use crate::error::{body_err, ModelError};
use crate::kind::ModelKind;

/// Name of the LBS baseline in tables.
pub const LBS_NAME: &str = "LBS only";
/// Name of the DQS baseline in tables.
pub const DQS_NAME: &str = "DQS only";

/// A skinning baseline: [`Skinning::Lbs`] or [`Skinning::Dqs`] with transferred weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SkinningBaseline(pub Skinning);

/// A garment bound to one body shape by transferred weights.
#[derive(Clone, Debug)]
pub struct SkinnedGarment {
    rest: Vec<[f64; 3]>,
    weights: SkinWeights,
    shaped: ShapedBody,
}

impl SkinnedGarment {
    /// Transfers `body`'s weights (at shape `betas`, rest pose) to `garment`, which must
    /// be in that same rest pose (a dataset's rest garment, or a garment fitted to the
    /// body).
    pub fn new(garment: &TriMesh, body: &BodyModel, betas: &[f32]) -> Result<Self, ModelError> {
        Self::bind(garment, body, betas, false)
    }

    /// [`SkinnedGarment::new`] with the transferred weights diffused over the garment
    /// (weft-body's `transfer_weights_diffused`): a loose skirt's hem blends both legs and
    /// the pelvis instead of tearing between them. HOOD starts its rollouts from this.
    pub fn diffused(
        garment: &TriMesh,
        body: &BodyModel,
        betas: &[f32],
    ) -> Result<Self, ModelError> {
        Self::bind(garment, body, betas, true)
    }

    fn bind(
        garment: &TriMesh,
        body: &BodyModel,
        betas: &[f32],
        diffused: bool,
    ) -> Result<Self, ModelError> {
        let betas: Vec<f64> = betas.iter().map(|&b| f64::from(b)).collect();
        let shaped = body.shaped(&betas).map_err(body_err("shaping the body"))?;
        let surface = body
            .body_surface(&shaped.vertices)
            .map_err(|e| body_err("the body surface")(e.into()))?;
        let feature = |what: &str| {
            let what = what.to_string();
            move |source| ModelError::Feature {
                what,
                source: Box::new(source),
            }
        };
        let weights = body
            .skinning_weights()
            .map_err(feature("the body's skinning weights"))?;
        let t = if diffused {
            transfer_weights_diffused(&surface, &weights, garment, &DiffusionParams::default())
        } else {
            transfer_weights(&surface, &weights, &garment.positions)
        }
        .map_err(feature("transferring skinning weights to the garment"))?;
        Ok(SkinnedGarment {
            rest: garment.positions.clone(),
            weights: SkinWeights::from_dense(t.weights.as_slice(), t.weights.joint_count()),
            shaped,
        })
    }

    /// The garment at every frame of `clip` skinned by `method` (in parallel over frames).
    pub fn animate(
        &self,
        body: &BodyModel,
        clip: &Clip,
        method: Skinning,
    ) -> Result<Frames, ModelError> {
        clip.check()?;
        clip.poses
            .par_iter()
            .zip(clip.trans)
            .map(|(pose, t)| {
                let rows: Vec<[f64; 3]> = pose.iter().map(|r| r.map(f64::from)).collect();
                let a = body
                    .skeleton()
                    .skinning_transforms_axis_angle(&self.shaped.joints, &rows, t.map(f64::from))
                    .map_err(|e| body_err("joint transforms")(e.into()))?;
                Ok(skin(method, &self.rest, &self.weights, &a)
                    .into_iter()
                    .map(|p| p.map(|x| x as f32))
                    .collect())
            })
            .collect()
    }
}

impl SkinningBaseline {
    /// LBS with transferred weights.
    pub const LBS: SkinningBaseline = SkinningBaseline(Skinning::Lbs);
    /// DQS with transferred weights.
    pub const DQS: SkinningBaseline = SkinningBaseline(Skinning::Dqs);
}

impl Deformer for SkinningBaseline {
    fn name(&self) -> String {
        match self.0 {
            Skinning::Lbs => LBS_NAME,
            Skinning::Dqs => DQS_NAME,
        }
        .to_string()
    }

    fn kind(&self) -> Option<ModelKind> {
        None
    }

    fn variant(&self) -> BTreeMap<String, String> {
        BTreeMap::from([
            (
                "skinning".to_string(),
                match self.0 {
                    Skinning::Lbs => "lbs",
                    Skinning::Dqs => "dqs",
                }
                .to_string(),
            ),
            ("weights".to_string(), "transferred".to_string()),
        ])
    }

    fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError> {
        SkinnedGarment::new(garment, body, clip.betas)?.animate(body, clip, self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_body::PosedSequence;

    fn walk(frames: usize) -> (Vec<weft_body::Pose>, Vec<[f32; 3]>) {
        let poses: Vec<weft_body::Pose> = (0..frames)
            .map(|t| {
                let mut p = [[0.0f32; 3]; 24];
                p[1] = [0.4 * (t as f32 * 0.7).sin(), 0.0, 0.0];
                p[2] = [-0.4 * (t as f32 * 0.7).sin(), 0.0, 0.0];
                p[18] = [0.0, 0.0, 0.3 * t as f32];
                p
            })
            .collect();
        let trans = (0..frames).map(|t| [0.0, 0.0, 0.02 * t as f32]).collect();
        (poses, trans)
    }

    #[test]
    fn body_vertices_as_garment_follow_the_body() {
        // A "garment" made of body vertices themselves: transferred weights are the
        // body's own, so LBS reproduces the posed body (up to pose blend shapes, which
        // the default body does not have or which are small).
        let body = weft_body::default_body().unwrap();
        let betas = [0.5f32, -0.3];
        let shaped = body.shaped(&[0.5, -0.3]).unwrap();
        let idx: Vec<usize> = (0..shaped.vertices.len()).step_by(97).collect();
        let garment = TriMesh::new(idx.iter().map(|&i| shaped.vertices[i]).collect(), vec![]);
        let (poses, trans) = walk(6);
        let clip = Clip {
            betas: &betas,
            poses: &poses,
            trans: &trans,
            fps: 30.0,
        };
        let frames = SkinningBaseline::LBS
            .animate(&garment, &body, &clip)
            .unwrap();
        let posed = PosedSequence::new(&body, &betas, &poses, &trans).unwrap();
        assert_eq!((frames.len(), posed.len()), (6, 6));
        let mut worst = 0.0f64;
        for (t, frame) in frames.iter().enumerate() {
            let truth = posed.frame(t).unwrap();
            for (k, &i) in idx.iter().enumerate() {
                let d: f64 = (0..3)
                    .map(|c| f64::from(frame[k][c] - truth[i][c]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                worst = worst.max(d);
            }
        }
        let tol = if body.has_pose_blend_shapes() {
            0.03
        } else {
            1e-4
        };
        assert!(worst < tol, "worst distance {worst} m");
        // DQS differs from LBS where joints bend, but stays close to the body.
        let dqs = SkinningBaseline::DQS
            .animate(&garment, &body, &clip)
            .unwrap();
        let diff = dqs[5]
            .iter()
            .zip(&frames[5])
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0f32, f32::max))
            .fold(0.0f32, f32::max);
        assert!(diff > 1e-5 && diff < 0.1, "DQS vs LBS: {diff} m");
        assert_ne!(SkinningBaseline::LBS.name(), SkinningBaseline::DQS.name());
        assert_eq!(SkinningBaseline::DQS.variant()["skinning"], "dqs");
    }

    #[test]
    fn bad_motion_is_an_error() {
        let body = weft_body::default_body().unwrap();
        let garment = TriMesh::new(vec![[0.0, 1.0, 0.1]], vec![]);
        let (poses, trans) = walk(2);
        let short = Clip {
            betas: &[],
            poses: &poses,
            trans: &trans[..1],
            fps: 30.0,
        };
        assert!(SkinningBaseline::LBS
            .animate(&garment, &body, &short)
            .is_err());
        let mut nan = poses.clone();
        nan[1][4][2] = f32::NAN;
        let bad = Clip {
            betas: &[],
            poses: &nan,
            trans: &trans,
            fps: 30.0,
        };
        let e = SkinningBaseline::LBS
            .animate(&garment, &body, &bad)
            .unwrap_err();
        assert!(
            matches!(e, ModelError::NonFinite { what: "poses", .. }),
            "{e}"
        );
    }
}
