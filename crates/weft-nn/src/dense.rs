//! Densely connected GAT blocks (seed 001 §3.2.2.3, eq. 3.6, Fig. 3.5): the dense modules of
//! DenseGATs and the local branch of MultiResGNet.
//!
//! - [`NormedGat`]: a GAT block followed by 1-D batch normalisation, then σ. The thesis
//!   normalises "all the outputs of layers"; the normalisation sits before σ (decision D6)
//!   because tanhshrink has zero slope at 0 (`d/dx = tanh² x`), so small un-normalised
//!   features would barely learn. Batch normalisation covers the whole block output, the
//!   self-reinforced stream included, and is optional for the "original GAT" ablation rows.
//! - [`DenseGatModule`]: `m` such blocks where block `k` reads the module input concatenated
//!   with every earlier block output, DenseNet style, so that features of every depth reach
//!   the output transform; or, for the "w/o dense connection" ablation, a plain sequence.
//!
//! Concatenation order follows eq. 3.6, newest block first:
//! `v^[l+m] = f(v^[l+m−1]) ‖ … ‖ f(v^[l]) ‖ v^[l]`, so the module input always occupies the
//! last `d_in` columns of the output.

use std::sync::Arc;

use burn::config::Config;
use burn::module::Module;
use burn::nn::{BatchNorm, BatchNormConfig};
use burn::tensor::{Device, Tensor};

use crate::activation::Activation;
use crate::adjacency::Adjacency;
use crate::error::{check_shape, NnError, ANY};
use crate::gat::{GatBlock, GatBlockConfig};

/// Configuration of a [`NormedGat`].
#[derive(Config, Debug)]
pub struct NormedGatConfig {
    /// The GAT block; its `activation` is applied after the normalisation, not inside it.
    pub gat: GatBlockConfig,
    /// Batch normalisation (over the nodes) between the block and σ.
    #[config(default = true)]
    pub batch_norm: bool,
}

/// GAT block → batch normalisation → σ; see the module documentation.
#[derive(Module, Debug)]
pub struct NormedGat {
    /// The GAT block, built without its own σ.
    pub gat: GatBlock,
    /// Normalisation of the block output, or none.
    pub norm: Option<BatchNorm>,
    #[module(skip)]
    pub(crate) activation: Activation,
}

impl NormedGatConfig {
    /// Output features per node (the GAT block's).
    pub fn output_width(&self) -> usize {
        self.gat.output_width()
    }

    /// Builds the layer; errors as [`GatBlockConfig::init`].
    pub fn init(&self, device: &Device) -> crate::Result<NormedGat> {
        let gat = self
            .gat
            .clone()
            .with_activation(Activation::None)
            .init(device)?;
        let norm = self
            .batch_norm
            .then(|| BatchNormConfig::new(gat.output_width()).init(device));
        Ok(NormedGat {
            gat,
            norm,
            activation: self.gat.activation,
        })
    }
}

impl NormedGat {
    /// Input features per node.
    pub fn input_width(&self) -> usize {
        self.gat.input_width()
    }

    /// Output features per node.
    pub fn output_width(&self) -> usize {
        self.gat.output_width()
    }

    /// `x`: `[N, d]` node features on the graph of `adjacency`; returns `[N, output_width]`.
    ///
    /// On an autodiff device the normalisation uses the statistics of these `N` nodes (every
    /// graph of a [`crate::GraphBatch`] together) and updates its running statistics;
    /// otherwise it uses the running statistics.
    pub fn forward(&self, x: Tensor<2>, adjacency: &Arc<Adjacency>) -> crate::Result<Tensor<2>> {
        let mut h = self.gat.forward(x, adjacency)?;
        if let Some(norm) = &self.norm {
            h = norm.forward(h);
        }
        Ok(self.activation.forward(h))
    }
}

/// Configuration of a [`DenseGatModule`]: `m` GAT blocks of equal widths.
#[derive(Config, Debug)]
pub struct DenseGatModuleConfig {
    /// Input features per node `d_in`.
    pub d_input: usize,
    /// Blocks `m` (6 in DenseGATs).
    pub blocks: usize,
    /// Channels per head `F` (8 in DenseGATs, 16 in MultiResGNet).
    pub channels: usize,
    /// Heads `K` (8 in both models).
    #[config(default = 1)]
    pub heads: usize,
    /// β of the self-reinforced stream (0.125 in DenseGATs, 1.0 in MultiResGNet), or none.
    #[config(default = "None")]
    pub self_reinforced: Option<f64>,
    /// σ after every block (tanhshrink in seed 001).
    #[config(default = "Activation::Tanhshrink")]
    pub activation: Activation,
    /// Batch normalisation before every σ.
    #[config(default = true)]
    pub batch_norm: bool,
    /// Dense connections (eq. 3.6); `false` chains the blocks plainly.
    #[config(default = true)]
    pub dense: bool,
}

