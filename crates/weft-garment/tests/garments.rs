//! Properties every procedural garment must have: vertex count on target, the right
//! openings, one piece, a clean manifold mesh, consistent orientation, determinism.

use std::collections::HashSet;

use weft_garment::{generate, DressTop, Garment, GarmentKind, Measurements, Style};
use weft_mesh::{validate::validate, Topology};

fn make(kind: GarmentKind, seed: u64, vertices: usize) -> Garment {
    let style = Style::from_seed(kind, seed);
    generate(kind, &style, &Measurements::default(), vertices).expect("generate")
}

fn expected_loops(g: &Garment) -> usize {
    match g.kind {
        GarmentKind::Skirt => 2,
        GarmentKind::Dress => match g.style.dress_top {
            DressTop::Strapless => 2,
            _ => 4,
        },
        GarmentKind::TShirt | GarmentKind::Tank | GarmentKind::LongSleeve => 4,
        GarmentKind::Shorts | GarmentKind::Pants => 3,
        GarmentKind::Jumpsuit => 5,
    }
}

fn check(g: &Garment, target: usize) {
    let name = g.kind.name();
    let n = g.mesh.vertex_count();
    let err = (n as f64 - target as f64).abs() / target as f64;
    assert!(err <= 0.15, "{name}: {n} vertices for target {target}");
    let findings = validate(&g.mesh);
    assert!(
        findings.is_empty(),
        "{name} at {target}: {:?}",
        &findings[..findings.len().min(5)]
    );
    let topo = Topology::new(&g.mesh);
    let loops = topo.boundary_loops();
    assert_eq!(
        loops.len(),
        expected_loops(g),
        "{name} ({:?}) at {target}: loop sizes {:?}",
        g.style.dress_top,
        loops.iter().map(Vec::len).collect::<Vec<_>>()
    );
    assert!(
        topo.non_manifold_edges().is_empty(),
        "{name}: non-manifold edges"
    );
    assert_eq!(
        g.mesh.graph().components().members().len(),
        1,
        "{name}: not one piece"
    );
    // Consistent orientation: every directed edge is walked by at most one face.
    let mut seen = HashSet::new();
    for f in &g.mesh.faces {
        for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
            assert!(
                seen.insert((a, b)),
                "{name}: edge {a}->{b} walked twice (inconsistent orientation)"
            );
        }
    }
    assert_eq!(g.corner_uvs.len(), g.mesh.face_count());
}

#[test]
fn every_kind_at_several_resolutions() {
    for kind in GarmentKind::ALL {
        for target in [500, 2000, 5000, 12_000] {
            let g = make(kind, 1, target);
            check(&g, target);
        }
    }
}

#[test]
fn every_dress_top_and_skirt_length() {
    for top in [DressTop::Strapless, DressTop::Straps, DressTop::Sleeves] {
        for seed in 0..3 {
            let mut style = Style::from_seed(GarmentKind::Dress, seed);
            style.dress_top = top;
            let g = generate(GarmentKind::Dress, &style, &Measurements::default(), 3000)
                .expect("dress");
            check(&g, 3000);
        }
    }
    for seed in 0..6 {
        check(&make(GarmentKind::Skirt, seed, 1500), 1500);
    }
}

#[test]
fn deterministic_for_a_seed_and_varied_across_seeds() {
    for kind in GarmentKind::ALL {
        let a = make(kind, 7, 2500);
        let b = make(kind, 7, 2500);
        assert_eq!(a, b, "{}: same seed, different garment", kind.name());
        let c = make(kind, 8, 2500);
        assert_ne!(
            a.mesh.positions,
            c.mesh.positions,
            "{}: seeds 7 and 8 agree",
            kind.name()
        );
    }
}

#[test]
fn topology_and_size_vary_across_kinds_and_resolutions() {
    let mut seen = HashSet::new();
    for kind in GarmentKind::ALL {
        for target in [800, 4000] {
            let g = make(kind, 0, target);
            seen.insert((g.mesh.vertex_count(), g.mesh.face_count()));
        }
    }
    assert_eq!(
        seen.len(),
        2 * GarmentKind::ALL.len(),
        "two garments share vertex and face counts"
    );
}

#[test]
fn uvs_are_close_to_the_rest_lengths() {
    // The unwrap is developable only approximately (cones, shoulder arcs), but UV edge
    // lengths must stay near the 3D ones for rest frames to be sensible.
    for kind in GarmentKind::ALL {
        let g = make(kind, 0, 3000);
        let mut ratios = Vec::new();
        for (f, uv) in g.mesh.faces.iter().zip(&g.corner_uvs) {
            for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                let p = g.mesh.positions[f[i] as usize];
                let q = g.mesh.positions[f[j] as usize];
                let l3 =
                    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
                let l2 = ((uv[i][0] - uv[j][0]).powi(2) + (uv[i][1] - uv[j][1]).powi(2)).sqrt();
                ratios.push(l2 / l3);
            }
        }
        ratios.sort_by(f64::total_cmp);
        let median = ratios[ratios.len() / 2];
        let p95 = ratios[ratios.len() * 95 / 100];
        assert!(
            (0.8..1.25).contains(&median),
            "{}: median UV/3D edge ratio {median}",
            kind.name()
        );
        assert!(
            p95 < 2.0,
            "{}: 95th percentile UV/3D edge ratio {p95}",
            kind.name()
        );
    }
}

#[test]
fn bad_arguments_are_errors() {
    let style = Style::from_seed(GarmentKind::Skirt, 0);
    let m = Measurements::default();
    assert!(generate(GarmentKind::Skirt, &style, &m, 10).is_err());
    assert!(generate(GarmentKind::Skirt, &style, &m, 10_000_000).is_err());
    let mut bad = style;
    bad.flare = f64::NAN;
    assert!(generate(GarmentKind::Skirt, &bad, &m, 1000).is_err());
    assert!(GarmentKind::parse("hat").is_err());
    for (k, n) in GarmentKind::ALL.iter().zip(GarmentKind::NAMES) {
        assert_eq!(GarmentKind::parse(n).ok(), Some(*k));
    }
}

#[test]
fn triangles_have_reasonable_aspect() {
    // Aspect = longest edge / (2·√3·inradius): 1 for equilateral.
    for kind in GarmentKind::ALL {
        let g = make(kind, 0, 4000);
        let mut worst = 0.0f64;
        let mut bad = 0;
        for f in &g.mesh.faces {
            let p = f.map(|i| g.mesh.positions[i as usize]);
            let l = |a: [f64; 3], b: [f64; 3]| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            };
            let (a, b, c) = (l(p[0], p[1]), l(p[1], p[2]), l(p[2], p[0]));
            let s = 0.5 * (a + b + c);
            let area = (s * (s - a) * (s - b) * (s - c)).max(0.0).sqrt();
            let aspect = a.max(b).max(c) * s / (2.0 * 3f64.sqrt() * area.max(1e-300));
            worst = worst.max(aspect);
            bad += usize::from(aspect > 6.0);
        }
        eprintln!(
            "{}: worst aspect {worst:.2}, {bad} of {} above 6",
            kind.name(),
            g.mesh.face_count()
        );
        assert!(
            bad * 100 <= g.mesh.face_count(),
            "{}: {bad} triangles with aspect above 6",
            kind.name()
        );
    }
}
