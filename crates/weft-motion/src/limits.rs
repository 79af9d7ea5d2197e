//! Joint limits: the range of each SMPL joint's rotation, as a box on the components of
//! its axis-angle vector, and the two ways weft keeps a pose inside it.
//!
//! A box on axis-angle components is a simple, differentiable stand-in for anatomical
//! limits (which are cones and coupled ranges): for rotations below about 90° each
//! component is close to the rotation about that axis (X: flexion of legs and spine,
//! twist of the arms, which lie along X in SMPL's T-pose; Y: twist of legs and spine,
//! forward/backward swing of the arms; Z: sideways bending of legs and spine, raising
//! and lowering of the arms). The ranges are generous adult ranges of motion from the
//! clinical literature, rounded, for a pose that starts from SMPL's T-pose; they bound
//! procedural motions, and [`clamp_pose`] can bound any other. Captured motions are not
//! clamped on load: real people and capture noise exceed textbook ranges.
//!
//! Sign conventions (SMPL frame: Y up, body facing +Z, left = +X): leg flexion (thigh
//! forward) is −X at the hip, knee flexion +X, ankle plantar flexion (toes down) +X,
//! spine and neck flexion (bending forward) +X; the left arm rises with +Z and swings
//! forward with −Y, the left elbow bends with −Y. The right side mirrors the left:
//! same X range, Y and Z ranges negated.

use weft_body::joints::{SMPL_JOINT_COUNT, SMPL_MIRROR};
use weft_body::Pose;

/// `[min, max]` in degrees for the X, Y and Z axis-angle components of each joint,
/// SMPL order.
pub const JOINT_LIMITS_DEG: [[[f32; 2]; 3]; SMPL_JOINT_COUNT] = {
    let mut t = [[[-180.0, 180.0]; 3]; SMPL_JOINT_COUNT];
    // Left side and midline; the right side is filled in by mirroring below.
    t[1] = [[-125.0, 35.0], [-45.0, 45.0], [-35.0, 50.0]]; // left_hip
    t[3] = [[-30.0, 50.0], [-35.0, 35.0], [-30.0, 30.0]]; // spine1
    t[4] = [[-5.0, 150.0], [-15.0, 15.0], [-10.0, 10.0]]; // left_knee
    t[6] = [[-25.0, 40.0], [-30.0, 30.0], [-25.0, 25.0]]; // spine2
    t[7] = [[-30.0, 50.0], [-30.0, 30.0], [-25.0, 25.0]]; // left_ankle
    t[9] = [[-25.0, 40.0], [-30.0, 30.0], [-25.0, 25.0]]; // spine3
    t[10] = [[-60.0, 30.0], [-10.0, 10.0], [-10.0, 10.0]]; // left_foot
    t[12] = [[-40.0, 50.0], [-60.0, 60.0], [-40.0, 40.0]]; // neck
    t[13] = [[-20.0, 20.0], [-30.0, 30.0], [-15.0, 35.0]]; // left_collar
    t[15] = [[-35.0, 35.0], [-50.0, 50.0], [-35.0, 35.0]]; // head
    t[16] = [[-90.0, 90.0], [-130.0, 45.0], [-100.0, 110.0]]; // left_shoulder
    t[18] = [[-90.0, 90.0], [-150.0, 10.0], [-15.0, 15.0]]; // left_elbow
    t[20] = [[-60.0, 60.0], [-30.0, 30.0], [-80.0, 70.0]]; // left_wrist
    t[22] = [[-20.0, 20.0], [-20.0, 20.0], [-45.0, 30.0]]; // left_hand
    let mut j = 0;
    while j < SMPL_JOINT_COUNT {
        let m = SMPL_MIRROR[j];
        if m < j {
            let l = t[m];
            t[j] = [l[0], [-l[1][1], -l[1][0]], [-l[2][1], -l[2][0]]];
        }
        j += 1;
    }
    t
};

/// Radians of [`JOINT_LIMITS_DEG`] for joint `j`, axis `k`.
fn limits_rad(j: usize, k: usize) -> (f32, f32) {
    let [lo, hi] = JOINT_LIMITS_DEG[j][k];
    (lo.to_radians(), hi.to_radians())
}

/// The first component of `pose` outside the limits, as `(joint, axis, radians)`.
pub fn limit_violation(pose: &Pose) -> Option<(usize, usize, f32)> {
    for (j, r) in pose.iter().enumerate() {
        for (k, &v) in r.iter().enumerate() {
            let (lo, hi) = limits_rad(j, k);
            // A hair of tolerance for the degree → radian rounding of the bounds.
            if v < lo - 1e-6 || v > hi + 1e-6 {
                return Some((j, k, v));
            }
        }
    }
    None
}

