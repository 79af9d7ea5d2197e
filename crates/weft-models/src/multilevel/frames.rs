//! [`FrameInputs`]: the per-frame inputs of a window of `T` frames, computed on the host.
//!
//! - Θᵗ (E^t1): `m` frames of 24 axis-angles and the root displacement from the previous
//!   frame (weft-body `motion::pose_history`), the displacement multiplied by the frame
//!   rate so that it is a velocity in m/s: the same motion at 30 and 60 fps then gives the
//!   same input. Oldest frame first, the order an LSTM reads.
//! - Vᵗ (E^t2): velocities (m/s, backward differences, weft-body
//!   `features::velocity_window`) of the `body_samples` body vertices that E^bs samples,
//!   over the same `m` frames, oldest first.
//! - The joint skinning transforms `A_j(θ_t) = G_j · T(−J_j)` of every frame, 3 × 4 row
//!   major, for the final linear blend skinning of the garment.
//! - With `body_contact`, the garment's contact with the posed body of every frame
//!   ([`super::contact`]).

use std::ops::Range;

use weft_body::features::velocity_window;
use weft_body::query::MovingSurface;
use weft_body::skinning::Skinning;
use weft_body::BodyModel;
use weft_motion::{pose_history, Motion, Pose};

use super::config::MultilevelConfig;
use super::contact::{contact_features, CONTACT_FEATURES};
use super::garment::{betas_f64, body_sample_indices, check_body, GarmentInput};
use crate::deformer::Clip;
use crate::error::ModelError;

/// Numbers per frame of the pose history: 24 axis-angles and the root velocity.
pub const POSE_FEATURES: usize = weft_motion::HISTORY_FEATURES;

/// Per-frame inputs of a window of frames; see the module documentation.
#[derive(Clone, Debug)]
pub struct FrameInputs {
    frames: usize,
    history: usize,
    joints: usize,
    samples: usize,
    /// The motion frames this window covers.
    pub range: Range<usize>,
    /// `[T, m, 75]`, oldest history frame first.
    pub poses: Vec<f32>,
    /// `[T, m, 3·body_samples]`, oldest first.
    pub velocities: Vec<f32>,
    /// `[T, S, 12]`: per joint `[R | t]` row-major.
    pub transforms: Vec<f32>,
    /// `[T, N, 4]` with `body_contact` ([`super::contact`]), else `None`.
    pub contact: Option<Vec<f32>>,
}

