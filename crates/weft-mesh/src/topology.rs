//! Face–edge incidence: which faces meet at each edge, the dihedral (hinge) pairs the
//! bending energies need, boundary edges and loops, and non-manifold edges.

use crate::mesh::TriMesh;

/// A hinge: an interior edge with exactly two incident faces, and the two vertices
/// opposite it. Bending energies (discrete shells) are sums over hinges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hinge {
    /// The shared edge, `edge[0] < edge[1]`.
    pub edge: [u32; 2],
    /// The two faces, in increasing face order.
    pub faces: [u32; 2],
    /// The vertex of `faces[0]` and of `faces[1]` not on the edge.
    pub opposite: [u32; 2],
}

/// Edge–face incidence of a triangle mesh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Topology {
    /// Unique undirected edges `[a, b]`, `a < b`, ascending (same order as
    /// [`TriMesh::edges`]).
    pub edges: Vec<[u32; 2]>,
    /// `edge_face_offsets[e]..edge_face_offsets[e + 1]` indexes `edge_faces` for edge `e`.
    pub edge_face_offsets: Vec<usize>,
    /// Faces incident to each edge, ascending per edge.
    pub edge_faces: Vec<u32>,
}

impl Topology {
    /// Builds the incidence of `mesh` (faces must index valid vertices).
    pub fn new(mesh: &TriMesh) -> Self {
        // (edge key, face) for the three edges of every face, sorted by key then face.
        let mut half: Vec<([u32; 2], u32)> = Vec::with_capacity(3 * mesh.faces.len());
        for (fi, f) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                if a != b {
                    half.push(([a.min(b), a.max(b)], fi as u32));
                }
            }
        }
        half.sort_unstable();
        let mut edges = Vec::new();
        let mut edge_face_offsets = vec![0];
        let mut edge_faces = Vec::with_capacity(half.len());
        for (i, &(key, face)) in half.iter().enumerate() {
            if i == 0 || half[i - 1].0 != key {
                if i > 0 {
                    edge_face_offsets.push(edge_faces.len());
                }
                edges.push(key);
            }
            edge_faces.push(face);
        }
        if !half.is_empty() {
            edge_face_offsets.push(edge_faces.len());
        }
        Topology {
            edges,
            edge_face_offsets,
            edge_faces,
        }
    }

    /// Faces incident to edge `e`.
    pub fn faces_of_edge(&self, e: usize) -> &[u32] {
        &self.edge_faces[self.edge_face_offsets[e]..self.edge_face_offsets[e + 1]]
    }

    /// Indices of edges with exactly one incident face.
    pub fn boundary_edges(&self) -> Vec<usize> {
        (0..self.edges.len())
            .filter(|&e| self.faces_of_edge(e).len() == 1)
            .collect()
    }

    /// Indices of edges with more than two incident faces.
    pub fn non_manifold_edges(&self) -> Vec<usize> {
        (0..self.edges.len())
            .filter(|&e| self.faces_of_edge(e).len() > 2)
            .collect()
    }

    /// Every interior edge with exactly two faces, with its opposite vertices.
    pub fn hinges(&self, mesh: &TriMesh) -> Vec<Hinge> {
        let opposite = |f: u32, [a, b]: [u32; 2]| {
            let face = mesh.faces[f as usize];
            face.into_iter()
                .find(|&v| v != a && v != b)
                .expect("a non-degenerate face has a vertex off each of its edges")
        };
        (0..self.edges.len())
            .filter_map(|e| match *self.faces_of_edge(e) {
                [f0, f1] => {
                    let edge = self.edges[e];
                    Some(Hinge {
                        edge,
                        faces: [f0, f1],
                        opposite: [opposite(f0, edge), opposite(f1, edge)],
                    })
                }
                _ => None,
            })
            .collect()
    }

    /// Boundary loops as vertex cycles (first vertex not repeated), each starting at its
    /// smallest vertex, ordered by that vertex.
    ///
    /// Boundary edges are chained through shared vertices. At a vertex where more than two
    /// boundary edges meet (two holes touching at a point, a non-manifold vertex) the walk
    /// takes the smallest unused edge, so each loop is still a closed cycle.
    pub fn boundary_loops(&self) -> Vec<Vec<u32>> {
        let boundary = self.boundary_edges();
        // Vertex → incident boundary edges (indices into `boundary`), small lists.
        let mut at: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
        for (i, &e) in boundary.iter().enumerate() {
            let [a, b] = self.edges[e];
            at.entry(a).or_default().push(i);
            at.entry(b).or_default().push(i);
        }
        let mut used = vec![false; boundary.len()];
        let mut loops = Vec::new();
        for (i, &e) in boundary.iter().enumerate() {
            if used[i] {
                continue;
            }
            used[i] = true;
            let [start, mut current] = self.edges[e];
            let mut cycle = vec![start];
            while current != start {
                cycle.push(current);
                let next = at[&current].iter().copied().find(|&j| !used[j]);
                let Some(j) = next else { break };
                used[j] = true;
                let [a, b] = self.edges[boundary[j]];
                current = if a == current { b } else { a };
            }
            let min_pos = (0..cycle.len()).min_by_key(|&k| cycle[k]).unwrap_or(0);
            cycle.rotate_left(min_pos);
            loops.push(cycle);
        }
        loops.sort_by_key(|c| c[0]);
        loops
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::{cylinder, grid};

    #[test]
    fn square_has_one_hinge_and_one_loop() {
        let m = grid(2, 2, 1.0);
        let t = Topology::new(&m);
        assert_eq!(t.edges, m.edges());
        let h = t.hinges(&m);
        assert_eq!(h.len(), 1);
        assert_eq!(h[0].edge, [0, 3]);
        assert_eq!(h[0].opposite, [2, 1]);
        assert_eq!(t.boundary_loops(), vec![vec![0, 1, 3, 2]]);
        assert!(t.non_manifold_edges().is_empty());
    }

    #[test]
    fn open_cylinder_has_two_boundary_loops() {
        let m = cylinder(5, 12, 1.0, 0.2);
        let t = Topology::new(&m);
        let loops = t.boundary_loops();
        assert_eq!(loops.len(), 2);
        assert!(loops.iter().all(|l| l.len() == 12));
        // Euler: interior edges = hinges.
        assert_eq!(t.hinges(&m).len(), t.edges.len() - 24);
    }

    #[test]
    fn three_faces_on_an_edge_are_non_manifold() {
        let m = TriMesh::new(
            vec![
                [0.; 3],
                [1., 0., 0.],
                [0., 1., 0.],
                [0., -1., 0.],
                [0., 0., 1.],
            ],
            vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
        );
        let t = Topology::new(&m);
        let nm = t.non_manifold_edges();
        assert_eq!(nm.len(), 1);
        assert_eq!(t.edges[nm[0]], [0, 1]);
        assert_eq!(t.faces_of_edge(nm[0]), &[0, 1, 2]);
    }
}
