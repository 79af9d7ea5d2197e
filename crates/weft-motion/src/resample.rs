//! Resampling a motion to another frame rate: spherical linear interpolation of every
//! joint rotation (as unit quaternions, along the shorter arc) and linear interpolation
//! of the root translation.
//!
//! Frame `k` of the result lies at time `k / fps`; the result covers the source's
//! duration, `⌊duration · fps⌋ + 1` frames (it never extrapolates past the last source
//! frame). A result frame that falls exactly on a source frame copies it unchanged, so
//! resampling to the same rate is the identity, bit for bit.

use super::error::MotionError;
use super::rot::{axis_angle, quat};
use super::types::{Motion, MAX_FPS, MAX_FRAMES};
use weft_body::Pose;

/// The motion at `fps` frames per second (see the module documentation). Fails for a
/// non-positive or non-finite rate, or when the result would exceed [`MAX_FRAMES`]
/// (checked before allocating).
pub fn resample(motion: &Motion, fps: f64) -> Result<Motion, MotionError> {
    if !(fps.is_finite() && fps > 0.0 && fps <= MAX_FPS) {
        return Err(MotionError::Parameter(format!(
            "target frame rate {fps}; expected frames per second above 0 and at most {MAX_FPS}"
        )));
    }
    let src_fps = motion.fps();
    if fps == src_fps {
        return Ok(motion.clone());
    }
    let n = motion.frame_count();
    // The tiny tolerance keeps a last frame that rounding puts a hair past the end.
    let count = (motion.duration() * fps + 1e-9).floor() + 1.0;
    if count > MAX_FRAMES as f64 {
        return Err(MotionError::Parameter(format!(
            "resampling {:.1} s to {fps} fps gives {count} frames; at most {MAX_FRAMES} fit in memory",
            motion.duration()
        )));
    }
    let count = count as usize;
    let ratio = src_fps / fps;
    let (poses, trans) = (motion.poses(), motion.trans());
    let mut out_poses: Vec<Pose> = Vec::with_capacity(count);
    let mut out_trans = Vec::with_capacity(count);
    for k in 0..count {
        let s = k as f64 * ratio;
        let i = (s.floor() as usize).min(n - 1);
        let u = s - i as f64;
        if i + 1 >= n || u <= 1e-9 {
            out_poses.push(poses[i]);
            out_trans.push(trans[i]);
            continue;
        }
        let mut pose = [[0.0f32; 3]; weft_body::joints::SMPL_JOINT_COUNT];
        for (j, r) in pose.iter_mut().enumerate() {
            let (a, b) = (quat(poses[i][j]), quat(poses[i + 1][j]));
            // Only exactly opposite quaternions have no slerp; after the sign flip to
            // the shorter arc that cannot happen, but no input may panic.
            let q = a
                .try_slerp(&b, u, 1e-12)
                .unwrap_or(if u < 0.5 { a } else { b });
            *r = axis_angle(&q);
        }
        out_poses.push(pose);
        let (a, b) = (trans[i], trans[i + 1]);
        out_trans
            .push([0, 1, 2].map(|c| (f64::from(a[c]) * (1.0 - u) + f64::from(b[c]) * u) as f32));
    }
    Motion::new(
        fps,
        out_poses,
        out_trans,
        motion.betas().map(<[f32]>::to_vec),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_body::joints::SMPL_JOINT_COUNT;

    /// A joint turning at constant angular velocity about a fixed axis, root moving at
    /// constant velocity: interpolation is then exact.
    fn steady(frames: usize, fps: f64) -> Motion {
        let poses = (0..frames)
            .map(|k| {
                let t = k as f32 / fps as f32;
                let mut p = [[0.0f32; 3]; SMPL_JOINT_COUNT];
                p[4] = [0.8 * t, 0.0, 0.0];
                p[16] = [0.0, 0.0, -0.5 * t];
                p
            })
            .collect();
        let trans = (0..frames)
            .map(|k| [0.0, 0.0, 1.2 * k as f32 / fps as f32])
            .collect();
        Motion::new(fps, poses, trans, Some(vec![0.1, 0.2])).unwrap()
    }

    #[test]
    fn same_rate_is_the_identity() {
        let m = steady(50, 30.0);
        assert_eq!(resample(&m, 30.0).unwrap(), m);
    }

    #[test]
    fn interpolation_is_exact_for_steady_motion() {
        let m = steady(61, 60.0); // 1 s
        let r = resample(&m, 24.0).unwrap();
        assert_eq!(r.frame_count(), 25);
        assert_eq!(r.betas(), Some(&[0.1f32, 0.2][..]));
        let expected = steady(25, 24.0);
        let d = r.distance(&expected).unwrap();
        assert!(d.rotation < 1e-5 && d.translation < 1e-5, "{d:?}");
        // Up then down again gives the original frames back.
        let up = resample(&m, 120.0).unwrap();
        assert_eq!(up.frame_count(), 121);
        let back = resample(&up, 60.0).unwrap();
        let d = back.distance(&m).unwrap();
        assert!(d.rotation < 1e-5 && d.translation < 1e-5, "{d:?}");
    }

    #[test]
    fn slerp_takes_the_short_way_across_pi() {
        let pi = std::f32::consts::PI;
        let mut a = [[0.0f32; 3]; SMPL_JOINT_COUNT];
        let mut b = a;
        a[0] = [0.0, 0.95 * pi, 0.0];
        b[0] = [0.0, -0.95 * pi, 0.0]; // 0.1π away the short way round
        let m = Motion::new(1.0, vec![a, b], vec![[0.0; 3]; 2], None).unwrap();
        let r = resample(&m, 2.0).unwrap();
        let mid = quat(r.poses()[1][0]);
        assert!(mid.angle() > 0.99 * std::f64::consts::PI, "{}", mid.angle());
    }

    #[test]
    fn bad_rates_and_huge_results_are_refused() {
        let m = steady(10, 30.0);
        for fps in [0.0, -3.0, f64::NAN, f64::INFINITY] {
            assert!(resample(&m, fps).is_err());
        }
        let e = resample(&m, 1e12).unwrap_err().to_string();
        assert!(e.contains("at most"), "{e}");
    }
}
