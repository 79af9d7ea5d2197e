//! SAGPool (Lee et al. 2019, self-attention graph pooling): the scores come from a graph
//! convolution, so they see the neighbourhood: `Z = tanh(Â X Θ)` with
//! `Â = D̃^{-1/2}(A + I)D̃^{-1/2}` (Kipf & Welling GCN); then the top `⌈ratio · N⌉` nodes
//! per graph, gated by their score: `X' = X[idx] ⊙ Z[idx]`.

use std::sync::Arc;

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::{Device, Tensor};

use super::topk::gate_and_coarsen;
use super::{check_ratio, Connectivity, Pooled};
use crate::batch::GraphBatch;
use crate::error::{check_shape, NnError};
use crate::sparse::{sparse_matmul, SparseImpl, SparseMatrix};

/// Configuration of a [`SagPool`].
#[derive(Config, Debug)]
pub struct SagPoolConfig {
    /// Features per node.
    pub channels: usize,
    /// Fraction of nodes kept per graph, in (0, 1].
    #[config(default = 0.5)]
    pub ratio: f64,
    /// Edges of the pooled graph.
    #[config(default = "Connectivity::Induced")]
    pub connectivity: Connectivity,
}

impl SagPoolConfig {
    /// Builds the layer (Glorot-uniform GCN weight; no bias, so the score is exactly
    /// `Â X Θ`).
    pub fn init(&self, device: &Device) -> crate::Result<SagPool> {
        check_ratio(self.ratio)?;
        if self.channels == 0 {
            return Err(NnError::Config("SAGPool needs channels > 0".into()));
        }
        Ok(SagPool {
            score: LinearConfig::new(self.channels, 1)
                .with_bias(false)
                .with_initializer(Initializer::XavierUniform { gain: 1.0 })
                .init(device),
            ratio: self.ratio,
            connectivity: self.connectivity,
        })
    }
}

/// SAGPool; see the module documentation.
#[derive(Module, Debug)]
pub struct SagPool {
    /// Θ of the scoring GCN, `C → 1`.
    pub score: Linear,
    /// Fraction kept.
    pub ratio: f64,
    #[module(skip)]
    connectivity: Connectivity,
}

/// The symmetric-normalised adjacency with self-loops of a batch, `D̃^{-1/2}(A+I)D̃^{-1/2}`.
pub fn gcn_normalized(batch: &GraphBatch) -> SparseMatrix {
    let adj = batch.adjacency();
    let n = adj.node_count();
    let inv_sqrt: Vec<f64> = (0..n)
        .map(|i| 1.0 / (adj.incoming(i).len() as f64).sqrt())
        .collect();
    let triplets = (0..n).flat_map(|i| {
        let inv_sqrt = &inv_sqrt;
        adj.incoming(i)
            .iter()
            .map(move |&j| (i as u32, j, inv_sqrt[i] * inv_sqrt[j as usize]))
    });
    SparseMatrix::from_triplets(n, n, triplets).expect("adjacency indices are in range")
}

impl SagPool {
    /// Pools `x` (`[N, C]` on `batch`).
    pub fn forward(&self, x: Tensor<2>, batch: &GraphBatch) -> crate::Result<Pooled> {
        let channels = self.score.weight.shape().dims::<2>()[0];
        check_shape("SAGPool input", &[batch.node_count(), channels], &x.dims())?;
        let a_hat = Arc::new(gcn_normalized(batch));
        let scores = sparse_matmul(&a_hat, self.score.forward(x.clone()), SparseImpl::Auto)?;
        gate_and_coarsen(x, scores, batch, self.ratio, self.connectivity)
    }
}
