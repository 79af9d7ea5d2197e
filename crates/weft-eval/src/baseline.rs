//! The no-learning baseline of Table 1: the body's skinning weights transferred to the
//! garment (closest body surface point, barycentric; weft-body's `features::transfer`),
//! then linear blend skinning with the body's joint transforms, nothing else.
//!
//! This is what a game engine does with a garment and no learned model, so it is the
//! floor every learned method must beat: it follows the body exactly but has no dynamics,
//! no folds, and it tears loose garments between the legs. Posing uses the same
//! conventions as the simulator and the model (weft-body's
//! `skinning_transforms_axis_angle` about the shaped joints `J(β)`, root translation
//! added after the pelvis rotation), so any error it shows is the garment's, not a frame
//! mismatch.
//!
//! [`PosedBodies`] poses the body surface frame by frame for the collision metric.

use rayon::prelude::*;
use weft_body::features::transfer_weights;
use weft_body::query::BodySurface;
use weft_body::skinning::{lbs, SkinWeights};
use weft_body::{BodyModel, ShapedBody, Skinning};
use weft_mesh::TriMesh;

use crate::error::EvalError;

/// Axis-angle of each of the body's joints for one frame, from SMPL's flat 72 numbers.
fn pose_rows(pose: &[f32; 72]) -> Vec<[f64; 3]> {
    pose.chunks_exact(3)
        .map(|r| [f64::from(r[0]), f64::from(r[1]), f64::from(r[2])])
        .collect()
}

fn check_motion(
    body: &BodyModel,
    poses: &[[f32; 72]],
    trans: &[[f32; 3]],
) -> Result<(), EvalError> {
    if body.joint_count() != 24 {
        return Err(EvalError::Invalid(format!(
            "the body has {} joints; motions hold SMPL's 24 joint rotations per frame",
            body.joint_count()
        )));
    }
    if poses.len() != trans.len() {
        return Err(EvalError::Count {
            what: "root translations vs poses",
            expected: poses.len(),
            found: trans.len(),
        });
    }
    let bad_pose = poses.iter().flatten().position(|x| !x.is_finite());
    let bad_trans = trans.iter().flatten().position(|x| !x.is_finite());
    if let Some(i) = bad_pose {
        return Err(EvalError::Invalid(format!(
            "pose value {} of frame {} is not finite",
            i % 72,
            i / 72
        )));
    }
    if let Some(i) = bad_trans {
        return Err(EvalError::Invalid(format!(
            "root translation of frame {} is not finite",
            i / 3
        )));
    }
    Ok(())
}

fn betas_f64(betas: &[f32]) -> Vec<f64> {
    betas.iter().map(|&b| f64::from(b)).collect()
}

/// A garment skinned to a body by transferred weights.
#[derive(Clone, Debug)]
pub struct LbsBaseline {
    rest: Vec<[f64; 3]>,
    weights: SkinWeights,
    shaped: ShapedBody,
}

impl LbsBaseline {
    /// Transfers `body`'s weights (at shape `betas`, rest pose) to `garment`, which must
    /// be in that same rest pose (a dataset's rest garment, or a garment fitted to the
    /// body).
    pub fn new(garment: &TriMesh, body: &BodyModel, betas: &[f32]) -> Result<Self, EvalError> {
        let shaped = body.shaped(&betas_f64(betas))?;
        let surface = body.body_surface(&shaped.vertices)?;
        let t = transfer_weights(&surface, &body.skinning_weights()?, &garment.positions)?;
        let weights = SkinWeights::from_dense(t.weights.as_slice(), t.weights.joint_count());
        Ok(LbsBaseline {
            rest: garment.positions.clone(),
            weights,
            shaped,
        })
    }

    /// Garment vertices of every frame of the motion `poses`/`trans` (in parallel over
    /// frames).
    pub fn animate(
        &self,
        body: &BodyModel,
        poses: &[[f32; 72]],
        trans: &[[f32; 3]],
    ) -> Result<Vec<Vec<[f32; 3]>>, EvalError> {
        check_motion(body, poses, trans)?;
        poses
            .par_iter()
            .zip(trans)
            .map(|(pose, t)| {
                let a = body.skeleton().skinning_transforms_axis_angle(
                    &self.shaped.joints,
                    &pose_rows(pose),
                    t.map(f64::from),
                );
                let a = a.map_err(|e| EvalError::Body(e.into()))?;
                Ok(lbs(&self.rest, &self.weights, &a)
                    .into_iter()
                    .map(|p| p.map(|x| x as f32))
                    .collect())
            })
            .collect()
    }
}

