//! The triangle mesh: vertex positions and faces, with the per-element geometry every
//! system needs (areas, normals, bounding box, unique edges, the vertex graph).

use crate::graph::Graph;
use crate::vec3::{add, cross, norm, normalize_or_zero, sub};

/// A triangle mesh in metres, right-handed, Y up.
///
/// Faces index `positions` and are counter-clockwise seen from the side their normal
/// points to. Construction does not validate; run [`crate::validate::validate`] on anything a user
/// supplied before trusting the invariants (indices in range, finite positions).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    pub faces: Vec<[u32; 3]>,
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest coordinate on each axis.
    pub min: [f64; 3],
    /// Largest coordinate on each axis.
    pub max: [f64; 3],
}

impl TriMesh {
    /// A mesh from positions and faces (not validated).
    pub fn new(positions: Vec<[f64; 3]>, faces: Vec<[u32; 3]>) -> Self {
        TriMesh { positions, faces }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// The bounding box of the vertices, `None` for a mesh without vertices.
    pub fn bounding_box(&self) -> Option<Aabb> {
        let first = *self.positions.first()?;
        let mut b = Aabb {
            min: first,
            max: first,
        };
        for p in &self.positions {
            b.min = std::array::from_fn(|k| b.min[k].min(p[k]));
            b.max = std::array::from_fn(|k| b.max[k].max(p[k]));
        }
        Some(b)
    }

    /// Twice-area vector `(b - a) × (c - a)` of face `f`: its direction is the face normal.
    fn face_cross(&self, f: [u32; 3]) -> [f64; 3] {
        let [a, b, c] = f.map(|i| self.positions[i as usize]);
        cross(sub(b, a), sub(c, a))
    }

    /// Area of each face.
    pub fn face_areas(&self) -> Vec<f64> {
        self.faces
            .iter()
            .map(|&f| 0.5 * norm(self.face_cross(f)))
            .collect()
    }

    /// Unit normal of each face (zero for a degenerate face).
    pub fn face_normals(&self) -> Vec<[f64; 3]> {
        self.faces
            .iter()
            .map(|&f| normalize_or_zero(self.face_cross(f)))
            .collect()
    }

    /// Area-weighted unit vertex normals: the sum of the incident faces' twice-area
    /// vectors, normalised. Zero for isolated vertices.
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        vertex_normals_of(&self.positions, &self.faces)
    }

    /// Each undirected edge once as `[a, b]`, `a < b`, sorted ascending.
    ///
    /// Buckets the three edges of every face by their smaller vertex (a counting sort),
    /// so the cost is linear in the face count rather than a global sort.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let n = self.positions.len();
        let mut count = vec![0usize; n + 1];
        for f in &self.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                count[a.min(b) as usize] += 1;
            }
        }
        let mut start = vec![0usize; n + 1];
        for v in 0..n {
            start[v + 1] = start[v] + count[v];
        }
        let mut fill = start.clone();
        let mut bucket = vec![0u32; start[n]];
        for f in &self.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let lo = a.min(b) as usize;
                bucket[fill[lo]] = a.max(b);
                fill[lo] += 1;
            }
        }
        let mut edges = Vec::with_capacity(start[n] / 2 + 1);
        for v in 0..n {
            let list = &mut bucket[start[v]..start[v + 1]];
            list.sort_unstable();
            let mut last = None;
            for &b in list.iter() {
                if last != Some(b) && b != v as u32 {
                    edges.push([v as u32, b]);
                }
                last = Some(b);
            }
        }
        edges
    }

    /// The vertex graph: one node per vertex, one edge per mesh edge.
    pub fn graph(&self) -> Graph {
        Graph::from_edges(self.positions.len(), &self.edges())
    }
}

/// [`TriMesh::vertex_normals`] of `positions` over `faces`, for a mesh whose vertices
/// move every frame (a rollout, a posed body) without building a [`TriMesh`] each time.
pub fn vertex_normals_of(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut acc = vec![[0.0; 3]; positions.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| positions[i as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for &i in f {
            acc[i as usize] = add(acc[i as usize], n);
        }
    }
    acc.into_iter().map(normalize_or_zero).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> TriMesh {
        TriMesh::new(
            vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn areas_normals_and_box_of_a_unit_square() {
        let m = quad();
        assert_eq!(m.face_areas(), vec![0.5, 0.5]);
        for n in m.vertex_normals() {
            assert_eq!(n, [0., 0., 1.]);
        }
        let b = m.bounding_box().unwrap();
        assert_eq!((b.min, b.max), ([0., 0., 0.], [1., 1., 0.]));
    }

    #[test]
    fn edges_are_unique_and_sorted() {
        let m = quad();
        assert_eq!(m.edges(), vec![[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]]);
        assert_eq!(m.graph().edge_count(), 5);
    }

    #[test]
    fn vertex_normals_weight_by_area() {
        // A big face in the XY plane and a tiny one in the XZ plane share vertex 0.
        let m = TriMesh::new(
            vec![
                [0., 0., 0.],
                [10., 0., 0.],
                [0., 10., 0.],
                [0.1, 0., 0.],
                [0., 0., 0.1],
            ],
            vec![[0, 1, 2], [0, 4, 3]],
        );
        let n = m.vertex_normals()[0];
        assert!(n[2] > 0.999, "{n:?}");
    }
}
