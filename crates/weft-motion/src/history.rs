//! The pose history Θᵗ of seed 000 (§3.2, "temporal information"): the input of the
//! temporal encoder E^{t1}, an LSTM over `m` frames of `3(S + 1)` numbers.
//!
//! For frame `t` and window `m`, Θᵗ = {θᵗ, θᵗ⁻¹, …, θᵗ⁻ᵐ⁺¹}, where each θ holds "the
//! axis-angle of each joint and the translation of the root relative to the preceding
//! frame": SMPL's 24 axis-angles (72 numbers, SMPL order) followed by
//! `trans[t] − trans[t − 1]` (3 numbers, metres, world frame, zero at the first frame),
//! so S = 24 and each row has 75 numbers.
//!
//! Row `i` of the window is frame `t − i` — the current frame first, as the paper writes
//! the set; an LSTM that reads oldest first iterates the rows in reverse. Frames before
//! the start are clamped to frame 0 (whose displacement is zero), so a window is always
//! full and the first frames look like a body that was standing still.

use super::error::MotionError;
use super::types::Motion;
use weft_body::joints::SMPL_JOINT_COUNT;

/// Numbers per frame in Θᵗ: 3 · (24 joints + the root displacement).
pub const HISTORY_FEATURES: usize = 3 * (SMPL_JOINT_COUNT + 1);

/// The most numbers [`pose_histories`] returns at once (2²⁸, 1 GiB of `f32`).
pub const MAX_HISTORY_VALUES: usize = 1 << 28;

/// θᵗ: frame `t`'s 72 axis-angle numbers and its root displacement from frame `t − 1`.
///
/// # Panics
/// When `t >= motion.frame_count()`.
pub fn pose_features(motion: &Motion, t: usize) -> [f32; HISTORY_FEATURES] {
    let mut out = [0.0f32; HISTORY_FEATURES];
    for (j, r) in motion.poses()[t].iter().enumerate() {
        out[3 * j..3 * j + 3].copy_from_slice(r);
    }
    if t > 0 {
        let (a, b) = (motion.trans()[t - 1], motion.trans()[t]);
        for k in 0..3 {
            out[3 * SMPL_JOINT_COUNT + k] = b[k] - a[k];
        }
    }
    out
}

/// Θᵗ as `window` rows of [`HISTORY_FEATURES`] numbers, row `i` = θ^max(t−i, 0).
pub fn pose_history(
    motion: &Motion,
    t: usize,
    window: usize,
) -> Result<Vec<[f32; HISTORY_FEATURES]>, MotionError> {
    check_window(window)?;
    if t >= motion.frame_count() {
        return Err(MotionError::Parameter(format!(
            "frame {t} of a motion with {} frames",
            motion.frame_count()
        )));
    }
    Ok((0..window)
        .map(|i| pose_features(motion, t.saturating_sub(i)))
        .collect())
}

/// Θᵗ for every frame: a `(frames, window, 75)` array in C order, flattened. Fails when
/// it would hold more than [`MAX_HISTORY_VALUES`] numbers (checked before allocating).
pub fn pose_histories(motion: &Motion, window: usize) -> Result<Vec<f32>, MotionError> {
    check_window(window)?;
    let n = motion.frame_count();
    let total = n
        .checked_mul(window)
        .and_then(|x| x.checked_mul(HISTORY_FEATURES))
        .filter(|&x| x <= MAX_HISTORY_VALUES)
        .ok_or_else(|| {
            MotionError::Parameter(format!(
                "pose histories of {n} frames × window {window} would hold more than {MAX_HISTORY_VALUES} numbers; take them per frame with pose_history"
            ))
        })?;
    let features: Vec<[f32; HISTORY_FEATURES]> = (0..n).map(|t| pose_features(motion, t)).collect();
    let mut out = Vec::with_capacity(total);
    for t in 0..n {
        for i in 0..window {
            out.extend_from_slice(&features[t.saturating_sub(i)]);
        }
    }
    Ok(out)
}

fn check_window(window: usize) -> Result<(), MotionError> {
    if window == 0 {
        return Err(MotionError::Parameter(
            "pose-history window 0; expected at least 1 frame".into(),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counting(frames: usize) -> Motion {
        let poses = (0..frames)
            .map(|t| {
                let mut p = [[0.0f32; 3]; SMPL_JOINT_COUNT];
                p[0][0] = t as f32 * 0.01;
                p[23][2] = -(t as f32) * 0.01;
                p
            })
            .collect();
        let trans = (0..frames).map(|t| [0.0, 0.0, (t * t) as f32]).collect();
        Motion::new(30.0, poses, trans, None).unwrap()
    }

    #[test]
    fn rows_go_back_in_time_and_clamp_at_the_start() {
        let m = counting(5);
        let h = pose_history(&m, 3, 5).unwrap();
        assert_eq!(h.len(), 5);
        // Rows: frames 3, 2, 1, 0, 0.
        let frames: Vec<f32> = h.iter().map(|r| (r[0] * 100.0).round()).collect();
        assert_eq!(frames, vec![3.0, 2.0, 1.0, 0.0, 0.0]);
        assert_eq!(h[0][71], -0.03);
        // Displacement trans[t] − trans[t−1] = t² − (t−1)² = 2t − 1; zero at frame 0.
        let dz: Vec<f32> = h.iter().map(|r| r[74]).collect();
        assert_eq!(dz, vec![5.0, 3.0, 1.0, 0.0, 0.0]);
        assert!(pose_history(&m, 5, 2).is_err());
        assert!(pose_history(&m, 0, 0).is_err());
    }

    #[test]
    fn all_histories_match_the_single_ones() {
        let m = counting(7);
        let all = pose_histories(&m, 3).unwrap();
        assert_eq!(all.len(), 7 * 3 * HISTORY_FEATURES);
        for t in 0..7 {
            let one: Vec<f32> = pose_history(&m, t, 3).unwrap().concat();
            let start = t * 3 * HISTORY_FEATURES;
            assert_eq!(&all[start..start + 3 * HISTORY_FEATURES], &one[..]);
        }
        let e = pose_histories(&m, usize::MAX).unwrap_err().to_string();
        assert!(e.contains("would hold more than"), "{e}");
    }
}
