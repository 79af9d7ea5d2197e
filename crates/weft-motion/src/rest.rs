//! A built-in rest skeleton: where SMPL's 24 joints sit in the rest pose of an average
//! adult, for the operations that need joint positions but were given no body
//! (retargeting a BVH file, writing a motion as BVH, converting AMASS's Z-up root
//! translation).
//!
//! The numbers are hand-set round values of typical adult proportions (1.70 m tall,
//! pelvis joint 0.22 m below the origin as in SMPL's template, T-pose arms), symmetric
//! in x. They are not SMPL's regressed joints, which come with SMPL's licence; pass a
//! body's own J(β) wherever a function takes rest joints to match that body exactly.

use weft_body::joints::SMPL_JOINT_COUNT;

/// Rest-pose joint positions (metres, Y up, facing +Z), SMPL order.
pub const DEFAULT_REST_JOINTS: [[f64; 3]; SMPL_JOINT_COUNT] = [
    [0.0, -0.22, 0.02],     // pelvis
    [0.07, -0.31, 0.02],    // left_hip
    [-0.07, -0.31, 0.02],   // right_hip
    [0.0, -0.11, 0.0],      // spine1
    [0.10, -0.70, 0.015],   // left_knee
    [-0.10, -0.70, 0.015],  // right_knee
    [0.0, 0.025, 0.025],    // spine2
    [0.085, -1.09, -0.015], // left_ankle
    [-0.085, -1.09, -0.015],
    [0.0, 0.075, 0.03],    // spine3
    [0.12, -1.14, 0.105],  // left_foot
    [-0.12, -1.14, 0.105], // right_foot
    [0.0, 0.29, -0.02],    // neck
    [0.08, 0.20, -0.005],  // left_collar
    [-0.08, 0.20, -0.005], // right_collar
    [0.0, 0.355, 0.03],    // head
    [0.17, 0.225, -0.02],  // left_shoulder
    [-0.17, 0.225, -0.02], // right_shoulder
    [0.435, 0.215, -0.04], // left_elbow
    [-0.435, 0.215, -0.04],
    [0.695, 0.23, -0.04], // left_wrist
    [-0.695, 0.23, -0.04],
    [0.785, 0.22, -0.055], // left_hand
    [-0.785, 0.22, -0.055],
];

/// Rest joint positions with every coordinate finite; the check callers run on joints
/// that come from outside (a body file) before building offsets from them.
pub(crate) fn check_rest_joints(joints: &[[f64; 3]; SMPL_JOINT_COUNT]) -> Result<(), String> {
    for (j, p) in joints.iter().enumerate() {
        if p.iter().any(|x| !x.is_finite()) {
            return Err(format!(
                "rest joint {j} ({}) is {p:?}; expected finite coordinates",
                weft_body::joints::SMPL_JOINT_NAMES[j]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_body::joints::{SMPL_MIRROR, SMPL_PARENTS};

    #[test]
    fn default_skeleton_is_symmetric_and_human_sized() {
        for j in 0..SMPL_JOINT_COUNT {
            let (a, b) = (DEFAULT_REST_JOINTS[j], DEFAULT_REST_JOINTS[SMPL_MIRROR[j]]);
            assert_eq!([a[0], a[1], a[2]], [-b[0], b[1], b[2]], "joint {j}");
            if let Some(p) = SMPL_PARENTS[j] {
                let q = DEFAULT_REST_JOINTS[p];
                let len =
                    ((a[0] - q[0]).powi(2) + (a[1] - q[1]).powi(2) + (a[2] - q[2]).powi(2)).sqrt();
                assert!((0.04..0.45).contains(&len), "bone {p}->{j}: {len}");
            }
        }
        // Ankle to head joint: most of a 1.70 m body.
        let span = DEFAULT_REST_JOINTS[15][1] - DEFAULT_REST_JOINTS[7][1];
        assert!((1.35..1.55).contains(&span), "{span}");
        assert!(check_rest_joints(&DEFAULT_REST_JOINTS).is_ok());
    }
}
