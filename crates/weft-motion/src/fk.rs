//! Joint positions of a posed SMPL skeleton (no mesh): what motion code needs to check
//! bone directions, foot heights and stride lengths. Skinning a body's mesh is the job
//! of [`crate::kinematics`] and [`crate::skinning`]; this is the same forward
//! kinematics restricted to the 24 joint positions, in `f64`.

use nalgebra::{UnitQuaternion, Vector3};

use super::rot::quat;
use weft_body::joints::{SMPL_JOINT_COUNT, SMPL_PARENTS};
use weft_body::Pose;

/// Global joint rotations of `pose`: `G_j = G_parent · R_j`, `G_0 = R_0`.
pub(crate) fn global_rotations(pose: &Pose) -> [UnitQuaternion<f64>; SMPL_JOINT_COUNT] {
    let mut g = [UnitQuaternion::identity(); SMPL_JOINT_COUNT];
    for j in 0..SMPL_JOINT_COUNT {
        let local = quat(pose[j]);
        g[j] = match SMPL_PARENTS[j] {
            Some(p) => g[p] * local,
            None => local,
        };
    }
    g
}

/// World positions (metres, Y up) of the 24 joints of a skeleton whose rest joints are
/// `rest`, posed by `pose` and translated by `trans` (SMPL's convention: the root turns
/// about the rest pelvis, then `trans` is added).
pub fn posed_joints(
    pose: &Pose,
    trans: [f32; 3],
    rest: &[[f64; 3]; SMPL_JOINT_COUNT],
) -> [[f64; 3]; SMPL_JOINT_COUNT] {
    let g = global_rotations(pose);
    let r = |j: usize| Vector3::from(rest[j]);
    let mut p = [Vector3::zeros(); SMPL_JOINT_COUNT];
    p[0] = r(0)
        + Vector3::new(
            f64::from(trans[0]),
            f64::from(trans[1]),
            f64::from(trans[2]),
        );
    for j in 1..SMPL_JOINT_COUNT {
        if let Some(parent) = SMPL_PARENTS[j] {
            p[j] = p[parent] + g[parent] * (r(j) - r(parent));
        }
    }
    p.map(|v| [v.x, v.y, v.z])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rest::DEFAULT_REST_JOINTS;

    #[test]
    fn rest_pose_gives_rest_joints_and_a_knee_bend_moves_the_ankle_back() {
        let pose = [[0.0f32; 3]; SMPL_JOINT_COUNT];
        let p = posed_joints(&pose, [0.0, 1.0, 0.0], &DEFAULT_REST_JOINTS);
        for j in 0..SMPL_JOINT_COUNT {
            assert!((p[j][1] - DEFAULT_REST_JOINTS[j][1] - 1.0).abs() < 1e-12);
        }
        let mut bent = pose;
        bent[4] = [std::f32::consts::FRAC_PI_2, 0.0, 0.0];
        let p = posed_joints(&bent, [0.0; 3], &DEFAULT_REST_JOINTS);
        // A positive rotation about X swings the shank from −Y towards −Z: backwards.
        let shank = Vector3::from(p[7]) - Vector3::from(p[4]);
        assert!(shank.z < -0.38 && shank.y.abs() < 0.05, "{shank}");
    }
}
