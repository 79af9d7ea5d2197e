//! Edge-length geodesic distances: Dijkstra over the mesh graph with Euclidean edge
//! lengths.
//!
//! This is the metric of the garment affinity matrix of seed 000 §3.2 ("Garment style
//! information": `G_ij` is the geodesic distance between vertices `i` and `j`), and of
//! farthest-point sampling. Shortest paths run along mesh edges only, so distances are
//! an upper bound of the true surface geodesic that converges as the mesh is refined
//! (and is exact along straight chains of edges).
//!
//! The results do not depend on vertex numbering: a floating-point Dijkstra computes
//! the least fixed point of `d[u] = min_v (d[v] + len(v, u))`, which is the same value
//! whatever order ties are popped in, and `len(v, u) == len(u, v)` bit for bit.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::graph::Graph;
use crate::mesh::TriMesh;
use crate::vec3::{norm, sub};

/// Why a [`Geodesics`] could not be built from a mesh or graph.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeodesicError {
    /// A face names a vertex that does not exist.
    #[error("face {face} names vertex {vertex}, but the mesh has {vertex_count} vertices")]
    FaceOutOfRange {
        /// 0-based face index.
        face: usize,
        /// The offending vertex index.
        vertex: u32,
        /// Number of vertices of the mesh.
        vertex_count: usize,
    },
    /// A vertex position is NaN or infinite, which would make edge lengths meaningless.
    #[error("vertex {vertex} has a non-finite position {position:?}")]
    NonFinitePosition {
        /// 0-based vertex index.
        vertex: usize,
        /// The position found.
        position: [f64; 3],
    },
    /// The graph and the position buffer disagree on the number of vertices.
    #[error("the graph has {graph} vertices but {positions} positions were given")]
    CountMismatch {
        /// Vertices of the graph.
        graph: usize,
        /// Length of the position buffer.
        positions: usize,
    },
}

/// The mesh graph with its Euclidean edge lengths, built once and queried for
/// single- or multi-source geodesic distances.
///
/// Invariant: `edge_lengths()[k]` is the length of the directed CSR edge
/// `v -> graph().adjacency()[k]` for `k` in `graph().offsets()[v]..graph().offsets()[v + 1]`,
/// so kernels can walk both arrays in lockstep.
#[derive(Clone, Debug, PartialEq)]
pub struct Geodesics {
    graph: Graph,
    lengths: Vec<f64>,
    positions: Vec<[f64; 3]>,
}

impl Geodesics {
    /// The geodesics of `mesh` (its vertex graph, with Euclidean edge lengths).
    ///
    /// Checks what would otherwise panic or poison the distances: face indices in range
    /// and finite positions.
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let n = mesh.vertex_count();
        for (face, f) in mesh.faces.iter().enumerate() {
            if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n) {
                return Err(GeodesicError::FaceOutOfRange {
                    face,
                    vertex,
                    vertex_count: n,
                });
            }
        }
        Self::from_graph(mesh.graph(), &mesh.positions)
    }

    /// The geodesics of an existing `graph` whose vertex `v` sits at `positions[v]`
    /// (a coarse hierarchy level, a graph without faces).
    pub fn from_graph(graph: Graph, positions: &[[f64; 3]]) -> Result<Self, GeodesicError> {
        if graph.vertex_count() != positions.len() {
            return Err(GeodesicError::CountMismatch {
                graph: graph.vertex_count(),
                positions: positions.len(),
            });
        }
        if let Some((vertex, &position)) = positions
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
        {
            return Err(GeodesicError::NonFinitePosition { vertex, position });
        }
        let mut lengths = Vec::with_capacity(graph.adjacency().len());
        for (v, &p) in positions.iter().enumerate() {
            lengths.extend(
                graph
                    .neighbors(v)
                    .iter()
                    .map(|&u| norm(sub(positions[u as usize], p))),
            );
        }
        Ok(Geodesics {
            graph,
            lengths,
            positions: positions.to_vec(),
        })
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The vertex graph.
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Edge lengths in CSR order, aligned with [`Graph::adjacency`].
    pub fn edge_lengths(&self) -> &[f64] {
        &self.lengths
    }

    /// Vertex positions the lengths were measured on.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Geodesic distance from `source` to every vertex; `f64::INFINITY` for vertices in
    /// other connected components.
    ///
    /// # Panics
    /// If `source >= self.vertex_count()`.
    pub fn distances_from(&self, source: usize) -> Vec<f64> {
        self.distances_from_many(&[source])
    }

    /// Distance from each vertex to the nearest of `sources` (a multi-source Dijkstra:
    /// the element-wise minimum of the single-source distances, in one pass). All
    /// `f64::INFINITY` when `sources` is empty.
    ///
    /// # Panics
    /// If a source is `>= self.vertex_count()`.
    pub fn distances_from_many(&self, sources: &[usize]) -> Vec<f64> {
        let n = self.vertex_count();
        for &s in sources {
            assert!(s < n, "source {s} out of range for {n} vertices");
        }
        let mut dist = vec![f64::INFINITY; n];
        let mut heap = BinaryHeap::new();
        for &s in sources {
            dist[s] = 0.0;
            heap.push(Entry {
                dist: 0.0,
                vertex: s as u32,
            });
        }
        let (offsets, adjacency) = (self.graph.offsets(), self.graph.adjacency());
        while let Some(Entry { dist: d, vertex }) = heap.pop() {
            let v = vertex as usize;
            if d > dist[v] {
                continue; // stale entry: `v` was settled with a shorter distance
            }
            let row = offsets[v]..offsets[v + 1];
            for (&u, &length) in adjacency[row.clone()].iter().zip(&self.lengths[row]) {
                let u = u as usize;
                let candidate = d + length;
                if candidate < dist[u] {
                    dist[u] = candidate;
                    heap.push(Entry {
                        dist: candidate,
                        vertex: u as u32,
                    });
                }
            }
        }
        dist
    }
}

