//! Skinning-weight transfer body → garment, plain and diffused.

mod features_common;

use features_common::*;
use proptest::prelude::*;
use weft_body::features::{
    diffuse_weights, transfer_weights, transfer_weights_diffused, DiffusionParams, FeatureError,
    SkinningWeights,
};
use weft_body::query::BodySurface;
use weft_mesh::primitives::cylinder;
use weft_mesh::TriMesh;

/// Smooth weights of three joints on the x axis (left +x, centre, right −x): mirror
/// symmetric, joint 0 ↔ joint 2 under x → −x.
fn symmetric_weights(p: &[[f64; 3]]) -> SkinningWeights {
    let joints = [[0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [-0.5, 0.0, 0.0]];
    let mut w = Vec::new();
    for v in p {
        for j in &joints {
            let d2: f64 = (0..3).map(|k| (v[k] - j[k]).powi(2)).sum();
            w.push((-d2 / 0.1).exp());
        }
    }
    SkinningWeights::new(w, 3).unwrap()
}

fn row_ok(w: &SkinningWeights) -> bool {
    (0..w.vertex_count()).all(|i| {
        let r = w.row(i);
        r.iter().all(|&x| x >= 0.0) && (r.iter().sum::<f64>() - 1.0).abs() < 1e-12
    })
}

#[test]
fn exact_on_the_body_surface() {
    let m = icosphere(3);
    let w = symmetric_weights(&m.0);
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    // Points on faces at known barycentric coordinates, and the vertices themselves.
    let mut garment = Vec::new();
    let mut expected = Vec::new();
    for (k, f) in m.1.iter().enumerate().step_by(13) {
        let b = [
            0.2 + 0.001 * (k % 7) as f64,
            0.5,
            0.3 - 0.001 * (k % 7) as f64,
        ];
        let [a, bb, c] = f.map(|i| m.0[i as usize]);
        garment.push(std::array::from_fn(|i| {
            b[0] * a[i] + b[1] * bb[i] + b[2] * c[i]
        }));
        expected.push(
            (0..3)
                .map(|j| (0..3).map(|c| b[c] * w.row(f[c] as usize)[j]).sum::<f64>())
                .collect::<Vec<_>>(),
        );
    }
    for (v, p) in m.0.iter().enumerate().step_by(11) {
        garment.push(*p);
        expected.push(w.row(v).to_vec());
    }
    let t = transfer_weights(&s, &w, &garment).unwrap();
    assert!(row_ok(&t.weights));
    for (i, e) in expected.iter().enumerate() {
        for (got, want) in t.weights.row(i).iter().zip(e) {
            assert!((got - want).abs() < 1e-9, "point {i}");
        }
        assert!(t.closest[i].distance < 1e-12);
    }
}

#[test]
fn mismatched_weights_are_an_error() {
    let m = icosphere(1);
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    let w = symmetric_weights(&m.0[..10]);
    assert!(matches!(
        transfer_weights(&s, &w, &[[0.0; 3]]),
        Err(FeatureError::CountMismatch { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn rows_sum_to_one_and_mirror_symmetrically(
        pts in prop::collection::vec([-1.5f64..1.5, -1.5f64..1.5, -1.5f64..1.5], 1..40),
    ) {
        // The icosphere is symmetric under x → −x (vertex set and faces).
        let m = icosphere(3);
        let w = symmetric_weights(&m.0);
        let s = BodySurface::new(&m.0, &m.1).unwrap();
        let mirrored: Vec<[f64; 3]> = pts.iter().map(|p| [-p[0], p[1], p[2]]).collect();
        let a = transfer_weights(&s, &w, &pts).unwrap();
        let b = transfer_weights(&s, &w, &mirrored).unwrap();
        prop_assert!(row_ok(&a.weights) && row_ok(&b.weights));
        for i in 0..pts.len() {
            let (ra, rb) = (a.weights.row(i), b.weights.row(i));
            prop_assert!((ra[0] - rb[2]).abs() < 1e-9 && (ra[1] - rb[1]).abs() < 1e-9 && (ra[2] - rb[0]).abs() < 1e-9,
                "{:?} vs {:?}", ra, rb);
        }
    }
}

/// Two legs (closed tubes at x = ±0.12) with one joint each, and a loose tube skirt
/// around both: the case diffusion exists for.
fn legs_and_skirt() -> (Mesh, SkinningWeights, TriMesh) {
    let leg = |x: f64| tube(&[[x, 0.9, 0.0], [x, 0.5, 0.0], [x, 0.1, 0.0]], 0.07, 16);
    let (mut p, mut f) = leg(0.12);
    let (p2, f2) = leg(-0.12);
    let off = p.len() as u32;
    let left = p.len();
    p.extend(p2);
    f.extend(f2.iter().map(|t| t.map(|i| i + off)));
    let w: Vec<f64> = (0..p.len())
        .flat_map(|v| if v < left { [1.0, 0.0] } else { [0.0, 1.0] })
        .collect();
    let weights = SkinningWeights::new(w, 2).unwrap();
    let mut skirt = cylinder(30, 60, 0.3, 0.02);
    for q in &mut skirt.positions {
        q[1] += 0.9;
    }
    ((p, f), weights, skirt)
}

/// The largest change of joint-0 weight across one garment edge.
fn max_edge_jump(g: &TriMesh, w: &SkinningWeights) -> f64 {
    g.edges()
        .iter()
        .map(|&[a, b]| (w.row(a as usize)[0] - w.row(b as usize)[0]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn diffusion_mends_the_tear_between_the_legs() {
    let (body, w, skirt) = legs_and_skirt();
    let s = BodySurface::new(&body.0, &body.1).unwrap();
    let plain = transfer_weights(&s, &w, &skirt.positions).unwrap();
    let diffused = transfer_weights_diffused(&s, &w, &skirt, &DiffusionParams::default()).unwrap();
    assert!(row_ok(&diffused.weights));
    // Plain transfer snaps each skirt vertex to one leg: a full 0 → 1 tear.
    assert!(max_edge_jump(&skirt, &plain.weights) > 0.99);
    // Diffused weights blend smoothly around the skirt.
    let jump = max_edge_jump(&skirt, &diffused.weights);
    assert!(jump < 0.2, "largest jump {jump}");
}

#[test]
fn tight_vertices_keep_their_weights() {
    // The garment is the body's own surface, pushed out by 20 cm below y = 0.
    let m = icosphere(3);
    let w = symmetric_weights(&m.0);
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    let garment = TriMesh::new(
        m.0.iter()
            .map(|p| if p[1] < 0.0 { p.map(|x| 1.2 * x) } else { *p })
            .collect(),
        m.1.clone(),
    );
    let plain = transfer_weights(&s, &w, &garment.positions).unwrap();
    let params = DiffusionParams::default();
    let d = transfer_weights_diffused(&s, &w, &garment, &params).unwrap();
    assert!(row_ok(&d.weights));
    let mut moved = 0;
    for (i, c) in plain.closest.iter().enumerate() {
        if c.distance <= params.tight_distance {
            // Unchanged up to the final renormalisation's rounding.
            for (a, b) in d.weights.row(i).iter().zip(plain.weights.row(i)) {
                assert!((a - b).abs() < 1e-15);
            }
        } else if d.weights.row(i) != plain.weights.row(i) {
            moved += 1;
        }
    }
    assert!(moved > 0);
    // No smoothing length: nothing moves.
    let none = DiffusionParams {
        smoothing_length: 0.0,
        ..params
    };
    let d0 = transfer_weights_diffused(&s, &w, &garment, &none).unwrap();
    for (a, b) in d0.weights.as_slice().iter().zip(plain.weights.as_slice()) {
        assert!((a - b).abs() < 1e-15);
    }
}

#[test]
fn uniform_weights_stay_uniform_and_bad_parameters_fail() {
    let g = cylinder(10, 12, 0.3, 0.05);
    let n = g.vertex_count();
    let w = SkinningWeights::new(vec![1.0; 4 * n], 4).unwrap();
    let far = vec![1.0; n];
    let out = diffuse_weights(
        &g.graph(),
        &g.positions,
        &w,
        &far,
        &DiffusionParams::default(),
    )
    .unwrap();
    for i in 0..n {
        for &x in out.row(i) {
            assert!((x - 0.25).abs() < 1e-12);
        }
    }
    let bad = DiffusionParams {
        loose_distance: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        diffuse_weights(&g.graph(), &g.positions, &w, &far, &bad),
        Err(FeatureError::BadParameter {
            name: "loose_distance",
            ..
        })
    ));
    assert!(matches!(
        diffuse_weights(
            &g.graph(),
            &g.positions,
            &w,
            &far[..3],
            &DiffusionParams::default()
        ),
        Err(FeatureError::CountMismatch { .. })
    ));
}
