//! Per-vertex body velocities over a window of frames: seed 000's `V^t`, the input of
//! the second temporal encoder `E^t2 : ℝ^{3N_b × m} → ℝ^{FS}` (§3.2, eq. 7).
//!
//! Definition. With posed body vertices `x^t` (LBS of the shaped body at frame `t`) and
//! `dt = 1 / fps`, the velocity is the *backward* difference
//! `v^t = (x^t − x^{t−1}) / dt`: causal, so it can be computed while a motion streams
//! in (a game feeding frames one by one), and it is the velocity a first-order implicit
//! integrator sees. At `t = 0` there is no previous frame; the body is taken to be at
//! rest before the motion starts, so `v^0 = 0`, and window slots before frame 0 are
//! zero too (the same convention as the pose history `Θ^t`, whose root translation
//! relative to the previous frame is zero at the start).
//!
//! Layout. A window at frame `t` holds `m` frames, **current frame first**
//! (`t, t − 1, …, t − m + 1`, clamped at frame 0), each `N_b × 3` — the order of the
//! pose history `Θ^t` in `weft_motion::pose_history`, as the paper writes both sets;
//! an LSTM that reads oldest first iterates the slots in reverse.
//! [`VelocityWindow::to_f32`] flattens it to `m × 3N_b`, one time step per row.

use super::distances::check_points;
use super::error::FeatureError;
use weft_mesh::vec3::{scale, sub};

/// Body-vertex velocities over `m` frames.
#[derive(Clone, Debug, PartialEq)]
pub struct VelocityWindow {
    frames: usize,
    vertices: usize,
    /// Slot-major: `data[k * vertices + i]` is vertex `i` in window slot `k` (frame
    /// `max(t − k, 0)`).
    data: Vec<[f64; 3]>,
}

impl VelocityWindow {
    /// Number of frames `m`.
    pub fn frame_count(&self) -> usize {
        self.frames
    }

    /// Number of body vertices `N_b`.
    pub fn vertex_count(&self) -> usize {
        self.vertices
    }

    /// Velocities (m/s) of window slot `k` (0 = the current frame `t`, `k` = frame
    /// `max(t − k, 0)`), one per vertex. Panics if
    /// `k >= frame_count()`, like slice indexing.
    pub fn frame(&self, k: usize) -> &[[f64; 3]] {
        &self.data[k * self.vertices..(k + 1) * self.vertices]
    }

    /// All velocities, slot-major, current frame first.
    pub fn as_slice(&self) -> &[[f64; 3]] {
        &self.data
    }

    /// `m × 3N_b` row-major `f32`: slot `k`, vertex `i`, axis `a` at
    /// `k·3N_b + 3i + a` (network boundary).
    pub fn to_f32(&self) -> Vec<f32> {
        self.data.iter().flat_map(|v| v.map(|x| x as f32)).collect()
    }
}

/// The velocity of every vertex at every frame of a posed sequence (`frames[t]` the
/// vertex positions at frame `t`), by backward differences with `v^0 = 0`.
pub fn vertex_velocities<V: AsRef<[[f64; 3]]>>(
    frames: &[V],
    fps: f64,
) -> Result<Vec<Vec<[f64; 3]>>, FeatureError> {
    check_sequence(frames, fps)?;
    Ok((0..frames.len())
        .map(|t| velocity_at(frames, fps, t))
        .collect())
}

/// The window of `m` velocity frames at frame `t`, current first (slot `k` = frame
/// `max(t − k, 0)`): seed 000's `V^t`. Slots before the start repeat frame 0, whose
/// velocity is zero (body at rest before the motion).
pub fn velocity_window<V: AsRef<[[f64; 3]]>>(
    frames: &[V],
    fps: f64,
    t: usize,
    m: usize,
) -> Result<VelocityWindow, FeatureError> {
    check_sequence(frames, fps)?;
    if t >= frames.len() {
        return Err(FeatureError::FrameOutOfRange {
            frame: t,
            frames: frames.len(),
        });
    }
    if m == 0 {
        return Err(FeatureError::BadParameter {
            name: "window length m",
            value: 0.0,
            expected: "at least one frame",
        });
    }
    let n = frames[0].as_ref().len();
    let mut data = Vec::with_capacity(m * n);
    for k in 0..m {
        data.extend(velocity_at(frames, fps, t.saturating_sub(k)));
    }
    Ok(VelocityWindow {
        frames: m,
        vertices: n,
        data,
    })
}

fn velocity_at<V: AsRef<[[f64; 3]]>>(frames: &[V], fps: f64, t: usize) -> Vec<[f64; 3]> {
    let now = frames[t].as_ref();
    match t.checked_sub(1) {
        None => vec![[0.0; 3]; now.len()],
        Some(prev) => now
            .iter()
            .zip(frames[prev].as_ref())
            .map(|(&a, &b)| scale(sub(a, b), fps))
            .collect(),
    }
}

fn check_sequence<V: AsRef<[[f64; 3]]>>(frames: &[V], fps: f64) -> Result<(), FeatureError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(FeatureError::BadParameter {
            name: "fps",
            value: fps,
            expected: "a finite frame rate above zero",
        });
    }
    let Some(first) = frames.first() else {
        return Err(FeatureError::FrameOutOfRange {
            frame: 0,
            frames: 0,
        });
    };
    let n = first.as_ref().len();
    for f in frames {
        let f = f.as_ref();
        if f.len() != n {
            return Err(FeatureError::CountMismatch {
                what: "vertices per frame (all frames must have the first frame's count)",
                expected: n,
                found: f.len(),
            });
        }
        check_points(f, "vertex")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_velocity_and_rest_start() {
        // One vertex moving 0.1 m per frame along x at 30 fps: 3 m/s.
        let frames: Vec<Vec<[f64; 3]>> = (0..5).map(|t| vec![[0.1 * t as f64, 0.0, 0.0]]).collect();
        let v = vertex_velocities(&frames, 30.0).unwrap();
        assert_eq!(v[0], vec![[0.0; 3]]);
        for vt in &v[1..] {
            assert!((vt[0][0] - 3.0).abs() < 1e-9);
        }
        let w = velocity_window(&frames, 30.0, 1, 3).unwrap();
        assert_eq!(w.frame_count(), 3);
        assert!((w.frame(0)[0][0] - 3.0).abs() < 1e-9); // frame 1
        assert_eq!(w.frame(1), &[[0.0; 3]]); // frame 0
        assert_eq!(w.frame(2), &[[0.0; 3]]); // before the motion: frame 0 again
        assert_eq!(w.to_f32().len(), 9);
        assert!(velocity_window(&frames, 30.0, 5, 3).is_err());
        assert!(velocity_window(&frames, 0.0, 1, 3).is_err());
        assert!(velocity_window(&frames, 30.0, 1, 0).is_err());
    }
}
