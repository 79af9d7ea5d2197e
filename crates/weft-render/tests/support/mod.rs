//! Procedural stand-ins for the pictures' subjects, shared by tests, the benchmark and
//! the gallery example: a mannequin-like body made of ellipsoids (until weft-body's
//! default body lands) and a flared, folded skirt over it.
#![allow(dead_code)]

use std::f64::consts::{PI, TAU};
use weft_mesh::primitives::cylinder;
use weft_mesh::TriMesh;

/// A closed ellipsoid of `rings × around` vertices plus two poles.
pub fn ellipsoid(center: [f64; 3], radii: [f64; 3], rings: usize, around: usize) -> TriMesh {
    let mut positions = vec![[center[0], center[1] + radii[1], center[2]]];
    for r in 1..=rings {
        let theta = PI * r as f64 / (rings + 1) as f64;
        for k in 0..around {
            let phi = TAU * k as f64 / around as f64;
            positions.push([
                center[0] + radii[0] * theta.sin() * phi.cos(),
                center[1] + radii[1] * theta.cos(),
                center[2] + radii[2] * theta.sin() * phi.sin(),
            ]);
        }
    }
    positions.push([center[0], center[1] - radii[1], center[2]]);
    let south = (positions.len() - 1) as u32;
    let id = |r: usize, k: usize| (1 + (r - 1) * around + k % around) as u32;
    let mut faces = Vec::new();
    for k in 0..around {
        faces.push([0, id(1, k + 1), id(1, k)]);
        faces.push([south, id(rings, k), id(rings, k + 1)]);
    }
    for r in 1..rings {
        for k in 0..around {
            faces.push([id(r, k), id(r, k + 1), id(r + 1, k + 1)]);
            faces.push([id(r, k), id(r + 1, k + 1), id(r + 1, k)]);
        }
    }
    TriMesh::new(positions, faces)
}

/// Concatenates meshes into one.
pub fn merge(parts: &[TriMesh]) -> TriMesh {
    let mut out = TriMesh::default();
    for p in parts {
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&p.positions);
        out.faces
            .extend(p.faces.iter().map(|f| f.map(|i| i + base)));
    }
    out
}

/// A standing, body-sized figure (1.72 m, facing +Z) of about 7 000 vertices.
pub fn mannequin() -> TriMesh {
    let e = |c, r| ellipsoid(c, r, 28, 40);
    merge(&[
        e([0.0, 1.62, 0.0], [0.085, 0.11, 0.095]),
        e([0.0, 1.47, 0.0], [0.05, 0.07, 0.05]),
        e([0.0, 1.22, 0.0], [0.17, 0.24, 0.105]),
        e([0.0, 0.97, 0.0], [0.16, 0.12, 0.11]),
        e([-0.09, 0.5, 0.0], [0.075, 0.44, 0.08]),
        e([0.09, 0.5, 0.0], [0.075, 0.44, 0.08]),
        e([-0.215, 1.14, 0.0], [0.045, 0.3, 0.05]),
        e([0.215, 1.14, 0.0], [0.045, 0.3, 0.05]),
    ])
}

/// The benchmark's garment: `cylinder(120, 100, 0.3, 0.01)` (12 000 vertices), lifted
/// to hang from y = 1.45 m around the mannequin.
pub fn tube_dress() -> TriMesh {
    let mut m = cylinder(120, 100, 0.3, 0.01);
    for p in &mut m.positions {
        p[1] += 1.45;
    }
    m
}

/// A knee-length skirt: waist at 1.0 m, flaring with folds towards the hem.
pub fn skirt(rings: usize, around: usize) -> TriMesh {
    let mut m = cylinder(rings, around, 1.0, 1.0);
    for p in &mut m.positions {
        let t = -p[1] / (rings - 1) as f64; // 0 at the waist, 1 at the hem
        let phi = p[2].atan2(p[0]);
        let r = 0.17 + 0.16 * t + 0.025 * t * (7.0 * phi).sin();
        let y = 1.0 - 0.5 * t;
        *p = [r * phi.cos() * 1.05, y, r * phi.sin() * 0.85];
    }
    m
}

/// A smooth stand-in for a per-vertex error in millimetres: larger towards the hem and
/// on the fold crests.
pub fn fake_error_mm(m: &TriMesh) -> Vec<f64> {
    m.positions
        .iter()
        .map(|p| {
            let t = (1.0 - p[1]) / 0.5;
            let phi = p[2].atan2(p[0]);
            (2.0 + 14.0 * t * t + 6.0 * t * (7.0 * phi + 0.6).sin().max(0.0)).max(0.0)
        })
        .collect()
}
