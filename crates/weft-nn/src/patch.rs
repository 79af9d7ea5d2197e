//! Connected vertex patches: the training crops of DenseGATs ("one thousand consecutive
//! vertices" per character) and MultiResGNet ("a vertex and ... the surrounding 1024
//! consecutive vertices"), seed 001 §3.2.3.2 and §3.3.3.2.
//!
//! Index-consecutive vertices need not be connected, and a GAT on a scattered vertex set has
//! almost no edges to attend over, so "consecutive" is read as graph-consecutive (decision
//! D5): a breadth-first patch grown from a seed vertex, with the subgraph it induces.
//!
//! A dressed character can have several components (body, garments). When the seed's
//! component is smaller than the requested size, the patch goes on with a new
//! breadth-first part from the first unvisited vertex after the seed in index order
//! (wrapping around), until it has the requested size or the graph is exhausted: every
//! batch item then has the same size, and each part is connected.

use weft_mesh::Graph;

use crate::error::{NnError, Result};

/// A vertex subset of a graph and the subgraph it induces.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Patch {
    vertices: Vec<u32>,
    graph: Graph,
    source_count: usize,
}

impl Patch {
    /// Breadth-first patch of `min(size, N)` vertices of `graph` grown from `seed` (see the
    /// module documentation); neighbours are visited in ascending order, so the patch is a
    /// function of `(graph, seed, size)`. Errors on `size == 0` or a seed out of range.
    pub fn grow(graph: &Graph, seed: usize, size: usize) -> Result<Self> {
        let n = graph.vertex_count();
        if seed >= n {
            return Err(NnError::Index {
                what: "patch seed vertex",
                index: seed,
                len: n,
            });
        }
        if size == 0 {
            return Err(NnError::Config("a patch needs at least one vertex".into()));
        }
        let target = size.min(n);
        // Local index of every chosen vertex, u32::MAX for the others.
        let mut local = vec![u32::MAX; n];
        let mut vertices = Vec::with_capacity(target);
        let mut starts = (seed..n).chain(0..seed);
        while vertices.len() < target {
            let Some(start) = starts.find(|&v| local[v] == u32::MAX) else {
                break;
            };
            // `vertices[head..]` is this part's breadth-first queue.
            let mut head = vertices.len();
            local[start] = vertices.len() as u32;
            vertices.push(start as u32);
            while head < vertices.len() && vertices.len() < target {
                let v = vertices[head] as usize;
                head += 1;
                for &u in graph.neighbors(v) {
                    if vertices.len() == target {
                        break;
                    }
                    if local[u as usize] == u32::MAX {
                        local[u as usize] = vertices.len() as u32;
                        vertices.push(u);
                    }
                }
            }
        }
        let mut edges = Vec::new();
        for (a, &v) in vertices.iter().enumerate() {
            for &u in graph.neighbors(v as usize) {
                let b = local[u as usize];
                if b != u32::MAX && (a as u32) < b {
                    edges.push([a as u32, b]);
                }
            }
        }
        Ok(Patch {
            graph: Graph::from_edges(vertices.len(), &edges),
            vertices,
            source_count: n,
        })
    }

    /// The chosen vertices of the source graph in breadth-first order (the seed first);
    /// patch vertex `i` is source vertex `vertices()[i]`.
    pub fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    /// The induced subgraph on patch indices: `i`–`j` is an edge when `vertices()[i]`–
    /// `vertices()[j]` is one in the source graph. Feed it to [`crate::GraphBatch::new`].
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Vertices of the source graph.
    pub fn source_count(&self) -> usize {
        self.source_count
    }

