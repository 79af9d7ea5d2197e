//! Undirected graphs in compressed sparse row (CSR) form: the mesh graph every system
//! runs its message passing and hierarchy construction on.
//!
//! Invariants (checked by [`Graph::from_edges`]): no self-loops, no duplicate edges, every
//! edge stored in both directions, and each vertex's neighbour list sorted ascending, so
//! that every traversal is deterministic.

use std::collections::VecDeque;

/// Hop distance of a vertex that a traversal did not reach.
pub const UNREACHED: u32 = u32::MAX;

/// An undirected graph stored as CSR adjacency.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Graph {
    /// `offsets[v]..offsets[v + 1]` indexes `neighbors` for vertex `v`; length `n + 1`.
    offsets: Vec<usize>,
    /// Concatenated, per-vertex sorted neighbour lists.
    neighbors: Vec<u32>,
}

impl Graph {
    /// Builds the graph on `vertex_count` vertices from undirected edges.
    ///
    /// Edges may come in either orientation and may repeat; self-loops are dropped.
    ///
    /// # Panics
    /// If an edge names a vertex `>= vertex_count`: callers pass validated indices.
    pub fn from_edges(vertex_count: usize, edges: &[[u32; 2]]) -> Self {
        let mut degree = vec![0usize; vertex_count + 1];
        for &[a, b] in edges {
            if a != b {
                degree[a as usize] += 1;
                degree[b as usize] += 1;
            }
        }
        let mut offsets = Vec::with_capacity(vertex_count + 1);
        let mut total = 0usize;
        for d in &degree[..vertex_count] {
            offsets.push(total);
            total += d;
        }
        offsets.push(total);
        let mut fill = offsets.clone();
        let mut neighbors = vec![0u32; total];
        for &[a, b] in edges {
            if a != b {
                neighbors[fill[a as usize]] = b;
                fill[a as usize] += 1;
                neighbors[fill[b as usize]] = a;
                fill[b as usize] += 1;
            }
        }
        // Sort and deduplicate each list, then compact.
        let mut write = 0usize;
        let mut new_offsets = Vec::with_capacity(vertex_count + 1);
        for v in 0..vertex_count {
            let (start, end) = (offsets[v], offsets[v + 1]);
            let list = &mut neighbors[start..end];
            list.sort_unstable();
            new_offsets.push(write);
            let mut last = None;
            for i in start..end {
                let u = neighbors[i];
                if last != Some(u) {
                    neighbors[write] = u;
                    write += 1;
                    last = Some(u);
                }
            }
        }
        new_offsets.push(write);
        neighbors.truncate(write);
        Graph {
            offsets: new_offsets,
            neighbors,
        }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of undirected edges.
    pub fn edge_count(&self) -> usize {
        self.neighbors.len() / 2
    }

    /// Sorted neighbours of `v`.
    #[inline]
    pub fn neighbors(&self, v: usize) -> &[u32] {
        &self.neighbors[self.offsets[v]..self.offsets[v + 1]]
    }

    /// Number of neighbours of `v`.
    #[inline]
    pub fn degree(&self, v: usize) -> usize {
        self.offsets[v + 1] - self.offsets[v]
    }

    /// The CSR row offsets (length `n + 1`), for kernels that walk the adjacency directly.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// The concatenated neighbour lists, indexed by [`Graph::offsets`].
    pub fn adjacency(&self) -> &[u32] {
        &self.neighbors
    }

    /// Each undirected edge once, as `[a, b]` with `a < b`, in ascending order.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut out = Vec::with_capacity(self.edge_count());
        for a in 0..self.vertex_count() {
            for &b in self.neighbors(a) {
                if (a as u32) < b {
                    out.push([a as u32, b]);
                }
            }
        }
        out
    }

    /// `field` after `rounds` Jacobi rounds of `f_i ← ½ f_i + ½ mean_{j∼i} f_j` (a
    /// vertex without neighbours keeps its value): the Laplacian smoothing that spreads a
    /// garment's resize displacements and makes GarFitNet's coarse targets.
    pub fn jacobi_smooth(&self, field: &[[f64; 3]], rounds: usize) -> Vec<[f64; 3]> {
        use crate::vec3::{add, scale};
        let mut field = field.to_vec();
        for _ in 0..rounds {
            field = (0..field.len())
                .map(|i| {
                    let nb = self.neighbors(i);
                    if nb.is_empty() {
                        return field[i];
                    }
                    let sum = nb.iter().fold([0.0; 3], |s, &j| add(s, field[j as usize]));
                    add(scale(field[i], 0.5), scale(sum, 0.5 / nb.len() as f64))
                })
                .collect();
        }
        field
    }

    /// Whether `a` and `b` are adjacent (binary search in the sorted list of `a`).
    pub fn has_edge(&self, a: usize, b: usize) -> bool {
        self.neighbors(a).binary_search(&(b as u32)).is_ok()
    }

    /// Hop distances from `source`; [`UNREACHED`] for vertices in other components.
    pub fn bfs_distances(&self, source: usize) -> Vec<u32> {
        let mut bfs = Bfs::new(self.vertex_count());
        bfs.run(self, source);
        bfs.dist
    }

