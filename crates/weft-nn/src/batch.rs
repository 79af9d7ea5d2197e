//! Batches of different garments as one disjoint graph.
//!
//! Garments differ in vertex count and topology, so a batch cannot be a `[B, N, C]` tensor.
//! As in PyTorch Geometric, the graphs are laid side by side: graph `g`'s nodes are the rows
//! `offsets[g]..offsets[g + 1]` of one `[ΣN_g, C]` feature matrix, and its edges are shifted
//! by `offsets[g]`. Message passing never crosses graphs because no edge does; pooling and
//! unpooling act per graph through block-diagonal maps ([`HierarchyBatch`]).

use std::sync::Arc;

use burn::tensor::{Device, Int, Tensor};
use weft_hierarchy::Hierarchy;
use weft_mesh::Graph;

use crate::adjacency::{index_tensor, Adjacency};
use crate::error::{check_shape, NnError, Result, ANY};
use crate::sparse::SparseMatrix;

/// Several graphs as one disjoint graph with node offsets.
#[derive(Clone, Debug)]
pub struct GraphBatch {
    graph: Graph,
    adjacency: Arc<Adjacency>,
    offsets: Vec<usize>,
}

impl GraphBatch {
    /// The disjoint union of `graphs`, in order. Errors on an empty list.
    pub fn new(graphs: &[&Graph]) -> Result<Self> {
        if graphs.is_empty() {
            return Err(NnError::EmptyBatch);
        }
        let total: usize = graphs.iter().map(|g| g.vertex_count()).sum();
        if u32::try_from(total).is_err() {
            return Err(NnError::Config(format!(
                "a batch holds at most {} nodes, got {total}",
                u32::MAX
            )));
        }
        let mut offsets = vec![0usize];
        let mut edges = Vec::new();
        for g in graphs {
            let base = *offsets.last().unwrap_or(&0);
            edges.extend(
                g.edges()
                    .into_iter()
                    .map(|[a, b]| [a + base as u32, b + base as u32]),
            );
            offsets.push(base + g.vertex_count());
        }
        let graph = Graph::from_edges(total, &edges);
        Ok(GraphBatch {
            adjacency: Arc::new(Adjacency::from_graph(&graph)),
            graph,
            offsets,
        })
    }

    /// A batch from a union graph and its node offsets (they must cover the graph, and no
    /// edge may cross two ranges: pooling layers build these from an existing batch).
    pub(crate) fn from_union(graph: Graph, offsets: Vec<usize>) -> Self {
        debug_assert_eq!(offsets.last().copied(), Some(graph.vertex_count()));
        GraphBatch {
            adjacency: Arc::new(Adjacency::from_graph(&graph)),
            graph,
            offsets,
        }
    }

    /// A batch of one graph.
    pub fn single(graph: &Graph) -> Self {
        Self::new(&[graph]).expect("one graph is a non-empty batch")
    }

    /// The union graph.
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// The GAT adjacency of the union (self-loops included).
    pub fn adjacency(&self) -> &Arc<Adjacency> {
        &self.adjacency
    }

    /// Number of graphs.
    pub fn graph_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Total number of nodes.
    pub fn node_count(&self) -> usize {
        *self.offsets.last().unwrap_or(&0)
    }

    /// Node offsets, length `graph_count + 1`.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// The rows of graph `g`.
    pub fn nodes(&self, g: usize) -> std::ops::Range<usize> {
        self.offsets[g]..self.offsets[g + 1]
    }

    /// For every node, the graph it belongs to.
    pub fn membership(&self) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.node_count());
        for g in 0..self.graph_count() {
            out.extend(std::iter::repeat_n(
                g as u32,
                self.offsets[g + 1] - self.offsets[g],
            ));
        }
        out
    }

    /// [`GraphBatch::membership`] as an index tensor.
    pub fn membership_tensor(&self, device: &Device) -> Tensor<1, Int> {
        index_tensor(&self.membership(), device)
    }

    /// Stacks per-graph features `[N_g, C]` into the batch's `[ΣN_g, C]`.
    pub fn stack(&self, features: Vec<Tensor<2>>) -> Result<Tensor<2>> {
        if features.len() != self.graph_count() {
            return Err(NnError::Config(format!(
                "the batch has {} graphs, got features for {}",
                self.graph_count(),
                features.len()
            )));
        }
        let width = features[0].dims()[1];
        for (g, f) in features.iter().enumerate() {
            check_shape(
                "per-graph features",
                &[self.nodes(g).len(), width],
                &f.dims(),
            )?;
        }
        Ok(Tensor::cat(features, 0))
    }

    /// Splits batch features `[ΣN_g, C]` back into one tensor per graph.
    pub fn split(&self, features: Tensor<2>) -> Result<Vec<Tensor<2>>> {
        check_shape(
            "batch features",
            &[self.node_count(), ANY],
            &features.dims(),
        )?;
        let width = features.dims()[1];
        Ok((0..self.graph_count())
            .map(|g| {
                let r = self.nodes(g);
                features.clone().slice([r.start..r.end, 0..width])
            })
            .collect())
    }
}

/// One level of a [`HierarchyBatch`] below the finest.
#[derive(Clone, Debug)]
pub struct BatchLevel {
    /// The level's graphs as one batch.
    pub batch: GraphBatch,
    /// Rows of the finer level kept here (batch numbering, ascending).
    pub kept: Vec<u32>,
    /// Unpooling from this level to the finer one (block-diagonal, Algorithm 2).
    pub unpooling: Arc<SparseMatrix>,
}

