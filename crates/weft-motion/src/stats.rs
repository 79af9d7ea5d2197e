//! Summary numbers of a motion, what `weft motion info` prints: length, per-joint range
//! of motion and the root's path.

use nalgebra::Vector3;

use super::types::Motion;
use weft_body::joints::{SMPL_JOINT_COUNT, SMPL_JOINT_NAMES};

/// The range one joint's rotation covers over a motion.
#[derive(Clone, Debug, PartialEq)]
pub struct JointRange {
    /// The SMPL joint name.
    pub name: &'static str,
    /// Smallest X, Y, Z axis-angle component, degrees.
    pub min_deg: [f64; 3],
    /// Largest X, Y, Z axis-angle component, degrees.
    pub max_deg: [f64; 3],
    /// Largest rotation angle (length of the axis-angle), degrees.
    pub max_angle_deg: f64,
}

/// Summary of a motion.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionStats {
    /// Number of frames.
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
    /// Seconds from the first to the last frame.
    pub duration: f64,
    /// One range per SMPL joint, SMPL order.
    pub joints: Vec<JointRange>,
    /// Length of the root translation's polyline, metres.
    pub root_path_length: f64,
    /// Root translation of the last frame minus the first, metres.
    pub root_displacement: [f64; 3],
    /// Whether the motion records a body shape β, and how many coefficients.
    pub betas: Option<usize>,
}

/// Summarises a motion.
pub fn motion_stats(motion: &Motion) -> MotionStats {
    let mut joints: Vec<JointRange> = SMPL_JOINT_NAMES
        .iter()
        .map(|&name| JointRange {
            name,
            min_deg: [f64::INFINITY; 3],
            max_deg: [f64::NEG_INFINITY; 3],
            max_angle_deg: 0.0,
        })
        .collect();
    for pose in motion.poses() {
        for (range, r) in joints.iter_mut().zip(pose.iter()) {
            let v = Vector3::new(f64::from(r[0]), f64::from(r[1]), f64::from(r[2]));
            for k in 0..3 {
                let d = v[k].to_degrees();
                range.min_deg[k] = range.min_deg[k].min(d);
                range.max_deg[k] = range.max_deg[k].max(d);
            }
            range.max_angle_deg = range.max_angle_deg.max(v.norm().to_degrees());
        }
    }
    let t = |p: &[f32; 3]| Vector3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
    let trans = motion.trans();
    let root_path_length = trans.windows(2).map(|w| (t(&w[1]) - t(&w[0])).norm()).sum();
    let d = t(&trans[trans.len() - 1]) - t(&trans[0]);
    debug_assert_eq!(joints.len(), SMPL_JOINT_COUNT);
    MotionStats {
        frames: motion.frame_count(),
        fps: motion.fps(),
        duration: motion.duration(),
        joints,
        root_path_length,
        root_displacement: [d.x, d.y, d.z],
        betas: motion.betas().map(<[f32]>::len),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_path() {
        let mut a = [[0.0f32; 3]; SMPL_JOINT_COUNT];
        let mut b = a;
        a[4] = [0.5, 0.0, 0.0];
        b[4] = [1.0, -0.2, 0.0];
        let m = Motion::new(
            10.0,
            vec![a, b, a],
            vec![[0.0; 3], [3.0, 4.0, 0.0], [3.0, 4.0, 1.0]],
            None,
        )
        .unwrap();
        let s = motion_stats(&m);
        assert_eq!((s.frames, s.duration), (3, 0.2));
        assert_eq!(s.root_path_length, 6.0);
        assert_eq!(s.root_displacement, [3.0, 4.0, 1.0]);
        let knee = &s.joints[4];
        assert_eq!(knee.name, "left_knee");
        assert!((knee.max_deg[0] - 1f64.to_degrees()).abs() < 1e-9);
        assert!((knee.min_deg[1] - (-0.2f32 as f64).to_degrees()).abs() < 1e-9);
        assert_eq!(s.joints[0].max_angle_deg, 0.0);
    }
}
