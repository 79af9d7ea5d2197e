//! SMPL's 24 joints: their names, their kinematic tree and their left/right mirror.
//!
//! Every pose in weft is indexed in this order, the order of SMPL's `kintree_table`
//! and `J_regressor` rows, so a pose read from AMASS, retargeted from a BVH file or
//! generated procedurally drives any SMPL-format body without a lookup table. The names
//! are those of the SMPL paper and the `smplx` package, lower-case with underscores.

/// Number of joints of an SMPL skeleton.
pub const SMPL_JOINT_COUNT: usize = 24;

/// One frame's pose: the axis-angle rotation (radians) of each of SMPL's 24 joints, in
/// SMPL order ([`SMPL_JOINT_NAMES`]). Each rotation is local, relative to the parent
/// joint's frame; joint 0 (the pelvis) carries the global orientation. The one pose
/// type of motions, models, training and evaluation.
pub type Pose = [[f32; 3]; SMPL_JOINT_COUNT];

/// The joints in SMPL order. Index 0 is the root (the pelvis). "left" is the body's own
/// left, which in SMPL's rest frame (Y up, facing +Z) lies on the +X side.
pub const SMPL_JOINT_NAMES: [&str; SMPL_JOINT_COUNT] = [
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hand",
    "right_hand",
];

/// The parent of each joint (SMPL's `kintree_table[0]`), `None` for the root. Every
/// parent index is smaller than its child's, so one pass in index order visits parents
/// before children.
pub const SMPL_PARENTS: [Option<usize>; SMPL_JOINT_COUNT] = [
    None,
    Some(0),
    Some(0),
    Some(0),
    Some(1),
    Some(2),
    Some(3),
    Some(4),
    Some(5),
    Some(6),
    Some(7),
    Some(8),
    Some(9),
    Some(9),
    Some(9),
    Some(12),
    Some(13),
    Some(14),
    Some(16),
    Some(17),
    Some(18),
    Some(19),
    Some(20),
    Some(21),
];

/// For each joint, the joint on the other side of the body (itself on the midline).
/// Mirroring a pose across the body's sagittal plane (x → −x) swaps these joints and
/// maps an axis-angle `(x, y, z)` to `(x, −y, −z)`.
pub const SMPL_MIRROR: [usize; SMPL_JOINT_COUNT] = [
    0, 2, 1, 3, 5, 4, 6, 8, 7, 9, 11, 10, 12, 14, 13, 15, 17, 16, 19, 18, 21, 20, 23, 22,
];

/// The index of the SMPL joint called `name` (exactly as in [`SMPL_JOINT_NAMES`]).
pub fn smpl_joint_index(name: &str) -> Option<usize> {
    SMPL_JOINT_NAMES.iter().position(|&n| n == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parents_come_before_children_and_mirror_is_an_involution() {
        for (j, p) in SMPL_PARENTS.iter().enumerate() {
            assert_eq!(p.is_none(), j == 0);
            if let Some(p) = p {
                assert!(*p < j);
                // A joint's mirror hangs off its parent's mirror.
                assert_eq!(SMPL_PARENTS[SMPL_MIRROR[j]], Some(SMPL_MIRROR[*p]));
            }
            assert_eq!(SMPL_MIRROR[SMPL_MIRROR[j]], j);
            let (name, mirror) = (SMPL_JOINT_NAMES[j], SMPL_JOINT_NAMES[SMPL_MIRROR[j]]);
            assert_eq!(
                name.replace("left", "#")
                    .replace("right", "left")
                    .replace('#', "right"),
                mirror
            );
        }
        assert_eq!(smpl_joint_index("left_elbow"), Some(18));
        assert_eq!(smpl_joint_index("Left_Elbow"), None);
    }
}