/// A heap entry ordered so that [`BinaryHeap`] (a max-heap) pops the smallest
/// distance first; `total_cmp` keeps the order total, ties go to the smaller vertex.
#[derive(Clone, Copy, Debug)]
struct Entry {
    dist: f64,
    vertex: u32,
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .dist
            .total_cmp(&self.dist)
            .then_with(|| other.vertex.cmp(&self.vertex))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Entry {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::grid;
    use proptest::prelude::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn a_polyline_path_accumulates_its_segment_lengths() {
        let xs = [0.0, 0.5, 2.0, 2.25, 7.0];
        let positions: Vec<[f64; 3]> = xs.iter().map(|&x| [x, 0.0, 0.0]).collect();
        let edges: Vec<[u32; 2]> = (0..4).map(|i| [i, i + 1]).collect();
        let geo = Geodesics::from_graph(Graph::from_edges(5, &edges), &positions).unwrap();
        assert_eq!(geo.distances_from(0), xs.to_vec());
        let from_mid = geo.distances_from(2);
        for (d, x) in from_mid.iter().zip(xs) {
            assert_eq!(*d, (x - 2.0f64).abs());
        }
        let nearest = geo.distances_from_many(&[0, 4]);
        assert_eq!(nearest, vec![0.0, 0.5, 2.0, 2.25, 0.0]);
    }

    /// Shortest path on `primitives::grid`: axis steps of `h` and diagonals of `√2 h`
    /// along `(+1, +1)` only, so a displacement `(dx, dz)` costs
    /// `√2 min(|dx|, |dz|) + ||dx| - |dz||` when the signs agree and `|dx| + |dz|`
    /// otherwise.
    fn grid_distance(a: (i64, i64), b: (i64, i64), h: f64) -> f64 {
        let (dx, dz) = (b.0 - a.0, b.1 - a.1);
        let (ax, az) = (dx.abs() as f64, dz.abs() as f64);
        if dx * dz >= 0 {
            h * (std::f64::consts::SQRT_2 * ax.min(az) + (ax - az).abs())
        } else {
            h * (ax + az)
        }
    }

    #[test]
    fn grid_distances_match_the_closed_form() {
        let (nx, nz, h) = (6usize, 5usize, 0.3);
        let mesh = grid(nx, nz, h);
        let geo = Geodesics::new(&mesh).unwrap();
        for s in 0..nx * nz {
            let d = geo.distances_from(s);
            let a = ((s % nx) as i64, (s / nx) as i64);
            for (v, &dv) in d.iter().enumerate() {
                let b = ((v % nx) as i64, (v / nx) as i64);
                let want = grid_distance(a, b, h);
                assert!(close(dv, want, 1e-12), "{s} -> {v}: {dv} vs {want}");
            }
        }
        // The full diagonal and the two sides from the corner.
        let d0 = geo.distances_from(0);
        assert!(close(d0[nx * nz - 1], h * (4.0 * 2f64.sqrt() + 1.0), 1e-12));
        assert!(close(d0[nx - 1], 5.0 * h, 1e-12));
        assert!(close(d0[(nz - 1) * nx], 4.0 * h, 1e-12));
    }

    #[test]
    fn lengths_follow_the_adjacency() {
        let mesh = grid(3, 3, 2.0);
        let geo = Geodesics::new(&mesh).unwrap();
        let g = geo.graph();
        assert_eq!(geo.edge_lengths().len(), g.adjacency().len());
        for v in 0..g.vertex_count() {
            for k in g.offsets()[v]..g.offsets()[v + 1] {
                let u = g.adjacency()[k] as usize;
                let want = norm(sub(mesh.positions[u], mesh.positions[v]));
                assert_eq!(geo.edge_lengths()[k], want);
            }
        }
    }

    #[test]
    fn unreachable_and_empty_sources_are_infinite() {
        let mut mesh = grid(2, 2, 1.0);
        mesh.positions.push([5.0, 5.0, 5.0]); // an isolated vertex
        let geo = Geodesics::new(&mesh).unwrap();
        let d = geo.distances_from(0);
        assert_eq!(d[4], f64::INFINITY);
        assert_eq!(geo.distances_from(4)[..4], [f64::INFINITY; 4]);
        assert!(geo.distances_from_many(&[]).iter().all(|d| d.is_infinite()));
    }

    #[test]
    fn bad_input_is_reported() {
        let mut mesh = grid(2, 2, 1.0);
        mesh.faces.push([0, 1, 9]);
        assert_eq!(
            Geodesics::new(&mesh),
            Err(GeodesicError::FaceOutOfRange {
                face: 2,
                vertex: 9,
                vertex_count: 4
            })
        );
        let mut mesh = grid(2, 2, 1.0);
        mesh.positions[3][1] = f64::NAN;
        assert!(matches!(
            Geodesics::new(&mesh),
            Err(GeodesicError::NonFinitePosition { vertex: 3, .. })
        ));
        assert!(matches!(
            Geodesics::from_graph(Graph::from_edges(2, &[[0, 1]]), &[[0.0; 3]]),
            Err(GeodesicError::CountMismatch { .. })
        ));
    }

    /// A jittered `nx × nz` grid with some faces dropped (possibly several components
    /// and isolated vertices).
    fn random_mesh() -> impl Strategy<Value = TriMesh> {
        (2usize..7, 2usize..7).prop_flat_map(|(nx, nz)| {
            let n = nx * nz;
            let f = 2 * (nx - 1) * (nz - 1);
            (
                prop::collection::vec(prop::array::uniform3(-0.3f64..0.3), n),
                prop::collection::vec(prop::bool::weighted(0.8), f),
            )
                .prop_map(move |(jitter, keep)| {
                    let mut mesh = grid(nx, nz, 1.0);
                    for (p, j) in mesh.positions.iter_mut().zip(jitter) {
                        for k in 0..3 {
                            p[k] += j[k];
                        }
                    }
                    mesh.faces = mesh
                        .faces
                        .iter()
                        .zip(keep)
                        .filter_map(|(&f, k)| k.then_some(f))
                        .collect();
                    mesh
                })
        })
    }

    proptest! {
        #[test]
        fn geodesics_form_a_metric(mesh in random_mesh()) {
            let geo = Geodesics::new(&mesh).unwrap();
            let n = mesh.vertex_count();
            let all: Vec<Vec<f64>> = (0..n).map(|s| geo.distances_from(s)).collect();
            let comp = geo.graph().components();
            for a in 0..n {
                prop_assert_eq!(all[a][a], 0.0);
                for b in 0..n {
                    let dab = all[a][b];
                    // Reachability is exactly the component relation.
                    prop_assert_eq!(dab.is_finite(), comp.label[a] == comp.label[b]);
                    // Symmetry (up to rounding: the sums run in opposite orders).
                    prop_assert!(dab == all[b][a] || close(dab, all[b][a], 1e-12));
                    // Never shorter than the straight line.
                    let chord = norm(sub(mesh.positions[a], mesh.positions[b]));
                    prop_assert!(dab >= chord * (1.0 - 1e-12));
                    // Triangle inequality.
                    for (dac, from_c) in all[a].iter().zip(&all) {
                        prop_assert!(dab <= dac + from_c[b] + 1e-12 * (1.0 + dab));
                    }
                }
            }
        }

        #[test]
        fn many_sources_give_the_nearest_source(mesh in random_mesh(), picks in prop::collection::vec(0usize..1000, 1..4)) {
            let geo = Geodesics::new(&mesh).unwrap();
            let n = mesh.vertex_count();
            let sources: Vec<usize> = picks.iter().map(|p| p % n).collect();
            let many = geo.distances_from_many(&sources);
            let singles: Vec<Vec<f64>> = sources.iter().map(|&s| geo.distances_from(s)).collect();
            for v in 0..n {
                let want = singles.iter().map(|d| d[v]).fold(f64::INFINITY, f64::min);
                prop_assert_eq!(many[v], want);
            }
        }
    }
}