    /// Connected components: a label per vertex (numbered in order of their smallest
    /// vertex) and the number of components.
    pub fn components(&self) -> Components {
        let n = self.vertex_count();
        let mut label = vec![u32::MAX; n];
        let mut count = 0u32;
        let mut queue = VecDeque::new();
        for start in 0..n {
            if label[start] != u32::MAX {
                continue;
            }
            label[start] = count;
            queue.push_back(start as u32);
            while let Some(v) = queue.pop_front() {
                for &u in self.neighbors(v as usize) {
                    if label[u as usize] == u32::MAX {
                        label[u as usize] = count;
                        queue.push_back(u);
                    }
                }
            }
            count += 1;
        }
        Components {
            label,
            count: count as usize,
        }
    }
}

/// Connected-component labelling of a [`Graph`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Components {
    /// Component of each vertex, `0..count`, numbered by smallest member vertex.
    pub label: Vec<u32>,
    /// Number of components.
    pub count: usize,
}

impl Components {
    /// The vertices of each component, ascending.
    pub fn members(&self) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.count];
        for (v, &c) in self.label.iter().enumerate() {
            out[c as usize].push(v as u32);
        }
        out
    }
}

/// A reusable breadth-first search: keeps its distance buffer and queue between runs so
/// that algorithms running many searches (eccentricity bounds) allocate once.
#[derive(Clone, Debug)]
pub struct Bfs {
    /// Hop distance of each vertex from the last source; [`UNREACHED`] if not reached.
    pub dist: Vec<u32>,
    /// Vertices reached by the last run, in visiting order (non-decreasing distance).
    pub order: Vec<u32>,
}

impl Bfs {
    /// A search over graphs with `vertex_count` vertices.
    pub fn new(vertex_count: usize) -> Self {
        Bfs {
            dist: vec![UNREACHED; vertex_count],
            order: Vec::with_capacity(vertex_count),
        }
    }

    /// Runs from `source`, resetting only what the previous run touched. Returns the
    /// eccentricity of `source` within its component (the largest distance reached).
    pub fn run(&mut self, graph: &Graph, source: usize) -> u32 {
        for &v in &self.order {
            self.dist[v as usize] = UNREACHED;
        }
        self.order.clear();
        self.dist[source] = 0;
        self.order.push(source as u32);
        let mut head = 0;
        while head < self.order.len() {
            let v = self.order[head] as usize;
            head += 1;
            let next = self.dist[v] + 1;
            for &u in graph.neighbors(v) {
                let d = &mut self.dist[u as usize];
                if *d == UNREACHED {
                    *d = next;
                    self.order.push(u);
                }
            }
        }
        self.order.last().map_or(0, |&v| self.dist[v as usize])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(n: u32) -> Graph {
        let edges: Vec<[u32; 2]> = (0..n - 1).map(|i| [i, i + 1]).collect();
        Graph::from_edges(n as usize, &edges)
    }

    #[test]
    fn jacobi_smoothing_averages_with_the_neighbours_and_keeps_isolated_vertices() {
        // 0 - 1 - 2, and 3 alone.
        let g = Graph::from_edges(4, &[[0, 1], [1, 2]]);
        let f = [[0.0; 3], [1.0, 2.0, 0.0], [0.0; 3], [5.0; 3]];
        let once = g.jacobi_smooth(&f, 1);
        assert_eq!(once[0], [0.5, 1.0, 0.0]);
        assert_eq!(once[1], [0.5, 1.0, 0.0]);
        assert_eq!(once[2], [0.5, 1.0, 0.0]);
        assert_eq!(once[3], [5.0; 3]);
        assert_eq!(g.jacobi_smooth(&f, 0), f.to_vec());
        // Many rounds flatten a component to a constant.
        let many = path(5).jacobi_smooth(&[[0.0; 3], [0.0; 3], [5.0; 3], [0.0; 3], [0.0; 3]], 200);
        assert!(many.iter().all(|v| (v[0] - many[0][0]).abs() < 1e-6));
    }

    #[test]
    fn duplicate_and_reversed_edges_collapse() {
        let g = Graph::from_edges(3, &[[0, 1], [1, 0], [1, 2], [2, 2], [0, 1]]);
        assert_eq!(g.edge_count(), 2);
        assert_eq!(g.neighbors(1), &[0, 2]);
        assert_eq!(g.edges(), vec![[0, 1], [1, 2]]);
        assert!(g.has_edge(2, 1));
        assert!(!g.has_edge(0, 2));
    }

    #[test]
    fn bfs_on_a_path() {
        let g = path(5);
        assert_eq!(g.bfs_distances(0), vec![0, 1, 2, 3, 4]);
        let mut bfs = Bfs::new(5);
        assert_eq!(bfs.run(&g, 2), 2);
        assert_eq!(bfs.run(&g, 4), 4);
        assert_eq!(bfs.dist, vec![4, 3, 2, 1, 0]);
    }

    #[test]
    fn components_are_labelled_by_smallest_vertex() {
        let g = Graph::from_edges(6, &[[4, 5], [0, 2], [1, 3]]);
        let c = g.components();
        assert_eq!(c.count, 3);
        assert_eq!(c.label, vec![0, 1, 0, 1, 2, 2]);
        assert_eq!(c.members()[1], vec![1, 3]);
        assert_eq!(g.bfs_distances(0)[1], UNREACHED);
    }
}
