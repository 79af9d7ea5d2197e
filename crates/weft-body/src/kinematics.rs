//! Forward kinematics over a kinematic tree (SMPL's `kintree_table`).
//!
//! A pose gives each joint a rotation relative to its parent, about the joint's rest
//! position. Walking the tree from the root composes them into **global** joint
//! transforms `G_j` (where joint `j`'s frame is in the posed body) and the **skinning**
//! transforms `A_j = G_j · T(−J_j)`, which take a point of the rest mesh to where joint
//! `j` alone would carry it: the `T_j R_j⁻¹` of seed 001 eq. 2.1.

use nalgebra::{Matrix3, Vector3};

use crate::rotation::rodrigues;

/// A rigid transform `x ↦ R x + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rigid {
    /// Rotation matrix.
    pub rotation: Matrix3<f64>,
    /// Translation.
    pub translation: Vector3<f64>,
}

impl Rigid {
    /// The identity.
    pub fn identity() -> Self {
        Rigid {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// Applies the transform to a point.
    #[inline]
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        (self.rotation * Vector3::from(p) + self.translation).into()
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn compose(&self, other: &Rigid) -> Rigid {
        Rigid {
            rotation: self.rotation * other.rotation,
            translation: self.rotation * other.translation + self.translation,
        }
    }
}

/// Why a kinematic tree or a pose was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum KinematicsError {
    /// A joint's parent does not come before it (or the root is not joint 0).
    #[error("joint {joint}: parent {parent:?} is not an earlier joint; expected joint 0 to be the only root and every other joint's parent to have a smaller index")]
    NotATree {
        /// The joint.
        joint: usize,
        /// Its parent as given.
        parent: Option<usize>,
    },
    /// The pose or the joint positions are not one per joint.
    #[error("{what} has {found} entries; expected one per joint ({expected})")]
    Count {
        /// Which input.
        what: &'static str,
        /// Number of joints.
        expected: usize,
        /// Number given.
        found: usize,
    },
}

/// A kinematic tree: each joint's parent, the root (joint 0) having none, and every
/// parent index smaller than its child's, so one pass in index order visits parents
/// before children (SMPL's order has this property).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Skeleton {
    parents: Vec<Option<usize>>,
}

impl Skeleton {
    /// Checks the tree property and wraps the parents.
    pub fn new(parents: Vec<Option<usize>>) -> Result<Self, KinematicsError> {
        for (j, &p) in parents.iter().enumerate() {
            let ok = match p {
                None => j == 0,
                Some(p) => p < j,
            };
            if !ok {
                return Err(KinematicsError::NotATree {
                    joint: j,
                    parent: p,
                });
            }
        }
        Ok(Skeleton { parents })
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.parents.len()
    }

    /// Whether there are no joints.
    pub fn is_empty(&self) -> bool {
        self.parents.is_empty()
    }

    /// Each joint's parent (`None` for the root).
    pub fn parents(&self) -> &[Option<usize>] {
        &self.parents
    }

    /// Global joint transforms for local `rotations` (one per joint, relative to the
    /// parent; the root's is global) about the rest joint positions `joints`, with the
    /// whole body moved by `translation` afterwards.
    ///
    /// `G_root = T(t) · [R_0 | J_0]`, `G_j = G_parent · [R_j | J_j − J_parent]`.
    pub fn global_transforms(
        &self,
        joints: &[[f64; 3]],
        rotations: &[Matrix3<f64>],
        translation: [f64; 3],
    ) -> Result<Vec<Rigid>, KinematicsError> {
        self.check("joint positions", joints.len())?;
        self.check("pose", rotations.len())?;
        let mut g: Vec<Rigid> = Vec::with_capacity(self.len());
        for (j, (&p, r)) in self.parents.iter().zip(rotations).enumerate() {
            let jj = Vector3::from(joints[j]);
            let local = match p {
                None => Rigid {
                    rotation: *r,
                    translation: jj + Vector3::from(translation),
                },
                Some(p) => Rigid {
                    rotation: *r,
                    translation: jj - Vector3::from(joints[p]),
                },
            };
            let global = match p {
                None => local,
                Some(p) => g[p].compose(&local),
            };
            g.push(global);
        }
        Ok(g)
    }

    /// The skinning transforms `A_j = G_j · T(−J_j)` of [`Self::global_transforms`]:
    /// each maps a rest-pose point to where joint `j` carries it.
    pub fn skinning_transforms(
        &self,
        joints: &[[f64; 3]],
        rotations: &[Matrix3<f64>],
        translation: [f64; 3],
    ) -> Result<Vec<Rigid>, KinematicsError> {
        let g = self.global_transforms(joints, rotations, translation)?;
        Ok(relative_transforms(&g, joints))
    }

    /// [`Self::skinning_transforms`] for a pose given as one axis-angle vector per joint.
    pub fn skinning_transforms_axis_angle(
        &self,
        joints: &[[f64; 3]],
        pose: &[[f64; 3]],
        translation: [f64; 3],
    ) -> Result<Vec<Rigid>, KinematicsError> {
        let rotations: Vec<Matrix3<f64>> = pose.iter().map(|&w| rodrigues(w)).collect();
        self.skinning_transforms(joints, &rotations, translation)
    }

