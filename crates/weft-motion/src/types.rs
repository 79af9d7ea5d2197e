//! The [`Motion`] type: a frame rate, one SMPL pose and one root translation per frame,
//! and optionally the shape β the motion was captured on.

use nalgebra::Vector3;

use super::error::MotionError;
use super::rot::quat;
use weft_body::joints::SMPL_JOINT_NAMES;
use weft_body::Pose;

/// The largest motion weft builds in memory: 10 million frames, about 3 GB of poses
/// (an hour of 120 fps capture is 432 000 frames). Readers and generators refuse longer
/// motions before allocating.
pub const MAX_FRAMES: usize = 10_000_000;

/// The highest frame rate a motion may have. Optical capture runs at 60 to 480 Hz and
/// high-speed systems rarely above 1 000; a larger rate in a file is a damaged header
/// (or seconds per frame read as frames per second), and would make time steps too small
/// for the simulator to mean anything.
pub const MAX_FPS: f64 = 1000.0;

/// A body motion in SMPL's parametrisation.
///
/// Conventions (those of the SMPL model itself, which weft keeps everywhere):
/// right-handed, **Y up, metres, seconds**; in the rest pose the body faces +Z and its
/// left side is +X. Frame `t` has the pose `poses[t]` and the root translation
/// `trans[t]`: the pelvis rotation `poses[t][0]` turns the body about its rest pelvis
/// joint J₀, and `trans[t]` is added afterwards, so the posed pelvis lies at
/// `J₀ + trans[t]`. A motion is therefore tied to a body only through J₀ (and β, when
/// [`betas`](Self::betas) records the shape it was captured on).
///
/// Invariants, checked by [`Motion::new`]: at least one frame and at most
/// [`MAX_FRAMES`], as many translations as poses, a finite positive frame rate, and
/// finite numbers everywhere.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    fps: f64,
    poses: Vec<Pose>,
    trans: Vec<[f32; 3]>,
    betas: Option<Vec<f32>>,
}

/// How far apart two motions are (see [`Motion::distance`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionDistance {
    /// The largest angle (radians) between corresponding joint rotations.
    pub rotation: f64,
    /// The largest distance (metres) between corresponding root translations.
    pub translation: f64,
}

