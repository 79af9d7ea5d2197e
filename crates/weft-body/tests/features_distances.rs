//! Joint–vertex distances D (seed 000 §3.2) and body-vertex velocities V^t through the
//! body model's own types.

mod features_common;

use features_common::*;
use weft_body::features::{descriptor_for_pose, joint_distances, velocity_window, SkinningWeights};
use weft_body::joints::{SMPL_JOINT_COUNT, SMPL_PARENTS};
use weft_body::{BodyModel, BodyParts, Skinning};
use weft_motion::{Motion, Pose};

/// A 24-joint SMPL-layout model on an icosphere: joint `j` regressed from vertex `3j`,
/// smooth weights, one shape direction that scales the body by 10 % per unit β.
fn sphere_model() -> BodyModel {
    let (p, f) = icosphere(2);
    let v = p.len();
    let mut j_regressor = vec![0.0; SMPL_JOINT_COUNT * v];
    for j in 0..SMPL_JOINT_COUNT {
        j_regressor[j * v + 3 * j] = 1.0;
    }
    let joints: Vec<[f64; 3]> = (0..SMPL_JOINT_COUNT).map(|j| p[3 * j]).collect();
    let mut weights = Vec::with_capacity(v * SMPL_JOINT_COUNT);
    for q in &p {
        let row: Vec<f64> = joints
            .iter()
            .map(|j| (-(0..3).map(|k| (q[k] - j[k]).powi(2)).sum::<f64>() / 0.05).exp() + 1e-12)
            .collect();
        let s: f64 = row.iter().sum();
        weights.extend(row.iter().map(|w| w / s));
    }
    let shapedirs = p.iter().flat_map(|q| q.map(|x| 0.1 * x)).collect();
    BodyModel::new(
        BodyParts {
            v_template: p,
            shapedirs,
            num_betas: 1,
            posedirs: None,
            j_regressor,
            weights,
            parents: SMPL_PARENTS.to_vec(),
            faces: f,
        },
        "test sphere",
    )
    .unwrap()
}

#[test]
fn joint_vertex_distances_follow_the_shape() {
    let model = sphere_model();
    let b0 = model.shaped(&[0.0]).unwrap();
    let b1 = model.shaped(&[1.0]).unwrap();
    let d0 = b0.joint_vertex_distances().unwrap();
    let d1 = b1.joint_vertex_distances().unwrap();
    assert_eq!(
        (d0.rows(), d0.cols()),
        (model.vertex_count(), SMPL_JOINT_COUNT)
    );
    // β = 1 scales the body and its joints by 1.1, so D scales by 1.1.
    for (a, b) in d0.as_slice().iter().zip(d1.as_slice()) {
        assert!((1.1 * a - b).abs() < 1e-12);
    }
    // Joint j sits on vertex 3j: a zero on the diagonal.
    for j in 0..SMPL_JOINT_COUNT {
        assert!(d0.get(3 * j, j).unwrap().abs() < 1e-12);
    }
    assert_eq!(d0.to_f32().len(), model.vertex_count() * SMPL_JOINT_COUNT);
    assert_eq!(d0, joint_distances(&b0.vertices, &b0.joints).unwrap());
}

#[test]
fn velocities_of_a_translating_body() {
    let model = sphere_model();
    let shaped = model.shaped(&[0.0]).unwrap();
    let frames = 6;
    let poses: Vec<Pose> = vec![[[0.0f32; 3]; SMPL_JOINT_COUNT]; frames];
    let trans: Vec<[f32; 3]> = (0..frames).map(|t| [0.05 * t as f32, 0.0, 0.0]).collect();
    let motion = Motion::new(30.0, poses, trans, None).unwrap();
    let w = motion
        .velocity_window(&model, &shaped, 3, 5, Skinning::Lbs)
        .unwrap();
    assert_eq!(
        (w.frame_count(), w.vertex_count()),
        (5, model.vertex_count())
    );
    // Slots 0..3 are frames 3, 2, 1 (1.5 m/s along x); slots 3 and 4 are frame 0 (rest).
    for k in 0..3 {
        for v in w.frame(k) {
            assert!((v[0] - 1.5).abs() < 1e-4 && v[1].abs() < 1e-9 && v[2].abs() < 1e-9);
        }
    }
    for k in 3..5 {
        assert!(w.frame(k).iter().all(|v| *v == [0.0; 3]));
    }
    assert_eq!(w.to_f32().len(), 5 * 3 * model.vertex_count());
    assert!(motion
        .velocity_window(&model, &shaped, frames, 2, Skinning::Lbs)
        .is_err());
    // Mismatched frame sizes are an error, not a panic.
    let ragged = vec![vec![[0.0; 3]; 3], vec![[0.0; 3]; 2]];
    assert!(velocity_window(&ragged, 30.0, 1, 2).is_err());
}

#[test]
fn body_descriptor_through_the_model() {
    let model = sphere_model();
    let shaped = model.shaped(&[0.5]).unwrap();
    let mut pose = [[0.0; 3]; SMPL_JOINT_COUNT];
    pose[0] = [0.1, 0.7, -0.2];
    pose[16] = [0.0, 0.0, 1.2];
    let a = model.relative_skinning_descriptor(&shaped, &pose).unwrap();
    let w = SkinningWeights::try_from(model.weights()).unwrap();
    let b = descriptor_for_pose(&shaped.vertices, &w, &SMPL_PARENTS, &pose, None).unwrap();
    assert_eq!(a, b);
    let s = model.body_surface(&shaped.vertices).unwrap();
    assert!(s.is_closed());
}

#[test]
fn features_of_the_default_body() {
    let model = weft_body::default_body().unwrap();
    let shaped = model.shaped(&[]).unwrap();
    let d = shaped.joint_vertex_distances().unwrap();
    assert_eq!(
        (d.rows(), d.cols()),
        (model.vertex_count(), SMPL_JOINT_COUNT)
    );
    let surface = model.body_surface(&shaped.vertices).unwrap();
    assert!(surface.is_closed());
    // The joints lie inside the body.
    let h = surface.signed_distances(&shaped.joints).unwrap();
    for (j, h) in h.iter().enumerate() {
        assert!(*h < 0.0, "joint {j} is {h} m outside the body");
    }
    // A skirt around the hips: transferred weights are proper rows.
    let mut skirt = weft_mesh::primitives::builtin_garment();
    skirt.positions.iter_mut().for_each(|p| p[1] += 0.1);
    let w = model.skinning_weights().unwrap();
    let t = weft_body::features::transfer_weights(&surface, &w, &skirt.positions).unwrap();
    for i in 0..skirt.vertex_count() {
        let r = t.weights.row(i);
        assert!(r.iter().all(|&x| x >= 0.0) && (r.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
}
