//! The relative skinning descriptor r_i(θ) of seed 001 eq. 3.7–3.9.

mod features_common;

use features_common::*;
use nalgebra::Matrix3;
use proptest::prelude::*;
use weft_body::features::{
    descriptor_for_pose, descriptor_from_transforms, relative_rotations,
    relative_skinning_descriptor, rodrigues, transfer_weights, SkinningWeights,
};
use weft_body::kinematics::Skeleton;
use weft_body::query::BodySurface;
use weft_body::rotation;
use weft_body::skinning::{lbs, SkinWeights};

/// An ellipsoid "body" with a three-joint chain (root, spine, arm) and smooth weights.
fn rig() -> (Mesh, Vec<[f64; 3]>, Vec<Option<usize>>, SkinningWeights) {
    let m = ellipsoid(2, [0.4, 0.6, 0.2], [0.0, 0.5, 0.0]);
    let joints = vec![[0.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.3, 0.7, 0.0]];
    let parents = vec![None, Some(0), Some(1)];
    let mut w = Vec::new();
    for p in &m.0 {
        for j in &joints {
            let d2: f64 = (0..3).map(|k| (p[k] - j[k]).powi(2)).sum();
            w.push((-d2 / 0.05).exp() + 1e-9);
        }
    }
    let w = SkinningWeights::new(w, joints.len()).unwrap();
    (m, joints, parents, w)
}

fn pose_strategy() -> impl Strategy<Value = Vec<[f64; 3]>> {
    prop::collection::vec([-1.5f64..1.5, -1.5f64..1.5, -1.5f64..1.5], 3)
}

fn close(a: &[[f64; 3]], b: &[[f64; 3]], tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (0..3).all(|k| (x[k] - y[k]).abs() <= tol))
}

#[test]
fn rest_pose_gives_rest_positions() {
    let (m, _, parents, w) = rig();
    let r = descriptor_for_pose(&m.0, &w, &parents, &[[0.0; 3]; 3], None).unwrap();
    assert!(close(&r, &m.0, 1e-12));
    // A non-zero rest pose θ*: at θ = θ*, G(θ) G(θ*)⁻¹ = I again.
    let rest = [[0.1, 0.2, -0.3], [0.0, 0.5, 0.0], [0.7, 0.0, 0.1]];
    let r = descriptor_for_pose(&m.0, &w, &parents, &rest, Some(&rest)).unwrap();
    assert!(close(&r, &m.0, 1e-12));
}

#[test]
fn a_root_rotation_rotates_every_vertex() {
    let (m, _, parents, w) = rig();
    let omega = [0.3, -0.8, 0.2];
    let r = descriptor_for_pose(&m.0, &w, &parents, &[omega, [0.0; 3], [0.0; 3]], None).unwrap();
    let rot = rodrigues(omega);
    let expected: Vec<[f64; 3]> =
        m.0.iter()
            .map(|p| std::array::from_fn(|i| (0..3).map(|k| rot[i][k] * p[k]).sum()))
            .collect();
    assert!(close(&r, &expected, 1e-12));
}

#[test]
fn errors_name_the_mismatch() {
    let (m, _, parents, w) = rig();
    let rel = relative_rotations(&parents, &[[0.0; 3]; 3], None).unwrap();
    assert!(relative_skinning_descriptor(&m.0[..5], &w, &rel).is_err());
    assert!(relative_skinning_descriptor(&m.0, &w, &rel[..2]).is_err());
    assert!(relative_rotations(&parents, &[[0.0; 3]; 2], None).is_err());
    assert!(relative_rotations(&parents, &[[f64::NAN, 0.0, 0.0]; 3], None).is_err());
}

#[test]
fn garment_vertex_on_a_body_vertex_gets_its_descriptor() {
    let (m, _, parents, w) = rig();
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    let garment: Vec<[f64; 3]> = m.0.iter().step_by(7).copied().collect();
    let t = transfer_weights(&s, &w, &garment).unwrap();
    let pose = [[0.2, 0.1, 0.0], [0.0, 0.4, -0.3], [1.0, 0.0, 0.2]];
    let body = descriptor_for_pose(&m.0, &w, &parents, &pose, None).unwrap();
    let gar = descriptor_for_pose(&garment, &t.weights, &parents, &pose, None).unwrap();
    let expected: Vec<[f64; 3]> = body.iter().step_by(7).copied().collect();
    assert!(close(&gar, &expected, 1e-12));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Seed 001's claim: r_i(θ) does not change when the character is translated,
    /// although the posed (LBS) vertices move with it.
    #[test]
    fn translation_invariant(pose in pose_strategy(), t in [-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0]) {
        let (m, joints, parents, w) = rig();
        let skeleton = Skeleton::new(parents.clone()).unwrap();
        let rotations: Vec<Matrix3<f64>> = pose.iter().map(|&o| rotation::rodrigues(o)).collect();
        let g0 = skeleton.global_transforms(&joints, &rotations, [0.0; 3]).unwrap();
        let g1 = skeleton.global_transforms(&joints, &rotations, t).unwrap();
        let r0 = descriptor_from_transforms(&m.0, &w, &g0, None).unwrap();
        let r1 = descriptor_from_transforms(&m.0, &w, &g1, None).unwrap();
        prop_assert!(close(&r0, &r1, 1e-12));
        // The posed vertices themselves move by t.
        let sparse = SkinWeights::from_dense(w.as_slice(), 3);
        let a0 = skeleton.skinning_transforms(&joints, &rotations, [0.0; 3]).unwrap();
        let a1 = skeleton.skinning_transforms(&joints, &rotations, t).unwrap();
        let (p0, p1) = (lbs(&m.0, &sparse, &a0), lbs(&m.0, &sparse, &a1));
        let shifted: Vec<[f64; 3]> = p0.iter().map(|p| [p[0] + t[0], p[1] + t[1], p[2] + t[2]]).collect();
        prop_assert!(close(&p1, &shifted, 1e-9));
        // Eq. 3.9 from axis-angles agrees with the transform route.
        let r2 = descriptor_for_pose(&m.0, &w, &parents, &pose, None).unwrap();
        prop_assert!(close(&r0, &r2, 1e-12));
    }

    /// r_i(θ) is LBS with every joint at the origin and no translation (eq. 3.9 vs
    /// seed 001 eq. 2.1).
    #[test]
    fn equals_lbs_with_joints_at_the_origin(pose in pose_strategy()) {
        let (m, _, parents, w) = rig();
        let skeleton = Skeleton::new(parents.clone()).unwrap();
        let rotations: Vec<Matrix3<f64>> = pose.iter().map(|&o| rotation::rodrigues(o)).collect();
        let a = skeleton.skinning_transforms(&[[0.0; 3]; 3], &rotations, [0.0; 3]).unwrap();
        let posed = lbs(&m.0, &SkinWeights::from_dense(w.as_slice(), 3), &a);
        let r = descriptor_for_pose(&m.0, &w, &parents, &pose, None).unwrap();
        prop_assert!(close(&r, &posed, 1e-12));
    }
}
