//! The message-passing adjacency every GAT layer runs on: destination-major CSR of
//! incoming edges with self-loops, plus its transpose.
//!
//! GAT (Veličković et al. 2018; seed 000 eq. 4, seed 001 eq. 3.4) attends over the
//! neighbourhood `N(i)` of node `i` *including `i` itself*, so the self-loop is part of the
//! adjacency, not a special case in the kernel. Row `i` lists the sources `j` of the edges
//! `j → i`, ascending, which makes every sum in the forward pass run in one fixed order: the
//! result is bit-identical whatever the thread count.
//!
//! The transpose (for every source `j`, the entries `e` with `src[e] = j`) lets the backward
//! pass accumulate into source rows without atomics: each thread owns the rows it writes.

use std::sync::Arc;

use burn::tensor::{Device, Int, Tensor, TensorData};
use weft_mesh::Graph;

use crate::error::{NnError, Result};

/// Destination-major CSR adjacency with self-loops and its transpose.
///
/// Invariants: `offsets.len() == n + 1`, row `i` (`offsets[i]..offsets[i + 1]`) holds
/// distinct ascending sources `< n`, and contains `i` when built with self-loops.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Adjacency {
    n: usize,
    offsets: Vec<usize>,
    sources: Vec<u32>,
    /// Destination of every entry (the row it sits in), for the edge-list form.
    targets: Vec<u32>,
    /// Transpose: `t_offsets[j]..t_offsets[j + 1]` indexes `t_entries`, the entries whose
    /// source is `j`, ascending.
    t_offsets: Vec<usize>,
    t_entries: Vec<u32>,
}

impl Adjacency {
    /// The GAT adjacency of an undirected mesh graph: `N(i) = neighbours(i) ∪ {i}`.
    pub fn from_graph(graph: &Graph) -> Self {
        let n = graph.vertex_count();
        let mut offsets = Vec::with_capacity(n + 1);
        let mut sources = Vec::with_capacity(graph.adjacency().len() + n);
        offsets.push(0);
        for i in 0..n {
            let mut placed = false;
            for &j in graph.neighbors(i) {
                if !placed && j as usize > i {
                    sources.push(i as u32);
                    placed = true;
                }
                sources.push(j);
            }
            if !placed {
                sources.push(i as u32);
            }
            offsets.push(sources.len());
        }
        Self::from_parts(n, offsets, sources)
    }

    /// A directed adjacency from a CSR of incoming edges (`sources` of row `i` are the `j`
    /// of the edges `j → i`), validated. Rows are sorted and deduplicated; with
    /// `self_loops` every node also attends to itself.
    pub fn from_csr(
        n: usize,
        offsets: &[usize],
        sources: &[u32],
        self_loops: bool,
    ) -> Result<Self> {
        if offsets.len() != n + 1 {
            return Err(NnError::Shape {
                what: "adjacency offsets",
                expected: vec![n + 1],
                got: vec![offsets.len()],
            });
        }
        if offsets[0] != 0 || offsets[n] != sources.len() || offsets.windows(2).any(|w| w[0] > w[1])
        {
            return Err(NnError::Config(format!(
                "adjacency offsets must rise from 0 to {} (the source count)",
                sources.len()
            )));
        }
        let mut new_offsets = Vec::with_capacity(n + 1);
        let mut new_sources = Vec::with_capacity(sources.len() + if self_loops { n } else { 0 });
        new_offsets.push(0);
        let mut row = Vec::new();
        for i in 0..n {
            row.clear();
            for &j in &sources[offsets[i]..offsets[i + 1]] {
                if j as usize >= n {
                    return Err(NnError::Index {
                        what: "adjacency source",
                        index: j as usize,
                        len: n,
                    });
                }
                row.push(j);
            }
            if self_loops {
                row.push(i as u32);
            }
            row.sort_unstable();
            row.dedup();
            new_sources.extend_from_slice(&row);
            new_offsets.push(new_sources.len());
        }
        Ok(Self::from_parts(n, new_offsets, new_sources))
    }

