//! Pooling and unpooling layers.
//!
//! - [`structure`]: the structure-preserving pooling of seed 000 (Algorithm 1: keep the
//!   vertices at even hop distance from the center) and its neighbour-weighted unpooling
//!   (Algorithm 2), both precomputed by weft-hierarchy and applied here as a row selection
//!   and a sparse product.
//! - The learned baselines of seed 000 Table 1, each with unpooling by index
//!   ([`unpool_by_index`]: the pooled rows go back to where they came from, zeros elsewhere,
//!   as in Graph U-Nets):
//!   [`topk`] (Gao & Ji 2019), [`sag`] (Lee et al. 2019), [`asap`] (Ranjan et al. 2020).
//! - [`edge`]: edge-contraction pooling and its unpooling (seed 001 eq. 3.10–3.12,
//!   MultiResGNet's global branch; Diehl's EdgePool).

pub mod asap;
pub mod edge;
pub mod sag;
pub mod structure;
pub mod topk;

use burn::tensor::{IndexingUpdateOp, Tensor};
use weft_mesh::Graph;

use crate::adjacency::index_tensor;
use crate::batch::GraphBatch;
use crate::error::{check_shape, NnError, Result, ANY};

pub use asap::{AsapPool, AsapPoolConfig};
pub use edge::{edge_unpool, Clusters, EdgePool, EdgePoolConfig, EdgePooled};
pub use sag::{SagPool, SagPoolConfig};
pub use structure::{StructurePool, StructureUnpool};
pub use topk::{TopKPool, TopKPoolConfig};

/// How a learned pooling connects the nodes it keeps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Connectivity {
    /// The induced subgraph `A[idx, idx]` (PyG's TopKPooling / SAGPooling).
    #[default]
    Induced,
    /// Kept nodes within two hops, `A²[idx, idx]` (Graph U-Nets' augmentation, which keeps
    /// a sparse selection connected).
    TwoHop,
}

/// Which rows a learned pooling kept, and the coarse graph on them.
#[derive(Clone, Debug)]
pub struct Selection {
    /// Kept rows of the fine batch, ascending (so per graph, in node order).
    pub kept: Vec<u32>,
    /// The coarse graphs as a batch (row `r` is fine row `kept[r]`).
    pub coarse: GraphBatch,
    /// Rows of the fine batch.
    pub fine_count: usize,
}

/// The output of a learned pooling layer.
#[derive(Clone, Debug)]
pub struct Pooled {
    /// Coarse features `[kept, C]`, gated by the scores.
    pub features: Tensor<2>,
    /// What was kept.
    pub selection: Selection,
}

/// Checks a pooling ratio in `(0, 1]`.
pub(crate) fn check_ratio(ratio: f64) -> Result<()> {
    if ratio > 0.0 && ratio <= 1.0 {
        Ok(())
    } else {
        Err(NnError::Config(format!(
            "pooling ratio must be in (0, 1], got {ratio}"
        )))
    }
}

/// Per graph, the `ceil(ratio · N_g)` (at least one) rows of highest score; ties go to the
/// lower index, so the choice is deterministic. Returned ascending.
pub(crate) fn top_k(scores: &[f32], batch: &GraphBatch, ratio: f64) -> Vec<u32> {
    let mut kept = Vec::new();
    for g in 0..batch.graph_count() {
        let rows = batch.nodes(g);
        let n = rows.len();
        if n == 0 {
            continue;
        }
        let k = ((ratio * n as f64).ceil() as usize).clamp(1, n);
        let mut order: Vec<usize> = rows.collect();
        order.sort_by(|&a, &b| {
            scores[b]
                .partial_cmp(&scores[a])
                .unwrap_or(std::cmp::Ordering::Equal)
                .then(a.cmp(&b))
        });
        let mut chosen: Vec<u32> = order[..k].iter().map(|&r| r as u32).collect();
        chosen.sort_unstable();
        kept.extend(chosen);
    }
    kept
}

/// The coarse batch on `kept` (ascending fine rows).
pub(crate) fn coarsen(batch: &GraphBatch, kept: &[u32], connectivity: Connectivity) -> GraphBatch {
    let fine = batch.graph();
    let mut coarse_index = vec![u32::MAX; fine.vertex_count()];
    for (c, &v) in kept.iter().enumerate() {
        coarse_index[v as usize] = c as u32;
    }
    let mut edges = Vec::new();
    for (c, &v) in kept.iter().enumerate() {
        for &u in fine.neighbors(v as usize) {
            let cu = coarse_index[u as usize];
            if cu != u32::MAX && (c as u32) < cu {
                edges.push([c as u32, cu]);
            }
            if connectivity == Connectivity::TwoHop {
                for &w in fine.neighbors(u as usize) {
                    let cw = coarse_index[w as usize];
                    if cw != u32::MAX && (c as u32) < cw {
                        edges.push([c as u32, cw]);
                    }
                }
            }
        }
    }
    batch_on(batch, kept, &edges)
}

/// The coarse batch on `kept` (ascending rows of `batch`) with `edges` in coarse numbering.
pub(crate) fn batch_on(batch: &GraphBatch, kept: &[u32], edges: &[[u32; 2]]) -> GraphBatch {
    let graph = Graph::from_edges(kept.len(), edges);
    let mut offsets = vec![0usize];
    let mut r = 0usize;
    for g in 0..batch.graph_count() {
        let end = batch.nodes(g).end;
        while r < kept.len() && (kept[r] as usize) < end {
            r += 1;
        }
        offsets.push(r);
    }
    GraphBatch::from_union(graph, offsets)
}

/// Unpooling by index: coarse row `r` goes back to fine row `kept[r]`, other rows are zero
/// (Graph U-Nets' gPool inverse, used for TopK, SAG and ASAP).
pub fn unpool_by_index(coarse: Tensor<2>, selection: &Selection) -> Result<Tensor<2>> {
    check_shape(
        "unpooling input",
        &[selection.kept.len(), ANY],
        &coarse.dims(),
    )?;
    let device = coarse.device();
    let width = coarse.dims()[1];
    let dtype = coarse.dtype();
    Ok(
        Tensor::<2>::zeros([selection.fine_count, width], (&device, dtype)).select_assign(
            0,
            index_tensor(&selection.kept, &device),
            coarse,
            IndexingUpdateOp::Add,
        ),
    )
}

/// Reads a `[N, 1]` score tensor to the host.
pub(crate) fn host_scores(scores: &Tensor<2>) -> Vec<f32> {
    scores
        .clone()
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .unwrap_or_default()
}

#[cfg(test)]
mod tests;
