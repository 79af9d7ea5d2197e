//! Writing a [`Motion`] as BVH on the SMPL skeleton, so any tool that reads BVH
//! (Blender, MotionBuilder, game engines) can play it.
//!
//! The skeleton is SMPL's tree with SMPL's joint names; its offsets come from the rest
//! joints passed in (a body's J(β), or [`DEFAULT_REST_JOINTS`](super::DEFAULT_REST_JOINTS)),
//! in metres. Joint frames are world-aligned in the rest pose, exactly as SMPL's are, so
//! a joint's BVH rotation *is* its SMPL local rotation, written as Euler angles in the
//! channel order `Zrotation Yrotation Xrotation` (R = Rz·Ry·Rx). The root's position
//! channels hold the posed pelvis, `J₀ + trans`. Angles are unwrapped frame to frame
//! (±360°) so players that interpolate channels do not spin a joint the long way round.
//! Leaf joints get an `End Site` continuing their bone, for display only.

use std::path::Path;

use nalgebra::Vector3;

use super::bvh::{Bvh, BvhJoint, Channel};
use super::error::MotionError;
use super::rest::check_rest_joints;
use super::rot::quat;
use super::types::Motion;
use weft_body::joints::{SMPL_JOINT_COUNT, SMPL_JOINT_NAMES, SMPL_PARENTS};

const ROTATIONS: [Channel; 3] = [Channel::Zrotation, Channel::Yrotation, Channel::Xrotation];

/// The SMPL skeleton as BVH joints, with offsets from `rest_joints` (metres).
pub fn smpl_bvh_skeleton(rest_joints: &[[f64; 3]; SMPL_JOINT_COUNT]) -> Vec<BvhJoint> {
    let r = |j: usize| Vector3::from(rest_joints[j]);
    let mut has_child = [false; SMPL_JOINT_COUNT];
    for p in SMPL_PARENTS.iter().flatten() {
        has_child[*p] = true;
    }
    (0..SMPL_JOINT_COUNT)
        .map(|j| {
            let parent = SMPL_PARENTS[j];
            let offset = match parent {
                Some(p) => r(j) - r(p),
                None => r(j),
            };
            let mut channels = Vec::with_capacity(6);
            if parent.is_none() {
                channels.extend([Channel::Xposition, Channel::Yposition, Channel::Zposition]);
            }
            channels.extend(ROTATIONS);
            let end_sites = if has_child[j] {
                Vec::new()
            } else {
                let bone = parent.map_or_else(Vector3::zeros, |p| r(j) - r(p));
                let end = match SMPL_JOINT_NAMES[j] {
                    // The top of the head, above the head joint.
                    "head" => Vector3::new(0.0, 2.0 * bone.norm(), 0.0),
                    // The toes, ahead of the ball of the foot.
                    "left_foot" | "right_foot" => Vector3::new(0.0, 0.0, 0.6 * bone.norm()),
                    // The finger tips, continuing the hand.
                    _ => bone,
                };
                vec![[end.x, end.y, end.z]]
            };
            BvhJoint {
                name: SMPL_JOINT_NAMES[j].to_owned(),
                parent,
                offset: [offset.x, offset.y, offset.z],
                channels,
                end_sites,
                line: 0,
            }
        })
        .collect()
}

/// The motion as a BVH on the SMPL skeleton (see the module documentation).
pub fn motion_to_bvh(
    motion: &Motion,
    rest_joints: &[[f64; 3]; SMPL_JOINT_COUNT],
) -> Result<Bvh, MotionError> {
    check_rest_joints(rest_joints).map_err(MotionError::Parameter)?;
    let joints = smpl_bvh_skeleton(rest_joints);
    let per_frame = 3 + 3 * SMPL_JOINT_COUNT;
    let mut values = Vec::with_capacity(motion.frame_count() * per_frame);
    let mut previous: Option<[[f64; 3]; SMPL_JOINT_COUNT]> = None;
    for (pose, t) in motion.poses().iter().zip(motion.trans()) {
        for k in 0..3 {
            values.push(rest_joints[0][k] + f64::from(t[k]));
        }
        let mut angles = [[0.0; 3]; SMPL_JOINT_COUNT];
        for (j, r) in pose.iter().enumerate() {
            angles[j] = euler_zyx(quat(*r).euler_angles(), previous.map(|p| p[j]));
            values.extend(angles[j]);
        }
        previous = Some(angles);
    }
    Bvh::new(joints, 1.0 / motion.fps(), values)
}