impl DenseGatModuleConfig {
    /// The block of this module's widths reading `d_input` features: also the transition
    /// block between two dense modules, which the thesis gives "the same parameters".
    pub fn block(&self, d_input: usize) -> NormedGatConfig {
        NormedGatConfig::new(
            GatBlockConfig::new(d_input, self.channels)
                .with_heads(self.heads)
                .with_self_reinforced(self.self_reinforced)
                .with_activation(self.activation),
        )
        .with_batch_norm(self.batch_norm)
    }

    /// Output features per block `d' = K·F + round(β·K·F)`.
    pub fn block_width(&self) -> usize {
        self.block(self.d_input).output_width()
    }

    /// Output features per node: `d_in + m·d'` when dense, else `d'`.
    pub fn output_width(&self) -> usize {
        if self.dense {
            self.d_input + self.blocks * self.block_width()
        } else {
            self.block_width()
        }
    }

    /// Builds the module; errors on no blocks or as [`GatBlockConfig::init`].
    pub fn init(&self, device: &Device) -> crate::Result<DenseGatModule> {
        if self.blocks == 0 {
            return Err(NnError::Config(
                "a dense GAT module needs at least one block".into(),
            ));
        }
        let width = self.block_width();
        let blocks = (0..self.blocks)
            .map(|k| {
                let d = match (self.dense, k) {
                    (_, 0) => self.d_input,
                    (true, _) => self.d_input + k * width,
                    (false, _) => width,
                };
                self.block(d).init(device)
            })
            .collect::<crate::Result<Vec<_>>>()?;
        Ok(DenseGatModule {
            blocks,
            dense: self.dense,
        })
    }
}

/// `m` GAT blocks, densely connected or chained; see the module documentation.
#[derive(Module, Debug)]
pub struct DenseGatModule {
    /// The blocks, in order.
    pub blocks: Vec<NormedGat>,
    #[module(skip)]
    pub(crate) dense: bool,
}

impl DenseGatModule {
    /// Input features per node.
    pub fn input_width(&self) -> usize {
        self.blocks[0].input_width()
    }

    /// Output features per node.
    pub fn output_width(&self) -> usize {
        let last = &self.blocks[self.blocks.len() - 1];
        if self.dense {
            last.input_width() + last.output_width()
        } else {
            last.output_width()
        }
    }

    /// `x`: `[N, d_in]` node features on the graph of `adjacency`; returns
    /// `[N, output_width]`, ordered as eq. 3.6 when dense (newest block first, `x` last).
    pub fn forward(&self, x: Tensor<2>, adjacency: &Arc<Adjacency>) -> crate::Result<Tensor<2>> {
        check_shape(
            "dense GAT module input",
            &[ANY, self.input_width()],
            &x.dims(),
        )?;
        let mut h = x;
        for block in &self.blocks {
            let out = block.forward(h.clone(), adjacency)?;
            h = if self.dense {
                Tensor::cat(vec![out, h], 1)
            } else {
                out
            };
        }
        Ok(h)
    }
}

#[cfg(test)]
mod tests {
    use burn::module::{ModuleMapper, Param};
    use burn::tensor::DType;

    use super::*;
    use crate::backend::{cpu_autodiff, seeded};
    use crate::batch::GraphBatch;
    use crate::testutil::{host, max_diff, random_graph, tensor, Rng};

    /// Casts every float tensor of a module (parameters and running statistics) to f64.
    struct ToF64;

