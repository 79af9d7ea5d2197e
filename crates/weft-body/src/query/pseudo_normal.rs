//! Angle-weighted pseudo-normals of a triangle mesh: one per face, per edge and per
//! vertex (Bærentzen & Aanæs, "Signed distance computation using the angle weighted
//! pseudonormal", IEEE TVCG 11(3), 2005).
//!
//! For a closed, consistently oriented (outward) 2-manifold, the sign of
//! `(p − c) · n(c)` — `c` the closest surface point to `p`, `n(c)` the pseudo-normal of
//! the feature `c` lies on — is the sign of the signed distance, exactly, for every `p`.
//! The face normal alone is not enough: when `c` lies on an edge or a vertex the face
//! found by the search can point the wrong way (the classic failure at the tip of a
//! cone, or along a concave crease). The pseudo-normals are:
//!
//! * face: its unit normal;
//! * edge: the sum of the unit normals of its faces (both get the angle π);
//! * vertex: `Σ_f α_f n_f`, `α_f` the angle of face `f` at the vertex.
//!
//! All are stored normalised. Edges are numbered here, independent of
//! [`weft_mesh::Topology`], because the query needs the edge of each face corner and
//! nothing else.
//!
//! Vertex pseudo-normals are computed when first asked for after each update, not for
//! every vertex: their corner angles (two `atan2` per face) were most of a per-frame
//! update, and a frame's queries touch a fraction of the body's vertices (the
//! collision term of a `cpu` training step asks for the triangles near the garment).
//! A vertex sums its faces in face order, as a scatter over the faces would, so the
//! values do not depend on which vertices were asked for, or in which order.

use std::sync::OnceLock;

use rayon::prelude::*;

use weft_mesh::vec3::{add, add_scaled, cross, dot, norm, normalize_or_zero, sub};

/// Pseudo-normals of a mesh with fixed faces; [`PseudoNormals::update`] recomputes them
/// for new positions. Equality ignores which vertex normals have been computed so far.
#[derive(Clone, Debug)]
pub(crate) struct PseudoNormals {
    /// Unit normal of each face (zero for a degenerate face).
    pub face: Vec<[f64; 3]>,
    /// Unit pseudo-normal of each edge.
    pub edge: Vec<[f64; 3]>,
    /// Unit angle-weighted pseudo-normal of each vertex (zero if unused), once computed
    /// ([`PseudoNormals::vertex`]).
    vertex: Vec<OnceLock<[f64; 3]>>,
    /// The face corners (`3 · face + corner`) at each vertex, in face order: those of
    /// vertex `v` are `corners[corner_start[v]..corner_start[v + 1]]`.
    corners: Vec<u32>,
    corner_start: Vec<u32>,
    /// `face_edges[f][k]`: the edge from corner `k` to corner `(k + 1) % 3` of face `f`.
    pub face_edges: Vec<[u32; 3]>,
    /// The two end vertices of each edge, ascending.
    pub edge_vertices: Vec<[u32; 2]>,
}

impl PseudoNormals {
    /// Numbers the edges of `faces` (indices must be in range for `positions`) and
    /// computes the normals.
    pub fn new(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Self {
        let mut half: Vec<([u32; 2], u32)> = Vec::with_capacity(3 * faces.len());
        for (fi, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                half.push(([a.min(b), a.max(b)], (3 * fi + k) as u32));
            }
        }
        half.sort_unstable();
        let mut face_edges = vec![[0u32; 3]; faces.len()];
        let mut edge_vertices = Vec::new();
        for (i, &(key, slot)) in half.iter().enumerate() {
            if i == 0 || half[i - 1].0 != key {
                edge_vertices.push(key);
            }
            let e = (edge_vertices.len() - 1) as u32;
            face_edges[slot as usize / 3][slot as usize % 3] = e;
        }
        // Corners by vertex, in face order (a counting sort).
        let mut corner_start = vec![0u32; positions.len() + 1];
        for &v in faces.iter().flatten() {
            corner_start[v as usize + 1] += 1;
        }
        for v in 0..positions.len() {
            corner_start[v + 1] += corner_start[v];
        }
        let mut next = corner_start.clone();
        let mut corners = vec![0u32; 3 * faces.len()];
        for (slot, &v) in faces.iter().flatten().enumerate() {
            corners[next[v as usize] as usize] = slot as u32;
            next[v as usize] += 1;
        }
        let mut n = PseudoNormals {
            face: Vec::new(),
            edge: vec![[0.0; 3]; edge_vertices.len()],
            vertex: Vec::new(),
            corners,
            corner_start,
            face_edges,
            edge_vertices,
        };
        n.update(positions, faces);
        n
    }

