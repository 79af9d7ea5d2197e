//! The poses a character is deformed into (seed 001 §3.2.3.1, §3.3.3.1): random joint
//! rotations inside the joint limits, and frames of walking, running, jumping, dancing
//! and kicking clips.
//!
//! Random poses draw every axis-angle component of every joint but the root uniformly
//! in its joint-limit box (weft-motion's `JOINT_LIMITS_DEG`) scaled towards zero by
//! `range` — the thesis's "hand-set range of rotation" per joint. The root stays
//! unrotated, and no pose has a root translation: the deformation of case 1 does not
//! depend on where the character stands (the translation test of Fig. 3.23 moves it
//! afterwards). The thesis also scales joints; SMPL skeletons do not scale, so weft
//! does not.

use weft_body::joints::SMPL_JOINT_COUNT;
use weft_body::Pose;
use weft_mesh::rng::SplitMix64;
use weft_motion::{generate as procedural_motion, MotionKind, ProceduralParams, JOINT_LIMITS_DEG};

use crate::error::DataError;

/// Length of the clip frames are taken from, at 30 fps (one walk cycle and more).
const CLIP_FRAMES: usize = 60;

/// A pose drawn uniformly in the joint limits scaled by `range` (see the module doc).
pub fn random_pose(rng: &mut SplitMix64, range: f64) -> Pose {
    let mut pose = [[0.0f32; 3]; SMPL_JOINT_COUNT];
    for (j, r) in pose.iter_mut().enumerate().skip(1) {
        for (k, v) in r.iter_mut().enumerate() {
            let [lo, hi] = JOINT_LIMITS_DEG[j][k];
            let (lo, hi) = (f64::from(lo) * range, f64::from(hi) * range);
            *v = rng.uniform(lo, hi).to_radians() as f32;
        }
    }
    pose
}

/// `count` frames of a seeded `kind` clip, evenly spaced over it, root translation
/// dropped.
pub fn clip_poses(kind: MotionKind, seed: u64, count: usize) -> Result<Vec<Pose>, DataError> {
    if count == 0 {
        return Ok(Vec::new());
    }
    let params = ProceduralParams {
        frames: CLIP_FRAMES,
        seed,
        ..ProceduralParams::new(kind)
    };
    let motion = procedural_motion(&params)
        .map_err(|e| DataError::config("motions", format!("{}: {e}", kind.name())))?;
    let poses = motion.poses();
    Ok((0..count)
        .map(|i| poses[((2 * i + 1) * poses.len() / (2 * count)).min(poses.len() - 1)])
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_poses_stay_in_the_scaled_limits_and_repeat_with_the_seed() {
        let mut a = SplitMix64::new(3);
        let mut b = SplitMix64::new(3);
        for _ in 0..50 {
            let p = random_pose(&mut a, 0.5);
            assert_eq!(p, random_pose(&mut b, 0.5));
            assert_eq!(p[0], [0.0; 3]);
            assert!(weft_motion::limit_violation(&p).is_none());
            for (j, r) in p.iter().enumerate().skip(1) {
                for (k, v) in r.iter().enumerate() {
                    let [lo, hi] = JOINT_LIMITS_DEG[j][k];
                    let d = v.to_degrees();
                    assert!(d >= lo * 0.5 - 1e-3 && d <= hi * 0.5 + 1e-3, "{j} {k} {d}");
                }
            }
        }
    }

    #[test]
    fn clips_give_distinct_evenly_spaced_frames() {
        let p = clip_poses(MotionKind::Walk, 1, 4).unwrap();
        assert_eq!(p.len(), 4);
        assert_ne!(p[0], p[1]);
        assert_eq!(p, clip_poses(MotionKind::Walk, 1, 4).unwrap());
        assert!(clip_poses(MotionKind::Kick, 1, 0).unwrap().is_empty());
    }
}