    impl ModuleMapper for ToF64 {
        fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
            param.map(|t| t.cast(DType::F64))
        }
    }

    fn densegats_config() -> DenseGatModuleConfig {
        DenseGatModuleConfig::new(32, 6, 8)
            .with_heads(8)
            .with_self_reinforced(Some(0.125))
    }

    #[test]
    fn densegats_widths_dense_and_plain() {
        let device = cpu_autodiff();
        let mut rng = Rng::new(1);
        let batch = GraphBatch::single(&random_graph(&mut rng, 40, 30));
        let x = tensor(rng.values(40 * 32), [40, 32], &device, DType::F32);
        for (dense, width) in [(true, 32 + 6 * 72), (false, 72)] {
            let config = densegats_config().with_dense(dense);
            assert_eq!(config.block_width(), 72);
            assert_eq!(config.output_width(), width);
            let module = config.init(&device).unwrap();
            assert_eq!((module.input_width(), module.output_width()), (32, width));
            let y = module.forward(x.clone(), batch.adjacency()).unwrap();
            assert_eq!(y.dims(), [40, width]);
        }
        // The transition block of DenseGATs: 464 → 72.
        assert_eq!(densegats_config().block(464).output_width(), 72);
        let module = densegats_config().init(&device).unwrap();
        let wrong = tensor(rng.values(40 * 31), [40, 31], &device, DType::F32);
        assert!(matches!(
            module.forward(wrong, batch.adjacency()),
            Err(NnError::Shape { .. })
        ));
        assert!(DenseGatModuleConfig::new(32, 0, 8).init(&device).is_err());
        assert!(densegats_config().with_heads(0).init(&device).is_err());
    }

    #[test]
    fn dense_output_ends_with_the_module_input() {
        let device = cpu_autodiff();
        let mut rng = Rng::new(2);
        let batch = GraphBatch::single(&random_graph(&mut rng, 25, 20));
        let values = rng.values(25 * 5);
        let x = tensor(values.clone(), [25, 5], &device, DType::F32);
        let module = DenseGatModuleConfig::new(5, 3, 2)
            .with_heads(2)
            .with_self_reinforced(Some(0.5))
            .init(&device)
            .unwrap();
        let y = module.forward(x, batch.adjacency()).unwrap();
        let w = module.output_width();
        assert_eq!(w, 5 + 3 * 6);
        let tail = host(&y.slice([0..25, w - 5..w]));
        assert!(max_diff(&tail, &host(&tensor(values, [25, 5], &device, DType::F32))) == 0.0);
    }

    #[test]
    fn batch_norm_normalises_the_whole_block_output() {
        let mut rng = Rng::new(3);
        let batch = GraphBatch::single(&random_graph(&mut rng, 50, 60));
        let values = rng.values(50 * 4);
        let run = |batch_norm: bool| {
            let device = seeded(&cpu_autodiff(), 9);
            let module = DenseGatModuleConfig::new(4, 1, 3)
                .with_heads(2)
                .with_self_reinforced(Some(0.5))
                .with_activation(Activation::None)
                .with_batch_norm(batch_norm)
                .with_dense(false)
                .init(&device)
                .unwrap();
            let x = tensor(values.clone(), [50, 4], &device, DType::F32);
            let y = module.forward(x, batch.adjacency()).unwrap();
            let mean = host(&y.clone().mean_dim(0));
            let var = host(&y.var_bias(0));
            (mean, var)
        };
        // Every column, the three of the self-reinforced stream included, has zero mean
        // and unit (biased) variance over the nodes.
        let (mean, var) = run(true);
        assert_eq!(mean.len(), 9);
        assert!(mean.iter().all(|m| m.abs() < 1e-5), "{mean:?}");
        assert!(var.iter().all(|v| (v - 1.0).abs() < 1e-3), "{var:?}");
        let (mean, var) = run(false);
        assert!(mean
            .iter()
            .zip(&var)
            .any(|(m, v)| m.abs() > 1e-3 || (v - 1.0).abs() > 1e-2));
    }

    #[test]
    fn gradients_match_central_differences_in_f64() {
        let mut rng = Rng::new(4);
        let (n, d) = (9, 3);
        let batch = GraphBatch::single(&random_graph(&mut rng, n, 6));
        let device = seeded(&cpu_autodiff(), 5);
        let module = DenseGatModuleConfig::new(d, 2, 2)
            .with_heads(2)
            .with_self_reinforced(Some(0.5))
            .init(&device)
            .unwrap()
            .map(&mut ToF64);
        let w = module.output_width();
        let x0 = rng.values(n * d);
        let r = rng.values(n * w);
        let weight0 = host(&module.blocks[1].gat.weight.val());
        let weight_shape = module.blocks[1].gat.weight.dims();
        // Σ out ⊙ R with the second block's transform replaced by `weight`; on the autodiff
        // device, so batch normalisation uses the batch statistics in every evaluation.
        let loss = |x: &[f64], weight: &[f64]| -> (Tensor<2>, Tensor<2>, Tensor<1>) {
            let mut m = module.clone();
            let weight = tensor(weight.to_vec(), weight_shape, &device, DType::F64);
            m.blocks[1].gat.weight = Param::from_tensor(weight.clone());
            let x = tensor(x.to_vec(), [n, d], &device, DType::F64).require_grad();
            let out = m.forward(x.clone(), batch.adjacency()).unwrap();
            let rt = tensor(r.clone(), [n, w], &device, DType::F64);
            (x, m.blocks[1].gat.weight.val(), (out * rt).sum())
        };
        let value = |x: &[f64], weight: &[f64]| host(&loss(x, weight).2.unsqueeze_dim(0))[0];
        let (x, weight, l) = loss(&x0, &weight0);
        assert_eq!(l.dtype(), DType::F64);
        let grads = l.backward();
        let gx = host(&x.grad(&grads).unwrap());
        let gw = host(&weight.grad(&grads).unwrap());
        let eps = 1e-6;
        let central = |perturb: &dyn Fn(f64) -> f64| (perturb(eps) - perturb(-eps)) / (2.0 * eps);
        let nx: Vec<f64> = (0..x0.len())
            .map(|k| {
                central(&|e| {
                    let mut x = x0.clone();
                    x[k] += e;
                    value(&x, &weight0)
                })
            })
            .collect();
        let nw: Vec<f64> = (0..weight0.len())
            .map(|k| {
                central(&|e| {
                    let mut w = weight0.clone();
                    w[k] += e;
                    value(&x0, &w)
                })
            })
            .collect();
        let scale = |g: &[f64]| g.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        assert!(max_diff(&gx, &nx) / scale(&nx) < 1e-6, "input");
        assert!(max_diff(&gw, &nw) / scale(&nw) < 1e-6, "weight");
    }
}
