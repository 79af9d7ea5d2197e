//! TopKPool (gPool of Graph U-Nets, Gao & Ji 2019): a learned projection scores every node,
//! `y = X p / ‖p‖`; each graph keeps its `⌈ratio · N⌉` best nodes, gated by `tanh(y)` so
//! the projection receives a gradient: `X' = X[idx] ⊙ tanh(y[idx])`.

use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::Initializer;
use burn::tensor::{Device, Tensor};

use super::{check_ratio, coarsen, host_scores, top_k, Connectivity, Pooled, Selection};
use crate::adjacency::index_tensor;
use crate::batch::GraphBatch;
use crate::error::{check_shape, NnError, ANY};

/// Configuration of a [`TopKPool`].
#[derive(Config, Debug)]
pub struct TopKPoolConfig {
    /// Features per node.
    pub channels: usize,
    /// Fraction of nodes kept per graph, in (0, 1].
    #[config(default = 0.5)]
    pub ratio: f64,
    /// Edges of the pooled graph.
    #[config(default = "Connectivity::Induced")]
    pub connectivity: Connectivity,
}

impl TopKPoolConfig {
    /// Builds the layer (Glorot-uniform projection).
    pub fn init(&self, device: &Device) -> crate::Result<TopKPool> {
        check_ratio(self.ratio)?;
        if self.channels == 0 {
            return Err(NnError::Config("TopKPool needs channels > 0".into()));
        }
        Ok(TopKPool {
            projection: Initializer::XavierUniform { gain: 1.0 }.init_with(
                [self.channels, 1],
                Some(self.channels),
                Some(1),
                device,
            ),
            ratio: self.ratio,
            connectivity: self.connectivity,
        })
    }
}

/// TopKPool; see the module documentation.
#[derive(Module, Debug)]
pub struct TopKPool {
    /// The projection `p`, `[C, 1]`.
    pub projection: Param<Tensor<2>>,
    /// Fraction kept.
    pub ratio: f64,
    #[module(skip)]
    connectivity: Connectivity,
}

impl TopKPool {
    /// Pools `x` (`[N, C]` on `batch`).
    pub fn forward(&self, x: Tensor<2>, batch: &GraphBatch) -> crate::Result<Pooled> {
        let channels = self.projection.shape().dims::<2>()[0];
        check_shape("TopKPool input", &[batch.node_count(), channels], &x.dims())?;
        let p = self.projection.val();
        let norm = p.clone().powf_scalar(2.0).sum().sqrt().reshape([1, 1]);
        let scores = x.clone().matmul(p) / norm;
        gate_and_coarsen(x, scores, batch, self.ratio, self.connectivity)
    }
}

/// The shared tail of TopK and SAG pooling: choose the rows by `scores` (`[N, 1]`), gate
/// them by `tanh(score)`, build the coarse graph.
pub(crate) fn gate_and_coarsen(
    x: Tensor<2>,
    scores: Tensor<2>,
    batch: &GraphBatch,
    ratio: f64,
    connectivity: Connectivity,
) -> crate::Result<Pooled> {
    check_shape("pooling scores", &[batch.node_count(), 1], &scores.dims())?;
    check_shape("pooling input", &[batch.node_count(), ANY], &x.dims())?;
    let kept = top_k(&host_scores(&scores), batch, ratio);
    let idx = index_tensor(&kept, &x.device());
    let features = x.select(0, idx.clone()) * scores.select(0, idx).tanh();
    Ok(Pooled {
        features,
        selection: Selection {
            coarse: coarsen(batch, &kept, connectivity),
            fine_count: batch.node_count(),
            kept,
        },
    })
}