impl FrameInputs {
    /// The inputs of motion frames `frames` of `clip` (a non-empty range of
    /// `0..clip.len()`) for the garment `garment` (read only with `body_contact`).
    ///
    /// Errors: a body whose joint count is not the config's (a motion of another
    /// skeleton: poses are SMPL's 24 joints), `poses` and `trans` of different lengths, an
    /// empty or out-of-range window, a non-positive frame rate, non-finite poses,
    /// translations or betas.
    pub fn new(
        body: &BodyModel,
        garment: &GarmentInput,
        clip: &Clip,
        frames: Range<usize>,
        cfg: &MultilevelConfig,
    ) -> Result<Self, ModelError> {
        let Clip {
            betas,
            poses,
            trans,
            fps,
        } = *clip;
        cfg.validate()?;
        check_body(body, cfg)?;
        if cfg.joints != 24 {
            return Err(ModelError::mismatch(
                "motion skeleton joints (poses hold 24 SMPL joints; config joints)",
                cfg.joints,
                24,
            ));
        }
        if poses.len() != trans.len() {
            return Err(ModelError::mismatch(
                "root translations (one per pose)",
                poses.len(),
                trans.len(),
            ));
        }
        if frames.start >= frames.end || frames.end > poses.len() {
            return Err(ModelError::mismatch(
                "frame window",
                format!("a non-empty range within 0..{}", poses.len()),
                format!("{frames:?}"),
            ));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(ModelError::mismatch("frame rate", "a positive number", fps));
        }
        let m = cfg.history;
        let first = frames.start.saturating_sub(m);
        // Only the frames the window and its history need.
        let local_poses: Vec<Pose> = poses[first..frames.end].to_vec();
        let local_trans = trans[first..frames.end].to_vec();
        for (what, values) in [
            (
                "poses",
                local_poses
                    .iter()
                    .flatten()
                    .flatten()
                    .copied()
                    .collect::<Vec<_>>(),
            ),
            (
                "root translations",
                local_trans.iter().flatten().copied().collect(),
            ),
        ] {
            crate::error::check_finite(what, &values)?;
        }
        let motion = Motion::new(fps, local_poses.clone(), local_trans.clone(), None)
            .map_err(|e| ModelError::Body(format!("motion: {e}")))?;
        let shaped = body
            .shaped(&betas_f64(betas)?)
            .map_err(crate::error::body_err("shaping the body"))?;

        let t_count = frames.len();
        let fps32 = fps as f32;
        let mut pose_out = Vec::with_capacity(t_count * m * POSE_FEATURES);
        for t in frames.clone() {
            let rows = pose_history(&motion, t - first, m)
                .map_err(|e| ModelError::Body(format!("pose history: {e}")))?;
            for row in rows.iter().rev() {
                let mut row = *row;
                for x in &mut row[POSE_FEATURES - 3..] {
                    *x *= fps32;
                }
                pose_out.extend_from_slice(&row);
            }
        }

        // Body velocities of the sampled vertices.
        let idx = body_sample_indices(shaped.vertices.len(), cfg.body_samples)?;
        let posed = body
            .pose_frames(&shaped, &local_poses, &local_trans, Skinning::Lbs)
            .map_err(|e| ModelError::Body(format!("posing the body: {e}")))?;
        let sampled: Vec<Vec<[f64; 3]>> = posed
            .iter()
            .map(|frame| idx.iter().map(|&i| frame[i].map(f64::from)).collect())
            .collect();
        let mut vel_out = Vec::with_capacity(t_count * m * 3 * idx.len());
        for t in frames.clone() {
            let w = velocity_window(&sampled, fps, t - first, m)
                .map_err(|e| ModelError::Body(format!("body velocities: {e}")))?;
            for k in (0..m).rev() {
                vel_out.extend(w.frame(k).iter().flat_map(|v| v.map(|x| x as f32)));
            }
        }

        // Skinning transforms of each frame.
        let mut transforms = Vec::with_capacity(t_count * cfg.joints * 12);
        for t in frames.clone() {
            let pose: Vec<[f64; 3]> = local_poses[t - first]
                .iter()
                .map(|r| r.map(f64::from))
                .collect();
            let a = body
                .skeleton()
                .skinning_transforms_axis_angle(
                    &shaped.joints,
                    &pose,
                    local_trans[t - first].map(f64::from),
                )
                .map_err(|e| ModelError::Body(format!("joint transforms: {e}")))?;
            for r in &a {
                for i in 0..3 {
                    for j in 0..3 {
                        transforms.push(r.rotation[(i, j)] as f32);
                    }
                    transforms.push(r.translation[i] as f32);
                }
            }
        }
        crate::error::check_finite("body velocities", &vel_out)?;

        let contact = if cfg.body_contact {
            let (n, s) = (garment.vertex_count(), cfg.joints);
            if garment.joint_count() != s {
                return Err(ModelError::mismatch(
                    "garment input joints (config joints)",
                    s,
                    garment.joint_count(),
                ));
            }
            let mut out = Vec::with_capacity(t_count * n * CONTACT_FEATURES);
            let surface_err = |e| ModelError::Body(format!("posed body surface: {e}"));
            let mut surface = MovingSurface::new(body.faces());
            for (k, t) in frames.clone().enumerate() {
                let surface = surface.frame(&posed[t - first]).map_err(surface_err)?;
                contact_features(
                    &garment.rest,
                    &garment.transfer_weights,
                    &transforms[k * s * 12..(k + 1) * s * 12],
                    surface,
                    cfg.contact_radius,
                    &mut out,
                )?;
            }
            crate::error::check_finite("body contact", &out)?;
            Some(out)
        } else {
            None
        };
        Ok(FrameInputs {
            frames: t_count,
            history: m,
            joints: cfg.joints,
            samples: idx.len(),
            range: frames,
            poses: pose_out,
            velocities: vel_out,
            transforms,
            contact,
        })
    }

    /// Frames `T` in the window.
    pub fn frame_count(&self) -> usize {
        self.frames
    }

    /// History length `m`.
    pub fn history(&self) -> usize {
        self.history
    }

    /// Joints `S` of the transforms.
    pub fn joint_count(&self) -> usize {
        self.joints
    }

    /// Sampled body vertices of the velocities.
    pub fn body_sample_count(&self) -> usize {
        self.samples
    }
}
