//! Closest point, signed distance and body edges against brute force and closed forms.

mod features_common;

use features_common::*;
use proptest::prelude::*;
use weft_body::query::{BodyEdgeRule, BodySurface, QueryError, SurfaceFeature, VertexTree};

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

#[test]
fn test_meshes_are_closed_and_outward() {
    for m in [
        icosphere(2),
        cuboid([0.0; 3], [1.0, 2.0, 3.0]),
        tube(&u_path(0.3, 0.5, 8), 0.08, 12),
    ] {
        assert!(consistently_oriented(&m));
        assert!(signed_volume6(&m) > 0.0);
        assert!(BodySurface::new(&m.0, &m.1).unwrap().is_closed());
    }
    let (p, f) = plane(4, 1.0, 0.0);
    assert!(!BodySurface::new(&p, &f).unwrap().is_closed());
}

#[test]
fn plane_distances_in_closed_form() {
    let (p, f) = plane(11, 1.0, 0.25);
    let s = BodySurface::new(&p, &f).unwrap();
    for &(x, y, z) in &[(0.1, 1.0, -0.3), (0.33, 0.25, 0.71), (-0.9, -0.5, 0.05)] {
        let c = s.closest_point([x, y, z]).unwrap();
        let h = y - 0.25;
        assert!((c.signed_distance - h).abs() < 1e-12, "{c:?}");
        assert!((c.point[0] - x).abs() < 1e-12 && (c.point[2] - z).abs() < 1e-12);
        assert!((c.interpolated_normal[1] - 1.0).abs() < 1e-12);
        let b = c.barycentric;
        assert!(b.iter().all(|&w| w >= 0.0) && (b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
    // Beyond the border: distance to the border edge, in closed form.
    let c = s.closest_point([1.5, 0.25 + 2.0, 0.0]).unwrap();
    assert!((c.distance - (0.25f64 + 4.0).sqrt()).abs() < 1e-12);
    assert!(matches!(
        c.feature,
        SurfaceFeature::Edge(_) | SurfaceFeature::Vertex(_)
    ));
}

#[test]
fn sphere_sign_and_distance() {
    let (p, f) = icosphere(4);
    let s = BodySurface::new(&p, &f).unwrap();
    // The polyhedron lies inside the unit sphere, within the chordal error.
    let sagitta = 0.01;
    for &r in &[0.0, 0.3, 0.9, 1.1, 2.0, 10.0] {
        for dir in [[1.0, 0.0, 0.0], [0.0, -0.6, 0.8], [0.577, 0.577, -0.578]] {
            let n = norm(dir);
            let q = dir.map(|x| r * x / n);
            let d = s.signed_distance(q).unwrap();
            assert!((d - (r - 1.0)).abs() < sagitta, "r {r}: {d}");
            assert_eq!(d < 0.0, r < 1.0);
        }
    }
}

#[test]
fn box_sign_near_edges_and_corners() {
    let m = cuboid([0.0; 3], [1.0; 3]);
    let s = BodySurface::new(&m.0, &m.1).unwrap();
    // Outside near a corner and an edge: the closest feature is the corner / edge, whose
    // face normals alone can point either way; pseudo-normals give the right sign.
    let c = s.closest_point([1.1, 1.1, 1.1]).unwrap();
    assert_eq!(c.feature, SurfaceFeature::Vertex(7));
    assert!((c.signed_distance - (3.0f64 * 0.01).sqrt()).abs() < 1e-12);
    let c = s.closest_point([0.5, -0.2, -0.2]).unwrap();
    assert!(matches!(c.feature, SurfaceFeature::Edge(_)));
    assert!((c.signed_distance - 0.08f64.sqrt()).abs() < 1e-12);
    // Inside: distance to the nearest face, negative.
    let d = s.signed_distance([0.5, 0.1, 0.5]).unwrap();
    assert!((d + 0.1).abs() < 1e-12);
    // Inside on a diagonal (equidistant to three faces): still negative.
    let d = s.signed_distance([0.2, 0.2, 0.2]).unwrap();
    assert!((d + 0.2).abs() < 1e-12);
    // On the surface: zero.
    assert_eq!(s.signed_distance([1.0, 0.5, 0.5]).unwrap(), 0.0);
}

#[test]
fn refit_and_rebuild_agree_with_a_fresh_surface() {
    let (p, f) = icosphere(3);
    let mut refit = BodySurface::new(&p, &f).unwrap();
    let mut rebuilt = refit.clone();
    // A large, non-rigid motion: stretch and shear.
    let moved: Vec<[f64; 3]> = p
        .iter()
        .map(|v| [2.0 * v[0] + 0.5 * v[1], v[1] + 1.0, 0.5 * v[2]])
        .collect();
    refit.refit(&moved).unwrap();
    rebuilt.rebuild(&moved).unwrap();
    let fresh = BodySurface::new(&moved, &f).unwrap();
    let queries: Vec<[f64; 3]> = (0..200)
        .map(|i| {
            let t = i as f64 * 0.37;
            [3.0 * t.sin(), 1.0 + 2.0 * (1.3 * t).cos(), (0.7 * t).sin()]
        })
        .collect();
    let a = refit.signed_distances(&queries).unwrap();
    let b = rebuilt.signed_distances(&queries).unwrap();
    let c = fresh.signed_distances(&queries).unwrap();
    for i in 0..queries.len() {
        assert!((a[i] - c[i]).abs() < 1e-12 && (b[i] - c[i]).abs() < 1e-12);
    }
    assert_eq!(
        refit.refit(&moved[..10]),
        Err(QueryError::CountMismatch {
            expected: p.len(),
            found: 10
        })
    );
}

#[test]
fn batched_queries_match_single_ones() {
    let (p, f) = icosphere(2);
    let s = BodySurface::new(&p, &f).unwrap();
    let q: Vec<[f64; 3]> = (0..100)
        .map(|i| [0.03 * i as f64 - 1.5, 0.2, 0.1])
        .collect();
    let batch = s.closest_points(&q).unwrap();
    for (c, &x) in batch.iter().zip(&q) {
        assert_eq!(*c, s.closest_point(x).unwrap());
    }
    let mut bad = q.clone();
    bad[7][1] = f64::NAN;
    assert!(matches!(
        s.closest_points(&bad),
        Err(QueryError::NonFinite { index: 7, .. })
    ));
    assert!(s
        .closest_point_within([5.0, 0.0, 0.0], 1.0)
        .unwrap()
        .is_none());
    assert!(s
        .closest_point_within([1.5, 0.0, 0.0], 0.6)
        .unwrap()
        .is_some());
}

#[test]
fn bad_meshes_are_errors() {
    assert!(matches!(
        BodySurface::new(&[[0.0; 3]], &[]),
        Err(QueryError::Empty { .. })
    ));
    assert!(matches!(
        BodySurface::new(&[[0.0; 3]; 3], &[[0, 1, 3]]),
        Err(QueryError::FaceOutOfRange {
            face: 0,
            vertex: 3,
            ..
        })
    ));
    assert!(matches!(
        BodySurface::new(
            &[[0.0; 3], [f64::INFINITY, 0.0, 0.0], [0.0; 3]],
            &[[0, 1, 2]]
        ),
        Err(QueryError::NonFinite { index: 1, .. })
    ));
    assert!(VertexTree::new(&[]).is_err());
    let t = VertexTree::new(&[[0.0; 3]]).unwrap();
    assert_eq!(
        t.within_radius([0.0; 3], -1.0),
        Err(QueryError::BadRadius(-1.0))
    );
}

fn random_soup() -> impl Strategy<Value = Mesh> {
    let coord = -1.0f64..1.0;
    (1usize..40).prop_flat_map(move |n| {
        (
            prop::collection::vec([coord.clone(), coord.clone(), coord.clone()], 3 * n),
            Just(n),
        )
            .prop_map(|(p, n)| {
                let f = (0..n as u32)
                    .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                    .collect();
                (p, f)
            })
    })
}

/// A star-shaped closed mesh: an icosphere with a random positive radius per vertex.
fn random_star() -> impl Strategy<Value = Mesh> {
    let (p0, f) = icosphere(2);
    prop::collection::vec(0.5f64..1.5, p0.len()).prop_map(move |r| {
        let p = p0.iter().zip(&r).map(|(v, &s)| v.map(|x| x * s)).collect();
        (p, f.clone())
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn closest_point_matches_brute_force(
        m in random_soup(),
        q in prop::collection::vec([-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0], 20),
    ) {
        let s = BodySurface::new(&m.0, &m.1).unwrap();
        for &x in &q {
            let c = s.closest_point(x).unwrap();
            let brute = m.1.iter()
                .map(|t| brute_triangle_distance(x, t.map(|i| m.0[i as usize])))
                .fold(f64::INFINITY, f64::min);
            prop_assert!((c.distance - brute).abs() < 1e-9, "{} vs {}", c.distance, brute);
            // The reported point is on the reported triangle at the reported coordinates.
            let t = m.1[c.triangle as usize].map(|i| m.0[i as usize]);
            let b = c.barycentric;
            for (k, &pk) in c.point.iter().enumerate() {
                let y = b[0] * t[0][k] + b[1] * t[1][k] + b[2] * t[2][k];
                prop_assert!((y - pk).abs() < 1e-9);
            }
            prop_assert!((norm([x[0] - c.point[0], x[1] - c.point[1], x[2] - c.point[2]]) - c.distance).abs() < 1e-9);
        }
    }

    #[test]
    fn sign_matches_ray_parity_on_star_shapes(
        m in random_star(),
        q in prop::collection::vec([-1.6f64..1.6, -1.6f64..1.6, -1.6f64..1.6], 30),
    ) {
        let s = BodySurface::new(&m.0, &m.1).unwrap();
        for &x in &q {
            let d = s.signed_distance(x).unwrap();
            if d.abs() > 1e-6 {
                prop_assert_eq!(d < 0.0, inside_by_parity(&m, x), "{:?} {}", x, d);
            }
        }
    }

    #[test]
    fn body_edges_match_brute_force(
        body in prop::collection::vec([-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0], 1..200),
        garment in prop::collection::vec([-1.2f64..1.2, -1.2f64..1.2, -1.2f64..1.2], 1..50),
        radius in 0.0f64..0.6,
    ) {
        let tree = VertexTree::new(&body).unwrap();
        let all = tree.body_edges(&garment, radius, BodyEdgeRule::All).unwrap();
        let nearest = tree.body_edges(&garment, radius, BodyEdgeRule::Nearest).unwrap();
        let two = tree.body_edges(&garment, radius, BodyEdgeRule::NearestK(2)).unwrap();
        let mut brute_all = Vec::new();
        let mut brute_nearest = Vec::new();
        for (g, &x) in garment.iter().enumerate() {
            let mut near: Vec<(f64, u32)> = body.iter().enumerate()
                .map(|(b, &y)| (norm([x[0] - y[0], x[1] - y[1], x[2] - y[2]]), b as u32))
                .filter(|&(d, _)| d <= radius)
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            if let Some(&(_, b)) = near.first() {
                brute_nearest.push([g as u32, b]);
            }
            brute_all.extend(near.iter().map(|&(_, b)| [g as u32, b]));
        }
        prop_assert_eq!(all.iter().map(|e| [e.garment, e.body]).collect::<Vec<_>>(), brute_all);
        prop_assert_eq!(nearest.iter().map(|e| [e.garment, e.body]).collect::<Vec<_>>(), brute_nearest);
        prop_assert!(two.len() <= 2 * garment.len());
        prop_assert!(all.iter().all(|e| e.distance <= radius));
    }
}