    /// Recomputes the face and edge normals for new `positions` (same length, same
    /// faces) and forgets the vertex normals (recomputed when asked for).
    ///
    /// The face normals are computed in parallel; the scatter onto edges is a sequential
    /// pass in face order, so results do not depend on the thread count.
    pub fn update(&mut self, positions: &[[f64; 3]], faces: &[[u32; 3]]) {
        faces
            .par_iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| positions[i as usize]);
                normalize_or_zero(cross(sub(b, a), sub(c, a)))
            })
            .collect_into_vec(&mut self.face);
        self.edge.iter_mut().for_each(|e| *e = [0.0; 3]);
        for (fi, &n) in self.face.iter().enumerate() {
            for &e in &self.face_edges[fi] {
                self.edge[e as usize] = add(self.edge[e as usize], n);
            }
        }
        self.edge
            .par_iter_mut()
            .for_each(|e| *e = normalize_or_zero(*e));
        self.vertex.clear();
        self.vertex.resize_with(positions.len(), OnceLock::new);
    }

    /// The unit pseudo-normal of vertex `v`, `Σ_f α_f n_f` over its faces in face order
    /// (zero if unused), from the `positions` and `faces` of the last update.
    pub fn vertex(&self, v: usize, positions: &[[f64; 3]], faces: &[[u32; 3]]) -> [f64; 3] {
        *self.vertex[v].get_or_init(|| {
            let (start, end) = (self.corner_start[v], self.corner_start[v + 1]);
            let mut sum = [0.0; 3];
            for &slot in &self.corners[start as usize..end as usize] {
                let f = slot as usize / 3;
                let angle = corner_angle(faces[f].map(|i| positions[i as usize]), slot % 3);
                sum = add_scaled(sum, self.face[f], angle);
            }
            normalize_or_zero(sum)
        })
    }
}

impl PartialEq for PseudoNormals {
    fn eq(&self, other: &Self) -> bool {
        self.face == other.face
            && self.edge == other.edge
            && self.corners == other.corners
            && self.corner_start == other.corner_start
            && self.face_edges == other.face_edges
            && self.edge_vertices == other.edge_vertices
    }
}

/// The angle of triangle `[a, b, c]` at corner `k`: the first two as
/// `atan2(|u × v|, u · v)` (no normalisation, accurate near 0 and π), the third as π
/// minus the other two.
fn corner_angle([a, b, c]: [[f64; 3]; 3], k: u32) -> f64 {
    let (ab, ac, bc) = (sub(b, a), sub(c, a), sub(c, b));
    let area = norm(cross(ab, ac));
    let alpha = || area.atan2(dot(ab, ac));
    let beta = || area.atan2(-dot(ab, bc));
    match k {
        0 => alpha(),
        1 => beta(),
        _ => (std::f64::consts::PI - alpha() - beta()).max(0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube, outward-facing triangles.
    pub(crate) fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let p: Vec<[f64; 3]> = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        let quads = [
            [0, 2, 3, 1], // z = 0, normal −z
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        let f = quads
            .iter()
            .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (p, f)
    }

    /// Vertex normals asked for one at a time, in any order, equal to the bit the scatter
    /// over every face's corner angles (the eager form they replace), after an update too.
    #[test]
    fn vertex_normals_on_demand_equal_the_scatter_over_faces() {
        let mesh = weft_mesh::primitives::cylinder(6, 9, 0.3, 0.1);
        let (faces, mut p) = (mesh.faces.clone(), mesh.positions.clone());
        let mut n = PseudoNormals::new(&p, &faces);
        let untouched = n.clone();
        for round in 0..2 {
            let mut scatter = vec![[0.0; 3]; p.len()];
            for f in &faces {
                let [a, b, c] = f.map(|i| p[i as usize]);
                let (ab, ac, bc) = (sub(b, a), sub(c, a), sub(c, b));
                let twice_area = cross(ab, ac);
                let normal = normalize_or_zero(twice_area);
                let area = norm(twice_area);
                let alpha = area.atan2(dot(ab, ac));
                let beta = area.atan2(-dot(ab, bc));
                let gamma = (std::f64::consts::PI - alpha - beta).max(0.0);
                for (k, angle) in [alpha, beta, gamma].into_iter().enumerate() {
                    let v = f[k] as usize;
                    scatter[v] = add_scaled(scatter[v], normal, angle);
                }
            }
            for v in (0..p.len()).rev().step_by(3).chain(0..p.len()) {
                let want = normalize_or_zero(scatter[v]);
                assert_eq!(n.vertex(v, &p, &faces), want, "round {round}, vertex {v}");
            }
            if round == 0 {
                // Equal to a copy that computed no vertex normal yet.
                assert_eq!(n, untouched);
            }
            // The next frame: every vertex moved, the normals forgotten and recomputed.
            for (i, q) in p.iter_mut().enumerate() {
                q[0] += 0.01 * (i as f64).sin();
                q[2] += 0.02 * (i as f64 * 0.7).cos();
            }
            n.update(&p, &faces);
        }
    }

    #[test]
    fn cube_corner_and_edge_normals_are_diagonal() {
        let (p, f) = cube();
        let n = PseudoNormals::new(&p, &f);
        assert_eq!(n.edge_vertices.len(), 18);
        let s = 1.0 / 3f64.sqrt();
        // Every corner of a cube sees three right angles: the normal is the diagonal,
        // whatever the triangulation.
        let v7 = n.vertex(7, &p, &f);
        assert!(v7.iter().all(|c| (c - s).abs() < 1e-12), "{v7:?}");
        let v0 = n.vertex(0, &p, &f);
        assert!(v0.iter().all(|c| (c + s).abs() < 1e-12), "{v0:?}");
        // Face normals point out.
        assert!((n.face[0][2] + 1.0).abs() < 1e-12);
        assert!((n.face[2][2] - 1.0).abs() < 1e-12);
        // The edge 0–1 (x axis at y = z = 0) lies between faces −z and −y.
        let e = n
            .edge_vertices
            .iter()
            .position(|&e| e == [0, 1])
            .expect("edge 0-1 exists");
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let ne = n.edge[e];
        assert!((ne[0]).abs() < 1e-12 && (ne[1] + h).abs() < 1e-12 && (ne[2] + h).abs() < 1e-12);
    }
}
