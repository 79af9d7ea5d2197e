//! No garment crosses itself in rest pose: no edge passes through a triangle it does not
//! touch (for two triangles in general position, they intersect iff an edge of one
//! crosses the other).

use std::collections::HashMap;

use weft_garment::{generate, DressTop, FitBody, GarmentKind, Measurements, Style};
use weft_mesh::vec3::{cross, dot, sub};
use weft_mesh::TriMesh;

/// Möller–Trumbore: does segment p→q cross triangle t (strictly inside)?
fn segment_hits(p: [f64; 3], q: [f64; 3], t: [[f64; 3]; 3]) -> bool {
    let d = sub(q, p);
    let e1 = sub(t[1], t[0]);
    let e2 = sub(t[2], t[0]);
    let h = cross(d, e2);
    let a = dot(e1, h);
    if a.abs() < 1e-14 {
        return false;
    }
    let f = 1.0 / a;
    let s = sub(p, t[0]);
    let u = f * dot(s, h);
    let qv = cross(s, e1);
    let v = f * dot(d, qv);
    let w = f * dot(e2, qv);
    let eps = 1e-9;
    u > eps && v > eps && u + v < 1.0 - eps && w > eps && w < 1.0 - eps
}

fn crossings(mesh: &TriMesh) -> usize {
    let tri = |f: &[u32; 3]| f.map(|i| mesh.positions[i as usize]);
    let cell = mesh
        .edges()
        .iter()
        .map(|e| {
            let d = sub(mesh.positions[e[0] as usize], mesh.positions[e[1] as usize]);
            dot(d, d).sqrt()
        })
        .fold(0.0, f64::max)
        .max(1e-6);
    let key = |p: [f64; 3]| p.map(|c| (c / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (fi, f) in mesh.faces.iter().enumerate() {
        let t = tri(f);
        let lo = key([0, 1, 2].map(|a| t.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min)));
        let hi = key([0, 1, 2].map(|a| t.iter().map(|p| p[a]).fold(f64::NEG_INFINITY, f64::max)));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    grid.entry([x, y, z]).or_default().push(fi);
                }
            }
        }
    }
    let mut hits = 0;
    for e in mesh.edges() {
        let (p, q) = (mesh.positions[e[0] as usize], mesh.positions[e[1] as usize]);
        let lo = key([0, 1, 2].map(|a| p[a].min(q[a])));
        let hi = key([0, 1, 2].map(|a| p[a].max(q[a])));
        let mut seen = Vec::new();
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    for &fi in grid.get(&[x, y, z]).map(Vec::as_slice).unwrap_or(&[]) {
                        let f = mesh.faces[fi];
                        if f.contains(&e[0]) || f.contains(&e[1]) || seen.contains(&fi) {
                            continue;
                        }
                        seen.push(fi);
                        if segment_hits(p, q, tri(&f)) {
                            hits += 1;
                        }
                    }
                }
            }
        }
    }
    hits
}

fn styles(kind: GarmentKind) -> Vec<Style> {
    (0..3)
        .map(|seed| {
            let mut s = Style::from_seed(kind, seed);
            if kind == GarmentKind::Dress {
                s.dress_top =
                    [DressTop::Strapless, DressTop::Straps, DressTop::Sleeves][seed as usize];
            }
            s
        })
        .collect()
}

#[test]
fn default_measurement_garments_do_not_cross_themselves() {
    let mut report = Vec::new();
    for kind in GarmentKind::ALL {
        for style in styles(kind) {
            let g = generate(kind, &style, &Measurements::default(), 2500).expect("generate");
            let n = crossings(&g.mesh);
            if n > 0 {
                report.push(format!("{} {:?}: {n}", kind.name(), style.dress_top));
            }
        }
    }
    assert!(report.is_empty(), "self-intersections: {report:?}");
}

#[test]
fn default_body_garments_do_not_cross_themselves() {
    let model = weft_body::default_body().expect("default body");
    let mut report = Vec::new();
    for betas in [vec![], vec![1.5, -1.0]] {
        let fit = FitBody::new(&model, &betas).expect("fit");
        for kind in GarmentKind::ALL {
            for style in styles(kind) {
                let g = fit.generate(kind, &style, 2500).expect("generate");
                let n = crossings(&g.mesh);
                if n > 0 {
                    report.push(format!(
                        "{} {:?} β={betas:?}: {n}",
                        kind.name(),
                        style.dress_top
                    ));
                }
            }
        }
    }
    assert!(report.is_empty(), "self-intersections: {report:?}");
}
