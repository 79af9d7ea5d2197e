//! The relative skinning descriptor `r_i(θ)` of MultiResGNet (seed 001 §3.3.1,
//! eq. 3.7–3.9), for body vertices and for garment vertices with transferred weights.
//!
//! Seed 001 replaces the vertex position `p_i` in the node features by
//!
//! ```text
//! G_s(θ)  = Π_{p ∈ A(s)} Z(ω_p)                                   (3.7)
//! Z(ω)    = I + sin‖ω‖ ω̂ + (1 − cos‖ω‖) ω̂²                         (3.8)
//! r_i(θ)  = Σ_s w_{s,i} G_s(θ) G_s(θ*)⁻¹ r̄_i                        (3.9)
//! ```
//!
//! where `ω̂` is the skew matrix of the *unit* axis `ω/‖ω‖` (Rodrigues; the thesis
//! writes `ω̂_p` for it), `A(s)` is the ordered chain of ancestors of joint `s`, root
//! first, **including `s` itself** (the wording is SMPL's for its global transforms,
//! whose product includes the joint's own rotation; without it a joint's rotation
//! would not move the vertices bound to it), `θ*` is the rest pose (all zeros for
//! SMPL, whose rest pose is the T-pose of `v_template`), `w_{s,i}` the skinning weights
//! and `r̄_i` the rest-pose position. It is LBS with every joint's translation dropped:
//! the rotation part of the skinning transform applied to the rest position. Because no
//! joint position or root translation enters, `r_i(θ)` is invariant to a global
//! translation of the character — the point of the descriptor (thesis Fig. 3.23) — but
//! not to a global rotation.
//!
//! For garments (seed 001 §4.3.1, eq. 4.7, computed "following Equation 3.9") the same
//! formula runs on the garment's rest positions with weights transferred from the body
//! ([`super::transfer`]); GarFitNet then adds its per-vertex coarse displacement
//! `Δ_coarse,i`, which is the model's business, not this function's.

use rayon::prelude::*;

use super::distances::check_points;
use super::error::FeatureError;
use super::weights::SkinningWeights;
use weft_mesh::vec3::is_finite;

/// A 3×3 rotation matrix, row-major (`m[row][col]`).
pub type Rotation = [[f64; 3]; 3];

/// The identity rotation.
pub const IDENTITY: Rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// `Z(ω)` of eq. 3.8 (Rodrigues' formula) for an axis-angle vector `ω` (radians), as a
/// row-major array: [`crate::rotation::rodrigues`], in this module's matrix type.
pub fn rodrigues(omega: [f64; 3]) -> Rotation {
    let m = crate::rotation::rodrigues(omega);
    std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
}