/// The body surface posed at each frame of a motion, for collision checks.
pub struct PosedBodies {
    frames: Vec<Vec<[f32; 3]>>,
    faces: Vec<[u32; 3]>,
}

impl PosedBodies {
    /// Poses `body` at shape `betas` for every frame (LBS with the model's pose blend
    /// shapes, as the simulator saw it).
    pub fn new(
        body: &BodyModel,
        betas: &[f32],
        poses: &[[f32; 72]],
        trans: &[[f32; 3]],
    ) -> Result<Self, EvalError> {
        check_motion(body, poses, trans)?;
        let shaped = body.shaped(&betas_f64(betas))?;
        let rows: Vec<Vec<[f32; 3]>> = poses
            .iter()
            .map(|p| p.chunks_exact(3).map(|r| [r[0], r[1], r[2]]).collect())
            .collect();
        let frames = body.pose_frames(&shaped, &rows, trans, Skinning::Lbs)?;
        Ok(PosedBodies {
            frames,
            faces: body.faces().to_vec(),
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The query surface of frame `t`.
    pub fn surface(&self, t: usize) -> Result<BodySurface, EvalError> {
        let frame = self.frames.get(t).ok_or(EvalError::Count {
            what: "posed body frame index vs frames",
            expected: self.frames.len(),
            found: t,
        })?;
        let p: Vec<[f64; 3]> = frame.iter().map(|v| v.map(f64::from)).collect();
        Ok(BodySurface::new(&p, &self.faces)?)
    }

    /// The posed body mesh of frame `t` (for pictures).
    pub fn mesh(&self, t: usize) -> Option<TriMesh> {
        self.frames.get(t).map(|f| {
            TriMesh::new(
                f.iter().map(|v| v.map(f64::from)).collect(),
                self.faces.clone(),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_body::motion::{generate, MotionKind, ProceduralParams};

    fn flat(motion: &weft_body::motion::Motion) -> (Vec<[f32; 72]>, Vec<[f32; 3]>) {
        let poses = motion
            .poses()
            .iter()
            .map(|p| {
                let mut out = [0.0f32; 72];
                for (j, r) in p.iter().enumerate() {
                    out[3 * j..3 * j + 3].copy_from_slice(r);
                }
                out
            })
            .collect();
        (poses, motion.trans().to_vec())
    }

    #[test]
    fn body_vertices_as_garment_follow_the_body() {
        // A "garment" made of body vertices themselves: transferred weights are the
        // body's own, so LBS reproduces the posed body (up to pose blend shapes, which
        // the default body does not have or which are small).
        let body = weft_body::default_body().unwrap();
        let betas = [0.5f32, -0.3];
        let shaped = body.shaped(&betas_f64(&betas)).unwrap();
        let idx: Vec<usize> = (0..shaped.vertices.len()).step_by(97).collect();
        let garment = TriMesh::new(idx.iter().map(|&i| shaped.vertices[i]).collect(), vec![]);
        let base = LbsBaseline::new(&garment, &body, &betas).unwrap();
        let mut params = ProceduralParams::new(MotionKind::parse("walk").unwrap());
        params.frames = 6;
        let motion = generate(&params).unwrap();
        let (poses, trans) = flat(&motion);
        let frames = base.animate(&body, &poses, &trans).unwrap();
        let posed = PosedBodies::new(&body, &betas, &poses, &trans).unwrap();
        assert_eq!((frames.len(), posed.len()), (6, 6));
        let mut worst = 0.0f64;
        for (t, frame) in frames.iter().enumerate() {
            for (k, &i) in idx.iter().enumerate() {
                let d: f64 = (0..3)
                    .map(|c| f64::from(frame[k][c] - posed.frames[t][i][c]).powi(2))
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
        assert!(posed.surface(5).is_ok() && posed.surface(6).is_err());
    }

    #[test]
    fn bad_motion_is_an_error() {
        let body = weft_body::default_body().unwrap();
        let garment = TriMesh::new(vec![[0.0, 1.0, 0.1]], vec![]);
        let base = LbsBaseline::new(&garment, &body, &[]).unwrap();
        assert!(base.animate(&body, &[[0.0; 72]; 2], &[[0.0; 3]]).is_err());
        assert!(base.animate(&body, &[[f32::NAN; 72]], &[[0.0; 3]]).is_err());
    }
}
