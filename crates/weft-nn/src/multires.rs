//! The multi-resolution GAT module of seed 001 (MultiResGModule, §3.3.2, Fig. 3.15): a
//! local branch and a global branch on the same node features, concatenated.
//!
//! - **local**: one dense module of `m` GAT blocks (eq. 3.6) on the fine graph;
//! - **global**: edge-contraction pooling (eq. 3.10–3.11, about half the nodes remain),
//!   GAT blocks in sequence on the pooled graph, unpooling (eq. 3.12), and one more GAT
//!   block on the fine graph (eq. 3.13's `f_GATB`).
//!
//! MultiResGNet puts one between its input and output transforms; GarFitNet (ch. 4) uses
//! one per output branch. Without the global branch it is the "single resolution"
//! ablation of Table 3.4.

use std::sync::Arc;

use burn::config::Config;
use burn::module::Module;
use burn::tensor::{Device, Tensor};

use crate::activation::Activation;
use crate::adjacency::Adjacency;
use crate::batch::GraphBatch;
use crate::dense::{DenseGatModule, DenseGatModuleConfig, NormedGat};
use crate::error::NnError;
use crate::pool::{edge_unpool, EdgePool, EdgePoolConfig};

/// Configuration of a [`MultiResGModule`].
#[derive(Config, Debug, PartialEq)]
pub struct MultiResGModuleConfig {
    /// Input features per node.
    pub d_input: usize,
    /// GAT blocks `m` of the local branch's dense module.
    #[config(default = 6)]
    pub local_blocks: usize,
    /// Channels per head `F` of every GAT block and of the pooling's attention.
    #[config(default = 16)]
    pub channels: usize,
    /// Heads `K`.
    #[config(default = 8)]
    pub heads: usize,
    /// β of the self-reinforced stream, or none.
    #[config(default = "Some(1.0)")]
    pub self_reinforced: Option<f64>,
    /// Batch normalisation after every block.
    #[config(default = true)]
    pub batch_norm: bool,
    /// σ of the GAT blocks.
    #[config(default = "Activation::Tanhshrink")]
    pub activation: Activation,
    /// The global branch (else single resolution).
    #[config(default = true)]
    pub global: bool,
    /// GAT blocks on the pooled graph (the `f_GATB` after unpooling comes on top).
    #[config(default = 2)]
    pub global_blocks: usize,
    /// Added to the pooling scores `α`: 0 is the thesis, 0.5 PyG's EdgePool.
    #[config(default = 0.0)]
    pub score_offset: f64,
}

impl MultiResGModuleConfig {
    /// `blocks` GAT blocks of this module's widths reading `d_input` features, densely
    /// connected or in sequence.
    fn blocks(&self, d_input: usize, blocks: usize, dense: bool) -> DenseGatModuleConfig {
        DenseGatModuleConfig::new(d_input, blocks, self.channels)
            .with_heads(self.heads)
            .with_self_reinforced(self.self_reinforced)
            .with_activation(self.activation)
            .with_batch_norm(self.batch_norm)
            .with_dense(dense)
    }

    /// Builds the module; errors on zero sizes and as its layers do.
    pub fn init(&self, device: &Device) -> crate::Result<MultiResGModule> {
        let local = self
            .blocks(self.d_input, self.local_blocks, true)
            .init(device)?;
        let global = if self.global {
            if self.global_blocks == 0 {
                return Err(NnError::Config(
                    "the global branch needs at least one block on the pooled graph".into(),
                ));
            }
            let pool = EdgePoolConfig::new(self.d_input)
                .with_channels(self.channels)
                .with_score_offset(self.score_offset)
                .init(device)?;
            let blocks = self.blocks(self.d_input, self.global_blocks, false);
            let coarse = blocks.init(device)?;
            let after = blocks.block(blocks.output_width()).init(device)?;
            Some(GlobalBranch {
                pool,
                coarse,
                after,
            })
        } else {
            None
        };
        Ok(MultiResGModule { local, global })
    }
}

/// The global branch: pool, GAT blocks on the pooled graph, unpool, `f_GATB`.
#[derive(Module, Debug)]
pub struct GlobalBranch {
    /// Edge-contraction pooling of the module's input (eq. 3.10–3.11).
    pub pool: EdgePool,
    /// GAT blocks in sequence on the pooled graph.
    pub coarse: DenseGatModule,
    /// The GAT block after unpooling (eq. 3.13's `f_GATB`).
    pub after: NormedGat,
}

impl GlobalBranch {
    /// `x`: `[N, d]` on `graph`; returns `[N, after.output_width()]`.
    pub fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> crate::Result<Tensor<2>> {
        let pooled = self.pool.forward(x, graph)?;
        let coarse = pooled.clusters.coarse.adjacency();
        let g = self.coarse.forward(pooled.features, coarse)?;
        let g = edge_unpool(g, &pooled.clusters)?;
        self.after.forward(g, graph.adjacency())
    }
}

/// The local and global branches; see the module documentation.
#[derive(Module, Debug)]
pub struct MultiResGModule {
    /// The local branch's dense module.
    pub local: DenseGatModule,
    /// The global branch, or none (single resolution).
    pub global: Option<GlobalBranch>,
}

impl MultiResGModule {
    /// Input features per node.
    pub fn input_width(&self) -> usize {
        self.local.input_width()
    }

    /// Output features per node: the local branch's, then the global branch's.
    pub fn output_width(&self) -> usize {
        self.local.output_width() + self.global.as_ref().map_or(0, |g| g.after.output_width())
    }

    /// `x`: `[N, d_input]` on `graph`; returns `[N, output_width]`.
    pub fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> crate::Result<Tensor<2>> {
        let adjacency: &Arc<Adjacency> = graph.adjacency();
        let local = self.local.forward(x.clone(), adjacency)?;
        Ok(match &self.global {
            Some(global) => Tensor::cat(vec![local, global.forward(x, graph)?], 1),
            None => local,
        })
    }
}

#[cfg(test)]
mod tests {
    use burn::tensor::Distribution;
    use weft_mesh::primitives::grid;

    use super::*;
    use crate::backend::cpu;

    #[test]
    fn widths_branches_and_the_single_resolution_form() {
        let device = cpu();
        let m = MultiResGModuleConfig::new(32).init(&device).unwrap();
        // The thesis's widths: local 32 + 6·256, global 256.
        assert_eq!(m.local.output_width(), 32 + 6 * 256);
        assert_eq!(m.output_width(), 32 + 7 * 256);
        let mesh = grid(9, 7, 1.0);
        let graph = GraphBatch::single(&mesh.graph());
        let n = mesh.positions.len();
        let x = Tensor::<2>::random([n, 32], Distribution::Default, &device);
        let y = m.forward(x.clone(), &graph).unwrap();
        assert_eq!(y.dims(), [n, m.output_width()]);
        // The first columns are the local branch alone.
        let local = m.local.forward(x.clone(), graph.adjacency()).unwrap();
        let head = y.slice([0..n, 0..m.local.output_width()]);
        assert!(head.sub(local).abs().max().into_scalar::<f32>() < 1e-6);
        let single = MultiResGModuleConfig::new(32)
            .with_global(false)
            .with_local_blocks(2)
            .with_channels(4)
            .with_heads(2)
            .init(&device)
            .unwrap();
        assert!(single.global.is_none());
        assert_eq!(single.output_width(), 32 + 2 * 16);
        assert!(MultiResGModuleConfig::new(32)
            .with_global_blocks(0)
            .init(&device)
            .is_err());
        assert!(m.forward(Tensor::zeros([n, 31], &device), &graph).is_err());
    }
}