/// `a · b`.
#[inline]
pub fn mul(a: Rotation, b: Rotation) -> Rotation {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// `aᵀ`: the inverse of a rotation.
#[inline]
pub fn transpose(a: Rotation) -> Rotation {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}

#[inline]
fn apply(m: &Rotation, v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// Checks a kinematic tree: every parent is an earlier joint.
pub(crate) fn check_parents(parents: &[Option<usize>]) -> Result<(), FeatureError> {
    for (joint, p) in parents.iter().enumerate() {
        if let Some(parent) = *p {
            if parent >= joint {
                return Err(FeatureError::BadParent { joint, parent });
            }
        }
    }
    Ok(())
}

/// `G_s(θ)` of eq. 3.7 for every joint: the product of the local rotations `Z(ω_p)`
/// down the chain from the root to `s` (inclusive), root leftmost — the rotation part
/// of forward kinematics. `parents[s]` is `None` for a root; parents come before
/// children (SMPL's order, [`crate::joints::SMPL_PARENTS`]). `pose[s]` is joint `s`'s
/// local axis-angle.
pub fn joint_rotations(
    parents: &[Option<usize>],
    pose: &[[f64; 3]],
) -> Result<Vec<Rotation>, FeatureError> {
    check_parents(parents)?;
    if pose.len() != parents.len() {
        return Err(FeatureError::CountMismatch {
            what: "pose rotations vs joints of the kinematic tree",
            expected: parents.len(),
            found: pose.len(),
        });
    }
    check_points(pose, "joint rotation")?;
    let mut g: Vec<Rotation> = Vec::with_capacity(parents.len());
    for (s, &omega) in pose.iter().enumerate() {
        let z = rodrigues(omega);
        g.push(match parents[s] {
            Some(p) => mul(g[p], z),
            None => z,
        });
    }
    Ok(g)
}

/// `G_s(θ) G_s(θ*)⁻¹` for every joint: the rotation each joint applies to rest-pose
/// geometry. `rest_pose = None` means the zero pose (SMPL), where this is `G_s(θ)`.
pub fn relative_rotations(
    parents: &[Option<usize>],
    pose: &[[f64; 3]],
    rest_pose: Option<&[[f64; 3]]>,
) -> Result<Vec<Rotation>, FeatureError> {
    let g = joint_rotations(parents, pose)?;
    match rest_pose {
        None => Ok(g),
        Some(rest) => {
            let g0 = joint_rotations(parents, rest)?;
            Ok(g.iter()
                .zip(&g0)
                .map(|(&a, &b)| mul(a, transpose(b)))
                .collect())
        }
    }
}

/// `r_i(θ)` of eq. 3.9 for every vertex, from its rest-pose position `rest_positions[i]`,
/// its weights `weights.row(i)` and the per-joint `relative` rotations
/// (`G_s(θ) G_s(θ*)⁻¹`, from [`relative_rotations`]); in parallel over vertices.
///
/// Works the same for body vertices (the model's weights) and garment vertices (weights
/// from [`super::transfer`]).
pub fn relative_skinning_descriptor(
    rest_positions: &[[f64; 3]],
    weights: &SkinningWeights,
    relative: &[Rotation],
) -> Result<Vec<[f64; 3]>, FeatureError> {
    if weights.vertex_count() != rest_positions.len() {
        return Err(FeatureError::CountMismatch {
            what: "skinning weight rows vs rest positions",
            expected: rest_positions.len(),
            found: weights.vertex_count(),
        });
    }
    if weights.joint_count() != relative.len() {
        return Err(FeatureError::CountMismatch {
            what: "skinning weight columns vs joint rotations",
            expected: relative.len(),
            found: weights.joint_count(),
        });
    }
    check_points(rest_positions, "rest position")?;
    if let Some(index) = relative
        .iter()
        .position(|m| !m.iter().all(|&row| is_finite(row)))
    {
        return Err(FeatureError::NonFinite {
            what: "joint rotation",
            index,
        });
    }
    Ok(rest_positions
        .par_iter()
        .enumerate()
        .map(|(i, &r)| {
            let mut blended = [[0.0; 3]; 3];
            for (&w, m) in weights.row(i).iter().zip(relative) {
                if w != 0.0 {
                    for a in 0..3 {
                        for b in 0..3 {
                            blended[a][b] += w * m[a][b];
                        }
                    }
                }
            }
            apply(&blended, r)
        })
        .collect())
}

/// [`relative_rotations`] then [`relative_skinning_descriptor`]: `r_i(θ)` from a pose
/// given as local axis-angles over a kinematic tree.
pub fn descriptor_for_pose(
    rest_positions: &[[f64; 3]],
    weights: &SkinningWeights,
    parents: &[Option<usize>],
    pose: &[[f64; 3]],
    rest_pose: Option<&[[f64; 3]]>,
) -> Result<Vec<[f64; 3]>, FeatureError> {
    let relative = relative_rotations(parents, pose, rest_pose)?;
    relative_skinning_descriptor(rest_positions, weights, &relative)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Rotation, b: Rotation) -> bool {
        (0..3).all(|i| (0..3).all(|j| (a[i][j] - b[i][j]).abs() < 1e-12))
    }

    #[test]
    fn rodrigues_closed_forms() {
        let r = rodrigues([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        assert!(close(
            r,
            [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        ));
        assert!(close(rodrigues([0.0; 3]), IDENTITY));
        let r = rodrigues([0.3, -1.2, 0.7]);
        assert!(close(mul(r, transpose(r)), IDENTITY));
    }

    #[test]
    fn chain_rotations_compose_root_first() {
        let parents = [None, Some(0), Some(1)];
        let pose = [[0.0, 0.0, 0.5], [0.0, 0.0, 0.25], [0.1, 0.0, 0.0]];
        let g = joint_rotations(&parents, &pose).unwrap();
        assert!(close(g[1], rodrigues([0.0, 0.0, 0.75])));
        assert!(close(g[2], mul(g[1], rodrigues([0.1, 0.0, 0.0]))));
        assert_eq!(
            joint_rotations(&[None, Some(1)], &pose[..2]),
            Err(FeatureError::BadParent {
                joint: 1,
                parent: 1
            })
        );
    }
}