    /// The rows of the patch vertices from a row-major `[source_count, width]` host matrix
    /// (features, targets), in patch order. Errors when the matrix has another shape.
    pub fn gather<T: Copy>(&self, rows: &[T], width: usize) -> Result<Vec<T>> {
        if rows.len() != self.source_count * width {
            return Err(NnError::Shape {
                what: "patch source rows (flat)",
                expected: vec![self.source_count * width],
                got: vec![rows.len()],
            });
        }
        Ok(self
            .vertices
            .iter()
            .flat_map(|&v| {
                let start = v as usize * width;
                rows[start..start + width].iter().copied()
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An `w × h` grid graph, vertex `x + w·y`, its indices shifted by `base`.
    fn grid_edges(w: u32, h: u32, base: u32) -> Vec<[u32; 2]> {
        let mut edges = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = base + x + w * y;
                if x + 1 < w {
                    edges.push([v, v + 1]);
                }
                if y + 1 < h {
                    edges.push([v, v + w]);
                }
            }
        }
        edges
    }

    /// A 10 × 10 grid (the body, 0..100) and a 4 × 3 grid (a garment, 100..112).
    fn two_components() -> Graph {
        let mut edges = grid_edges(10, 10, 0);
        edges.extend(grid_edges(4, 3, 100));
        Graph::from_edges(112, &edges)
    }

    fn check_induced(source: &Graph, patch: &Patch) {
        let v = patch.vertices();
        let mut sorted = v.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), v.len(), "distinct vertices");
        let mut expected = Vec::new();
        for a in 0..v.len() {
            for b in a + 1..v.len() {
                if source.has_edge(v[a] as usize, v[b] as usize) {
                    expected.push([a as u32, b as u32]);
                }
            }
        }
        assert_eq!(patch.graph().edges(), expected);
    }

    #[test]
    fn patch_is_connected_induced_and_deterministic() {
        let g = two_components();
        let patch = Patch::grow(&g, 45, 30).unwrap();
        assert_eq!(patch.vertices().len(), 30);
        assert_eq!(patch.vertices()[0], 45);
        assert!(patch.vertices().iter().all(|&v| v < 100));
        assert_eq!(patch.graph().components().count, 1);
        check_induced(&g, &patch);
        // Breadth-first: hop distances from the seed never decrease along the order.
        let dist = g.bfs_distances(45);
        assert!(patch
            .vertices()
            .windows(2)
            .all(|w| dist[w[0] as usize] <= dist[w[1] as usize]));
        assert_eq!(Patch::grow(&g, 45, 30).unwrap(), patch);
    }

    #[test]
    fn small_component_continues_after_the_seed_and_whole_graph_fits() {
        let g = two_components();
        // The garment (12 vertices) is exhausted, then the body from vertex 0 (wrapping).
        let patch = Patch::grow(&g, 105, 20).unwrap();
        let v = patch.vertices();
        assert_eq!(v.len(), 20);
        assert!(v[..12].iter().all(|&x| x >= 100));
        assert_eq!(v[12], 0);
        assert!(v[12..].iter().all(|&x| x < 100));
        assert_eq!(patch.graph().components().count, 2);
        check_induced(&g, &patch);
        for size in [112, 500] {
            let whole = Patch::grow(&g, 7, size).unwrap();
            assert_eq!(whole.vertices().len(), 112);
            assert_eq!(whole.graph().edge_count(), g.edge_count());
            check_induced(&g, &whole);
        }
    }

    #[test]
    fn gather_follows_patch_order_and_errors_are_typed() {
        let g = two_components();
        let patch = Patch::grow(&g, 0, 3).unwrap();
        assert_eq!(patch.vertices(), [0, 1, 10]);
        assert_eq!(patch.source_count(), 112);
        let rows: Vec<u32> = (0..112 * 2).collect();
        assert_eq!(patch.gather(&rows, 2).unwrap(), [0, 1, 2, 3, 20, 21]);
        assert!(matches!(patch.gather(&rows, 3), Err(NnError::Shape { .. })));
        assert!(matches!(
            Patch::grow(&g, 112, 5),
            Err(NnError::Index { index: 112, .. })
        ));
        assert!(Patch::grow(&g, 0, 0).is_err());
    }
}