    /// A directed adjacency from an edge list `[source, target]`.
    pub fn from_edges(n: usize, edges: &[[u32; 2]], self_loops: bool) -> Result<Self> {
        let mut count = vec![0usize; n + 1];
        for &[s, t] in edges {
            for v in [s, t] {
                if v as usize >= n {
                    return Err(NnError::Index {
                        what: "edge endpoint",
                        index: v as usize,
                        len: n,
                    });
                }
            }
            count[t as usize + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut sources = vec![0u32; edges.len()];
        for &[s, t] in edges {
            sources[fill[t as usize]] = s;
            fill[t as usize] += 1;
        }
        Self::from_csr(n, &count, &sources, self_loops)
    }

    fn from_parts(n: usize, offsets: Vec<usize>, sources: Vec<u32>) -> Self {
        let mut targets = Vec::with_capacity(sources.len());
        for i in 0..n {
            targets.extend(std::iter::repeat_n(i as u32, offsets[i + 1] - offsets[i]));
        }
        // Entries are visited in ascending order, so each transpose row is ascending.
        let (t_offsets, t_entries) = group_by_key(n, &sources);
        Adjacency {
            n,
            offsets,
            sources,
            targets,
            t_offsets,
            t_entries,
        }
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.n
    }

    /// Number of directed entries (edges `j → i`, self-loops included).
    pub fn entry_count(&self) -> usize {
        self.sources.len()
    }

    /// Row offsets (length `n + 1`).
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// Sources of all entries, row by row.
    pub fn sources(&self) -> &[u32] {
        &self.sources
    }

    /// Destination of every entry.
    pub fn targets(&self) -> &[u32] {
        &self.targets
    }

    /// Sources of the edges into `i`.
    pub fn incoming(&self, i: usize) -> &[u32] {
        &self.sources[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Transpose offsets (length `n + 1`) into [`Adjacency::transpose_entries`].
    pub fn transpose_offsets(&self) -> &[usize] {
        &self.t_offsets
    }

    /// Entry indices grouped by source node.
    pub fn transpose_entries(&self) -> &[u32] {
        &self.t_entries
    }

    /// The edge list as two index tensors `(sources, targets)` for the generic tensor path.
    pub fn index_tensors(&self, device: &Device) -> (Tensor<1, Int>, Tensor<1, Int>) {
        (
            index_tensor(&self.sources, device),
            index_tensor(&self.targets, device),
        )
    }

    /// Shares the adjacency, as the fused operation takes it.
    pub fn into_shared(self) -> Arc<Self> {
        Arc::new(self)
    }
}

/// The positions of `keys` (each `< n`) grouped by key, by counting: key `k`'s positions
/// are `order[offsets[k]..offsets[k + 1]]`, ascending.
pub(crate) fn group_by_key(n: usize, keys: &[u32]) -> (Vec<usize>, Vec<u32>) {
    let mut offsets = vec![0usize; n + 1];
    for &k in keys {
        offsets[k as usize + 1] += 1;
    }
    for k in 0..n {
        offsets[k + 1] += offsets[k];
    }
    let mut next = offsets.clone();
    let mut order = vec![0u32; keys.len()];
    for (i, &k) in keys.iter().enumerate() {
        order[next[k as usize]] = i as u32;
        next[k as usize] += 1;
    }
    (offsets, order)
}

/// A 1-D integer tensor of indices.
pub fn index_tensor(indices: &[u32], device: &Device) -> Tensor<1, Int> {
    let data: Vec<i64> = indices.iter().map(|&i| i64::from(i)).collect();
    Tensor::from_data(TensorData::new(data, [indices.len()]), device)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graph_rows_hold_self_loops_in_order() {
        let g = Graph::from_edges(4, &[[0, 1], [1, 2], [2, 3], [3, 0]]);
        let a = Adjacency::from_graph(&g);
        assert_eq!(a.incoming(0), &[0, 1, 3]);
        assert_eq!(a.incoming(2), &[1, 2, 3]);
        assert_eq!(a.entry_count(), 8 + 4);
        // Transpose lists every entry once, grouped by source.
        let mut seen = vec![false; a.entry_count()];
        for j in 0..4 {
            for &e in &a.t_entries[a.t_offsets[j]..a.t_offsets[j + 1]] {
                assert_eq!(a.sources()[e as usize] as usize, j);
                seen[e as usize] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn csr_is_validated() {
        assert!(matches!(
            Adjacency::from_csr(2, &[0, 1, 2], &[1, 5], true),
            Err(NnError::Index { index: 5, .. })
        ));
        assert!(Adjacency::from_csr(2, &[0, 2], &[1, 0], true).is_err());
        let a = Adjacency::from_edges(3, &[[0, 1], [2, 1], [0, 1]], true).unwrap();
        assert_eq!(a.incoming(1), &[0, 1, 2]);
        assert_eq!(a.incoming(0), &[0]);
    }
}
