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
