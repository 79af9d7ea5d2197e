//! Volumetric point-to-joint distances: Euclidean where the straight segment stays in
//! the body, never below Euclidean, continuous, and routed through the skeleton where
//! the straight segment crosses air.

mod features_common;

use features_common::*;
use proptest::prelude::*;
use weft_body::features::{joint_distances, FeatureError, VolumetricDistance, VolumetricParams};
use weft_body::query::BodySurface;

const RU: f64 = 0.3;
const H: f64 = 0.6;

/// A U-shaped closed tube (radius 8 cm) with a 7-joint skeleton along its centreline:
/// root at the bottom, three joints up each arm.
fn u_body() -> (Mesh, Vec<[f64; 3]>, Vec<Option<usize>>) {
    let mesh = tube(&u_path(RU, H, 24), 0.08, 24);
    let at = |deg: f64| {
        let a = deg.to_radians();
        [RU * a.cos(), RU * a.sin(), 0.0]
    };
    let joints = vec![
        at(270.0),
        at(225.0),
        at(180.0),
        [-RU, H - 0.05, 0.0],
        at(315.0),
        at(360.0),
        [RU, H - 0.05, 0.0],
    ];
    let parents = vec![None, Some(0), Some(1), Some(2), Some(0), Some(4), Some(5)];
    (mesh, joints, parents)
}

fn tree_length(joints: &[[f64; 3]], path: &[usize]) -> f64 {
    path.windows(2)
        .map(|w| {
            let (a, b) = (joints[w[0]], joints[w[1]]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .sum()
}

#[test]
fn equals_euclidean_inside_a_convex_body() {
    let (p, f) = ellipsoid(3, [0.3, 0.8, 0.2], [0.0, 1.0, 0.0]);
    let s = BodySurface::new(&p, &f).unwrap();
    let joints = vec![[0.0, 1.0, 0.0], [0.0, 1.5, 0.0], [0.1, 0.5, 0.0]];
    let parents = vec![None, Some(0), Some(0)];
    let v = VolumetricDistance::new(&s, &joints, &parents, VolumetricParams::default()).unwrap();
    let points: Vec<[f64; 3]> = vec![[0.0, 1.0, 0.1], [0.2, 0.9, -0.05], [-0.1, 1.6, 0.0]];
    let vol = v.matrix(&points).unwrap();
    let euc = joint_distances(&points, &joints).unwrap();
    for (a, b) in vol.as_slice().iter().zip(euc.as_slice()) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
    // Surface vertices of a convex body: the segments run inside (up to rounding at
    // the start point).
    let vol = v.matrix(&p).unwrap();
    let euc = joint_distances(&p, &joints).unwrap();
    for (a, b) in vol.as_slice().iter().zip(euc.as_slice()) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
}

#[test]
fn routes_through_the_skeleton_across_a_gap() {
    let (m, joints, parents) = u_body();
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    let v = VolumetricDistance::new(&s, &joints, &parents, VolumetricParams::default()).unwrap();
    // Near the left tip, inside; the right tip joint is 0.6 m away across the air.
    let p = [-RU + 0.02, H - 0.05, 0.0];
    let d = v.distances(p).unwrap();
    let euclid = (2.0 * RU - 0.02f64).abs();
    let along = tree_length(&joints, &[3, 2, 1, 0, 4, 5, 6]);
    assert!(d[6] > along - 0.05, "{} vs skeleton {along}", d[6]);
    assert!(d[6] < along + 0.05, "{} vs skeleton {along}", d[6]);
    assert!(d[6] > 2.0 * euclid);
    // Its own arm's tip joint is in line of sight inside the tube: Euclidean.
    assert!((d[3] - 0.02).abs() < 1e-9);
}

#[test]
fn continuous_along_a_sweep_across_the_body() {
    let (m, joints, parents) = u_body();
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    let v = VolumetricDistance::new(&s, &joints, &parents, VolumetricParams::default()).unwrap();
    // From outside the left arm, through its wall and interior and out across the gap:
    // sweep, find the largest jump between neighbouring samples, zoom in around it and
    // sweep again. A discontinuity would keep its jump while the step shrinks; here the
    // jump must shrink with the step (a local Lipschitz bound; the function is steep
    // where a segment grazes the surface, about λ times the grazing slope).
    let (mut lo, mut hi) = (-RU - 0.05, -RU + 0.13);
    let n = 400;
    for _level in 0..4 {
        let step = (hi - lo) / n as f64;
        let pts: Vec<[f64; 3]> = (0..=n).map(|k| [lo + step * k as f64, 0.3, 0.01]).collect();
        let d = v.matrix(&pts).unwrap();
        let mut worst = (0.0f64, 0usize);
        for k in 0..n {
            for j in 0..joints.len() {
                let jump = (d.row(k + 1)[j] - d.row(k)[j]).abs();
                if jump > worst.0 {
                    worst = (jump, k);
                }
            }
        }
        assert!(
            worst.0 <= 1e4 * step,
            "jump {} over a step of {step}",
            worst.0
        );
        lo = pts[worst.1][0] - step;
        hi = pts[worst.1][0] + 2.0 * step;
    }
}

#[test]
fn bad_parameters_are_errors() {
    let (m, joints, parents) = u_body();
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    let p = VolumetricParams {
        samples: 0,
        ..Default::default()
    };
    assert!(matches!(
        VolumetricDistance::new(&s, &joints, &parents, p),
        Err(FeatureError::BadParameter {
            name: "samples",
            ..
        })
    ));
    assert!(matches!(
        VolumetricDistance::new(&s, &joints, &parents[..3], VolumetricParams::default()),
        Err(FeatureError::CountMismatch { .. })
    ));
    let mut bad = parents.clone();
    bad[2] = Some(5);
    assert!(matches!(
        VolumetricDistance::new(&s, &joints, &bad, VolumetricParams::default()),
        Err(FeatureError::BadParent {
            joint: 2,
            parent: 5
        })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn never_below_euclidean(
        pts in prop::collection::vec([-0.5f64..0.5, -0.5f64..0.8, -0.2f64..0.2], 1..8),
    ) {
        let (m, joints, parents) = u_body();
        let s = BodySurface::new(&m.0, &m.1).unwrap();
        let v = VolumetricDistance::new(&s, &joints, &parents, VolumetricParams::default()).unwrap();
        let vol = v.matrix(&pts).unwrap();
        let euc = joint_distances(&pts, &joints).unwrap();
        for (a, b) in vol.as_slice().iter().zip(euc.as_slice()) {
            prop_assert!(*a >= *b - 1e-12, "{} < {}", a, b);
        }
    }
}
