//! Procedural meshes for tests, benchmarks and the built-in demo garment.

use crate::mesh::TriMesh;

/// A flat `nx × nz` vertex grid in the XZ plane with spacing `h`, each quad split along
/// the same diagonal.
pub fn grid(nx: usize, nz: usize, h: f64) -> TriMesh {
    assert!(nx >= 2 && nz >= 2, "a grid needs at least 2 × 2 vertices");
    let positions = (0..nz)
        .flat_map(|j| (0..nx).map(move |i| [i as f64 * h, 0.0, j as f64 * h]))
        .collect();
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut faces = Vec::with_capacity(2 * (nx - 1) * (nz - 1));
    for j in 0..nz - 1 {
        for i in 0..nx - 1 {
            faces.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    TriMesh::new(positions, faces)
}

/// An open cylinder of `rings` rings × `around` vertices (radius `radius`, ring spacing
/// `spacing`, axis along Y, top ring first), each quad split along the same diagonal,
/// normals pointing outwards.
pub fn cylinder(rings: usize, around: usize, radius: f64, spacing: f64) -> TriMesh {
    assert!(
        rings >= 2 && around >= 3,
        "a cylinder needs 2 rings of 3 vertices"
    );
    let positions = (0..rings)
        .flat_map(|r| {
            (0..around).map(move |k| {
                let phi = std::f64::consts::TAU * k as f64 / around as f64;
                [
                    radius * phi.cos(),
                    -(r as f64) * spacing,
                    radius * phi.sin(),
                ]
            })
        })
        .collect();
    let id = |r: usize, k: usize| (r * around + k % around) as u32;
    let mut faces = Vec::with_capacity(2 * (rings - 1) * around);
    for r in 0..rings - 1 {
        for k in 0..around {
            faces.push([id(r, k), id(r, k + 1), id(r + 1, k + 1)]);
            faces.push([id(r, k), id(r + 1, k + 1), id(r + 1, k)]);
        }
    }
    TriMesh::new(positions, faces)
}

/// The built-in garment of `weft mesh hierarchy`: an open cylinder of 40 rings × 100
/// vertices, about the size of a knee-length tube skirt (radius 0.3 m, 1.5 cm rings).
pub fn builtin_garment() -> TriMesh {
    cylinder(40, 100, 0.3, 0.015)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts() {
        let g = grid(4, 3, 1.0);
        assert_eq!((g.vertex_count(), g.face_count()), (12, 12));
        let c = builtin_garment();
        assert_eq!((c.vertex_count(), c.face_count()), (4000, 7800));
        assert_eq!(c.graph().components().count, 1);
    }

    #[test]
    fn cylinder_normals_point_outwards() {
        let c = cylinder(3, 8, 1.0, 0.5);
        for (p, n) in c.positions.iter().zip(c.vertex_normals()) {
            assert!(p[0] * n[0] + p[2] * n[2] > 0.0);
        }
    }
}