    fn check(&self, what: &'static str, found: usize) -> Result<(), KinematicsError> {
        if found == self.len() {
            Ok(())
        } else {
            Err(KinematicsError::Count {
                what,
                expected: self.len(),
                found,
            })
        }
    }
}

/// `A_j = G_j · T(−J_j)`: global transforms made relative to the rest joint positions.
pub fn relative_transforms(globals: &[Rigid], joints: &[[f64; 3]]) -> Vec<Rigid> {
    globals
        .iter()
        .zip(joints)
        .map(|(g, &j)| Rigid {
            rotation: g.rotation,
            translation: g.translation - g.rotation * Vector3::from(j),
        })
        .collect()
}

/// Posed joint positions: the translation part of each global transform.
pub fn posed_joints(globals: &[Rigid]) -> Vec<[f64; 3]> {
    globals.iter().map(|g| g.translation.into()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A chain 0 → 1 → 2 along +X, one unit apart, plus joint 3 off the root along +Y.
    fn chain() -> (Skeleton, Vec<[f64; 3]>) {
        let s = Skeleton::new(vec![None, Some(0), Some(1), Some(0)]).unwrap();
        let j = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        (s, j)
    }

    fn near(a: [f64; 3], b: [f64; 3]) -> bool {
        (Vector3::from(a) - Vector3::from(b)).norm() < 1e-12
    }

    #[test]
    fn trees_must_list_parents_first() {
        assert!(Skeleton::new(vec![None, Some(0), Some(1)]).is_ok());
        assert_eq!(
            Skeleton::new(vec![None, Some(2), Some(0)]),
            Err(KinematicsError::NotATree {
                joint: 1,
                parent: Some(2)
            })
        );
        assert!(Skeleton::new(vec![Some(0)]).is_err());
        assert!(Skeleton::new(vec![None, None]).is_err());
        let (s, j) = chain();
        let e = s
            .skinning_transforms_axis_angle(&j, &[[0.0; 3]; 3], [0.0; 3])
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "pose has 3 entries; expected one per joint (4)"
        );
    }

    #[test]
    fn identity_pose_keeps_the_rest_pose() {
        let (s, j) = chain();
        let g = s
            .global_transforms(&j, &[Matrix3::identity(); 4], [0.0; 3])
            .unwrap();
        assert_eq!(posed_joints(&g), j);
        for a in relative_transforms(&g, &j) {
            assert_eq!(a, Rigid::identity());
        }
    }

    #[test]
    fn one_joint_rotation_in_closed_form() {
        let (s, j) = chain();
        // A quarter turn about Z at joint 1 swings joint 2 from (2,0,0) to (1,1,0).
        let mut pose = [[0.0; 3]; 4];
        pose[1] = [0.0, 0.0, std::f64::consts::FRAC_PI_2];
        let a = s
            .skinning_transforms_axis_angle(&j, &pose, [0.0; 3])
            .unwrap();
        assert!(near(a[2].apply([2.0, 0.0, 0.0]), [1.0, 1.0, 0.0]));
        assert!(near(a[1].apply([1.5, 0.0, 0.0]), [1.0, 0.5, 0.0]));
        // The joint itself stays put; the root's branch is untouched.
        assert!(near(a[1].apply([1.0, 0.0, 0.0]), [1.0, 0.0, 0.0]));
        assert_eq!(a[0], Rigid::identity());
        assert_eq!(a[3], Rigid::identity());
        // Rotating the root by the same turn moves everything about the root.
        pose[1] = [0.0; 3];
        pose[0] = [0.0, 0.0, std::f64::consts::FRAC_PI_2];
        let a = s
            .skinning_transforms_axis_angle(&j, &pose, [0.5, 0.0, 0.0])
            .unwrap();
        assert!(near(a[2].apply([2.0, 0.0, 0.0]), [0.5, 2.0, 0.0]));
        assert!(near(a[3].apply([0.0, 1.0, 0.0]), [-0.5, 0.0, 0.0]));
    }

    proptest! {
        /// Rotating every joint by R_j and then undoing it is the identity, and the posed
        /// bone lengths equal the rest ones (rigid limbs).
        #[test]
        fn bone_lengths_are_preserved(pose in prop::collection::vec(prop::array::uniform3(-2.0f64..2.0), 4), t in prop::array::uniform3(-1.0f64..1.0)) {
            let (s, j) = chain();
            let g = s.global_transforms(&j, &pose.iter().map(|&w| rodrigues(w)).collect::<Vec<_>>(), t).unwrap();
            let pj = posed_joints(&g);
            for (c, p) in s.parents().iter().enumerate() {
                if let Some(p) = p {
                    let rest = (Vector3::from(j[c]) - Vector3::from(j[*p])).norm();
                    let posed = (Vector3::from(pj[c]) - Vector3::from(pj[*p])).norm();
                    prop_assert!((rest - posed).abs() < 1e-12);
                }
            }
            // The root joint lands at J_0 + t.
            prop_assert!(near(pj[0], [t[0], t[1], t[2]]));
        }
    }
}