/// `[z, y, x]` degrees with `R = Rz(z)·Ry(y)·Rx(x)` from nalgebra's `(roll, pitch, yaw)`
/// (= `(x, y, z)`), choosing between the two equivalent solutions — `(z, y, x)` and
/// `(z + 180°, 180° − y, x + 180°)` — and the multiples of 360° on each angle, the one
/// closest to the previous frame's angles.
fn euler_zyx((x, y, z): (f64, f64, f64), previous: Option<[f64; 3]>) -> [f64; 3] {
    let first = [z.to_degrees(), y.to_degrees(), x.to_degrees()];
    let Some(prev) = previous else {
        return first;
    };
    let second = [first[0] + 180.0, 180.0 - first[1], first[2] + 180.0];
    let unwrap = |mut a: [f64; 3]| {
        for (v, p) in a.iter_mut().zip(prev) {
            *v += 360.0 * ((p - *v) / 360.0).round();
        }
        let cost: f64 = a.iter().zip(prev).map(|(v, p)| (v - p).abs()).sum();
        (a, cost)
    };
    let (a, ca) = unwrap(first);
    let (b, cb) = unwrap(second);
    if cb < ca {
        b
    } else {
        a
    }
}

/// Writes the motion as a BVH file on the SMPL skeleton, atomically.
pub fn write_bvh(
    path: &Path,
    motion: &Motion,
    rest_joints: &[[f64; 3]; SMPL_JOINT_COUNT],
) -> Result<(), MotionError> {
    motion_to_bvh(motion, rest_joints)?.write(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rest::DEFAULT_REST_JOINTS;

    #[test]
    fn euler_channels_reproduce_the_rotation() {
        let mut pose = [[0.0f32; 3]; SMPL_JOINT_COUNT];
        pose[16] = [0.4, -1.1, 0.7];
        pose[0] = [0.0, 3.0, 0.1];
        let m = Motion::new(30.0, vec![pose], vec![[0.1, 0.2, 0.3]], None).unwrap();
        let b = motion_to_bvh(&m, &DEFAULT_REST_JOINTS).unwrap();
        assert_eq!(b.joints().len(), 24);
        assert_eq!(b.channel_count(), 75);
        for j in [0, 16] {
            let r = b.local_transform(0, j).rotation;
            assert!(r.angle_to(&quat(pose[j])) < 1e-9, "joint {j}");
        }
        let root = b.local_transform(0, 0).translation.vector;
        assert!(
            (root - Vector3::new(0.1, -0.02, 0.32)).norm() < 1e-6,
            "{root}"
        );
    }

    #[test]
    fn angles_are_unwrapped_between_frames() {
        // A pelvis turning steadily about Y through ±180°.
        let poses: Vec<_> = (0..40)
            .map(|t| {
                let mut p = [[0.0f32; 3]; SMPL_JOINT_COUNT];
                let a = 0.2 * t as f32;
                let a = (a + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU)
                    - std::f32::consts::PI;
                p[0] = [0.0, a, 0.0];
                p
            })
            .collect();
        let m = Motion::new(30.0, poses, vec![[0.0; 3]; 40], None).unwrap();
        let b = motion_to_bvh(&m, &DEFAULT_REST_JOINTS).unwrap();
        for f in 1..40 {
            for c in 3..6 {
                let d = (b.frame(f)[c] - b.frame(f - 1)[c]).abs();
                assert!(d < 20.0, "frame {f} channel {c} jumps {d}°");
            }
        }
    }
}