/// Hierarchies of several garments, level by level, as disjoint batches: the input of the
/// structure-preserving pooling layers ([`crate::pool::StructurePool`],
/// [`crate::pool::StructureUnpool`]).
#[derive(Clone, Debug)]
pub struct HierarchyBatch {
    finest: GraphBatch,
    coarser: Vec<BatchLevel>,
}

impl HierarchyBatch {
    /// Batches `hierarchies` level by level. They must have the same number of levels
    /// (build them with the same level count on meshes large enough to pool that often).
    pub fn new(hierarchies: &[&Hierarchy]) -> Result<Self> {
        let first = hierarchies.first().ok_or(NnError::EmptyBatch)?;
        let levels = first.len();
        if let Some(h) = hierarchies.iter().find(|h| h.len() != levels) {
            return Err(NnError::Config(format!(
                "hierarchies in one batch need the same number of levels: {} and {}",
                levels,
                h.len()
            )));
        }
        let level_batch = |l: usize| {
            let graphs: Vec<&Graph> = hierarchies.iter().map(|h| &h.levels()[l].graph).collect();
            GraphBatch::new(&graphs)
        };
        let finest = level_batch(0)?;
        let mut coarser = Vec::with_capacity(levels.saturating_sub(1));
        for l in 1..levels {
            let batch = level_batch(l)?;
            let finer_offsets = if l == 1 {
                finest.offsets().to_vec()
            } else {
                coarser
                    .last()
                    .map(|c: &BatchLevel| c.batch.offsets().to_vec())
                    .unwrap_or_default()
            };
            let mut kept = Vec::with_capacity(batch.node_count());
            let mut blocks = Vec::with_capacity(hierarchies.len());
            for (g, h) in hierarchies.iter().enumerate() {
                let level = &h.levels()[l];
                kept.extend(level.kept.iter().map(|&v| v + finer_offsets[g] as u32));
                let unpooling = level.unpooling.as_ref().ok_or_else(|| {
                    NnError::Config(format!("hierarchy level {l} has no unpooling"))
                })?;
                blocks.push(SparseMatrix::from_unpooling(unpooling));
            }
            let refs: Vec<&SparseMatrix> = blocks.iter().collect();
            coarser.push(BatchLevel {
                batch,
                kept,
                unpooling: Arc::new(SparseMatrix::block_diagonal(&refs)),
            });
        }
        Ok(HierarchyBatch { finest, coarser })
    }

    /// Number of levels (the finest included).
    pub fn len(&self) -> usize {
        self.coarser.len() + 1
    }

    /// Always false: there is a finest level.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The batch of level `l`.
    pub fn batch(&self, l: usize) -> &GraphBatch {
        if l == 0 {
            &self.finest
        } else {
            &self.coarser[l - 1].batch
        }
    }

    /// Level `l ≥ 1`: kept rows and unpooling; `None` for level 0 or past the coarsest.
    pub fn level(&self, l: usize) -> Option<&BatchLevel> {
        l.checked_sub(1).and_then(|i| self.coarser.get(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::cpu;
    use burn::tensor::TensorData;

    fn path(n: u32) -> Graph {
        Graph::from_edges(
            n as usize,
            &(0..n - 1).map(|i| [i, i + 1]).collect::<Vec<_>>(),
        )
    }

    #[test]
    fn union_shifts_edges_and_keeps_graphs_apart() {
        let (a, b) = (path(3), path(4));
        let batch = GraphBatch::new(&[&a, &b]).unwrap();
        assert_eq!(batch.node_count(), 7);
        assert_eq!(batch.offsets(), &[0, 3, 7]);
        assert_eq!(batch.adjacency().incoming(3), &[3, 4]);
        assert_eq!(batch.adjacency().incoming(2), &[1, 2]);
        assert_eq!(batch.membership(), vec![0, 0, 0, 1, 1, 1, 1]);
        let x = Tensor::<2>::from_data(
            TensorData::new((0..14).map(|v| v as f32).collect::<Vec<_>>(), [7, 2]),
            &cpu(),
        );
        let parts = batch.split(x.clone()).unwrap();
        assert_eq!(parts[1].dims(), [4, 2]);
        let back = batch.stack(parts).unwrap();
        back.into_data().assert_eq(&x.into_data(), true);
        assert!(matches!(GraphBatch::new(&[]), Err(NnError::EmptyBatch)));
    }

    #[test]
    fn hierarchy_batch_offsets_kept_rows() {
        let (a, b) = (path(5), path(7));
        let ha = Hierarchy::build(a, 2).unwrap();
        let hb = Hierarchy::build(b, 2).unwrap();
        let hbatch = HierarchyBatch::new(&[&ha, &hb]).unwrap();
        assert_eq!(hbatch.len(), 2);
        let level = hbatch.level(1).unwrap();
        let ka = &ha.levels()[1].kept;
        assert_eq!(&level.kept[..ka.len()], &ka[..]);
        assert_eq!(level.kept[ka.len()], hb.levels()[1].kept[0] + 5);
        assert_eq!(level.unpooling.rows(), 12);
        assert_eq!(level.unpooling.cols(), level.batch.node_count());
    }
}