impl Motion {
    /// A motion from its arrays; fails with [`MotionError::Invalid`] naming the first
    /// frame, joint or value that breaks an invariant.
    pub fn new(
        fps: f64,
        poses: Vec<Pose>,
        trans: Vec<[f32; 3]>,
        betas: Option<Vec<f32>>,
    ) -> Result<Self, MotionError> {
        if !(fps.is_finite() && fps > 0.0 && fps <= MAX_FPS) {
            return Err(MotionError::Invalid(format!(
                "frame rate {fps}; expected frames per second above 0 and at most {MAX_FPS}"
            )));
        }
        if poses.is_empty() {
            return Err(MotionError::Invalid(
                "no frames; expected at least one pose".into(),
            ));
        }
        if poses.len() > MAX_FRAMES {
            return Err(MotionError::Invalid(format!(
                "{} frames; at most {MAX_FRAMES} fit in memory",
                poses.len()
            )));
        }
        if poses.len() != trans.len() {
            return Err(MotionError::Invalid(format!(
                "{} poses but {} root translations; expected one of each per frame",
                poses.len(),
                trans.len()
            )));
        }
        for (t, pose) in poses.iter().enumerate() {
            for (j, r) in pose.iter().enumerate() {
                if r.iter().any(|x| !x.is_finite()) {
                    return Err(MotionError::Invalid(format!(
                        "frame {t}, joint {j} ({}): rotation {r:?} is not finite",
                        SMPL_JOINT_NAMES[j]
                    )));
                }
            }
        }
        if let Some(t) = trans.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(MotionError::Invalid(format!(
                "frame {t}: root translation {:?} is not finite",
                trans[t]
            )));
        }
        if let Some(b) = &betas {
            if let Some(i) = b.iter().position(|x| !x.is_finite()) {
                return Err(MotionError::Invalid(format!("beta {i} is not finite")));
            }
        }
        Ok(Motion {
            fps,
            poses,
            trans,
            betas,
        })
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        self.fps
    }

    /// Number of frames (at least 1).
    pub fn frame_count(&self) -> usize {
        self.poses.len()
    }

    /// Seconds from the first frame to the last: `(frames − 1) / fps`.
    pub fn duration(&self) -> f64 {
        (self.poses.len() - 1) as f64 / self.fps
    }

    /// One pose per frame.
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    /// One root translation per frame (metres, Y up).
    pub fn trans(&self) -> &[[f32; 3]] {
        &self.trans
    }

    /// The shape β the motion was captured on, when the source recorded it.
    pub fn betas(&self) -> Option<&[f32]> {
        self.betas.as_deref()
    }

    /// Replaces the recorded shape β.
    pub fn with_betas(mut self, betas: Option<Vec<f32>>) -> Result<Self, MotionError> {
        self.betas = None;
        Motion::new(self.fps, self.poses, self.trans, betas)
    }

    /// The largest rotation and translation differences between two motions with the
    /// same number of frames, frame by frame; `None` when the frame counts differ.
    /// Rotations are compared as rotations (the angle of `q₁⁻¹ q₂`), so the two
    /// axis-angle spellings of one rotation (angle θ about a, 2π − θ about −a) count as
    /// equal.
    pub fn distance(&self, other: &Motion) -> Option<MotionDistance> {
        if self.frame_count() != other.frame_count() {
            return None;
        }
        let mut d = MotionDistance {
            rotation: 0.0,
            translation: 0.0,
        };
        for (a, b) in self.poses.iter().zip(&other.poses) {
            for (ra, rb) in a.iter().zip(b) {
                d.rotation = d.rotation.max(quat(*ra).angle_to(&quat(*rb)));
            }
        }
        for (a, b) in self.trans.iter().zip(&other.trans) {
            let va = Vector3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2]));
            let vb = Vector3::new(f64::from(b[0]), f64::from(b[1]), f64::from(b[2]));
            d.translation = d.translation.max((va - vb).norm());
        }
        Some(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_body::joints::SMPL_JOINT_COUNT;

    fn still(frames: usize) -> (Vec<Pose>, Vec<[f32; 3]>) {
        (
            vec![[[0.0; 3]; SMPL_JOINT_COUNT]; frames],
            vec![[0.0; 3]; frames],
        )
    }

    #[test]
    fn new_checks_every_invariant() {
        let (p, t) = still(3);
        let m = Motion::new(30.0, p.clone(), t.clone(), Some(vec![0.5; 10])).unwrap();
        assert_eq!(m.frame_count(), 3);
        assert!((m.duration() - 2.0 / 30.0).abs() < 1e-15);
        for fps in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Motion::new(fps, p.clone(), t.clone(), None).is_err());
        }
        assert!(Motion::new(30.0, vec![], vec![], None).is_err());
        let e = Motion::new(30.0, p.clone(), t[..2].to_vec(), None).unwrap_err();
        assert!(
            e.to_string().contains("3 poses but 2 root translations"),
            "{e}"
        );
        let mut bad = p.clone();
        bad[1][18][2] = f32::NAN;
        let e = Motion::new(30.0, bad, t.clone(), None).unwrap_err();
        assert!(
            e.to_string().contains("frame 1, joint 18 (left_elbow)"),
            "{e}"
        );
        let mut bad = t.clone();
        bad[2][0] = f32::INFINITY;
        assert!(Motion::new(30.0, p.clone(), bad, None).is_err());
        assert!(Motion::new(30.0, p, t, Some(vec![f32::NAN])).is_err());
    }

    #[test]
    fn distance_treats_equivalent_axis_angles_as_equal() {
        let (mut p, t) = still(1);
        let mut q = p.clone();
        let pi = std::f32::consts::PI;
        p[0][3] = [0.0, 0.9 * pi, 0.0];
        q[0][3] = [0.0, -1.1 * pi, 0.0];
        let a = Motion::new(30.0, p, t.clone(), None).unwrap();
        let b = Motion::new(30.0, q, t, None).unwrap();
        let d = a.distance(&b).unwrap();
        assert!(d.rotation < 1e-5 && d.translation == 0.0, "{d:?}");
    }
}