/// Clamps every axis-angle component into its range; returns how many were changed.
pub fn clamp_pose(pose: &mut Pose) -> usize {
    let mut changed = 0;
    for (j, r) in pose.iter_mut().enumerate() {
        for (k, v) in r.iter_mut().enumerate() {
            let (lo, hi) = limits_rad(j, k);
            let c = v.clamp(lo, hi);
            if c != *v {
                *v = c;
                changed += 1;
            }
        }
    }
    changed
}

/// Maps a value smoothly into `(lo, hi)`: unchanged away from the bounds, then an
/// exponential approach to the bound within a margin of it. Continuous with its first
/// derivative (C¹), so a smooth motion stays smooth — a hard clamp would put a kink
/// (a jump in joint velocity) wherever the motion reaches a limit.
///
/// Each side's margin is 10 % of the range, but never more than half the distance from
/// the bound to 0, so the rest pose and small angles near a bound that is close to 0
/// (a straight knee, at 0° of a −5°…150° range) pass unchanged.
pub(crate) fn soft_limit(v: f64, lo: f64, hi: f64) -> f64 {
    let (m_lo, m_hi) = soft_margins(lo, hi);
    let (a, b) = (lo + m_lo, hi - m_hi);
    if v > b {
        hi - m_hi * (-(v - b) / m_hi).exp()
    } else if v < a {
        lo + m_lo * (-(a - v) / m_lo).exp()
    } else {
        v
    }
}

/// The margins of [`soft_limit`] below `hi` and above `lo`.
pub(crate) fn soft_margins(lo: f64, hi: f64) -> (f64, f64) {
    let range = hi - lo;
    let side = |bound: f64| (0.1 * range).min(0.5 * bound.abs()).max(0.01 * range);
    (side(lo), side(hi))
}

/// [`soft_limit`] applied to every component of a pose given in radians as `f64`.
pub(crate) fn soft_limit_pose(pose: &mut [[f64; 3]; SMPL_JOINT_COUNT]) {
    for (j, r) in pose.iter_mut().enumerate() {
        for (k, v) in r.iter_mut().enumerate() {
            let (lo, hi) = limits_rad(j, k);
            *v = soft_limit(*v, f64::from(lo), f64::from(hi));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_ordered_mirrored_and_contain_the_rest_pose() {
        for j in 0..SMPL_JOINT_COUNT {
            let m = SMPL_MIRROR[j];
            for (k, (&[lo, hi], &[mlo, mhi])) in JOINT_LIMITS_DEG[j]
                .iter()
                .zip(&JOINT_LIMITS_DEG[m])
                .enumerate()
            {
                assert!(lo <= 0.0 && 0.0 <= hi && lo < hi, "joint {j} axis {k}");
                if k == 0 {
                    assert_eq!([lo, hi], [mlo, mhi]);
                } else {
                    assert_eq!([lo, hi], [-mhi, -mlo], "joint {j} axis {k}");
                }
            }
        }
        assert_eq!(limit_violation(&[[0.0; 3]; SMPL_JOINT_COUNT]), None);
        // Right elbow bends with +Y, the mirror of the left's −Y.
        assert_eq!(JOINT_LIMITS_DEG[19][1], [-10.0, 150.0]);
    }

    #[test]
    fn clamp_moves_only_what_is_outside() {
        let mut pose = [[0.0f32; 3]; SMPL_JOINT_COUNT];
        pose[4] = [3.0, 0.1, -1.0]; // left knee: 172° flexion, 5.7° y, −57° z
        pose[18] = [0.2, -1.0, 0.0];
        assert_eq!(limit_violation(&pose), Some((4, 0, 3.0)));
        assert_eq!(clamp_pose(&mut pose), 2);
        assert!((pose[4][0] - 150f32.to_radians()).abs() < 1e-6);
        assert_eq!(pose[4][1], 0.1);
        assert!((pose[4][2] + 10f32.to_radians()).abs() < 1e-6);
        assert_eq!(pose[18], [0.2, -1.0, 0.0]);
        assert_eq!(limit_violation(&pose), None);
    }

    #[test]
    fn soft_limit_is_c1_and_bounded() {
        let (lo, hi) = (-1.0, 2.0);
        let h = 1e-6;
        let mut prev_slope = None;
        let mut x = -5.0;
        while x < 6.0 {
            let y = soft_limit(x, lo, hi);
            assert!(y > lo && y < hi, "{x} -> {y}");
            let slope = (soft_limit(x + h, lo, hi) - soft_limit(x - h, lo, hi)) / (2.0 * h);
            assert!((0.0..=1.0 + 1e-6).contains(&slope));
            if let Some(p) = prev_slope {
                let d: f64 = slope - p;
                assert!(d.abs() < 0.02, "slope jumps at {x}");
            }
            prev_slope = Some(slope);
            x += 0.001;
        }
        assert_eq!(soft_limit(0.5, lo, hi), 0.5);
        // A bound near 0 keeps 0 (and the rest pose) untouched.
        assert_eq!(soft_limit(0.0, -5.0, 150.0), 0.0);
        assert_eq!(soft_margins(-5.0, 150.0), (2.5, 15.5));
    }
}
