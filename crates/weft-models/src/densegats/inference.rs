//! [`DenseGatsInference`]: DenseGATs as evaluation and animation run it, on weft-nn's
//! inference forms ([`weft_nn::infer`]: batch normalisation and σ fused into each layer's
//! output pass, attention for all heads of a node in one pass, dense modules in one
//! buffer). Same values as [`DenseGats`]' forward on the inference device (to f32
//! rounding; tests below), several times faster (docs/benchmarks.md); training keeps
//! [`DenseGats`].

use burn::tensor::Tensor;
use weft_nn::infer::{Features, InferDenseModule, InferGat, InferLinear, InferMlp};
use weft_nn::{Activation, Adjacency, GraphBatch};

use super::DenseGats;
use crate::error::ModelError;
use crate::refine::{nn_error as nn, RefineNet};

/// DenseGATs for inference; built by [`DenseGats::inference`].
#[derive(Clone, Debug)]
pub struct DenseGatsInference {
    /// Input transform.
    pub input: InferMlp,
    /// Dense modules.
    pub modules: Vec<InferDenseModule>,
    /// Transition blocks between modules.
    pub transitions: Vec<InferGat>,
    /// Output transform's hidden layers.
    pub hidden: Option<InferMlp>,
    /// The last linear layer to the 3-vector.
    pub head: InferLinear,
}

impl DenseGats {
    /// This network's inference form (its parameters and running statistics as they are
    /// now).
    pub fn inference(&self) -> DenseGatsInference {
        DenseGatsInference {
            input: InferMlp::from(&self.input),
            modules: self.modules.iter().map(InferDenseModule::from).collect(),
            transitions: self.transitions.iter().map(InferGat::from).collect(),
            hidden: self.hidden.as_ref().map(InferMlp::from),
            head: InferLinear::new(&self.head, None, Activation::None),
        }
    }
}

impl DenseGatsInference {
    /// Dense module `k` with the transition block before it (none before the first).
    pub fn module(
        &self,
        k: usize,
        h: &Features,
        adjacency: &Adjacency,
    ) -> Result<Features, ModelError> {
        let m = &self.modules[k];
        match k.checked_sub(1).map(|t| &self.transitions[t]) {
            Some(t) => m.forward(&t.forward(h, adjacency).map_err(nn)?, adjacency),
            None => m.forward(h, adjacency),
        }
        .map_err(nn)
    }

    /// The output transform and the last layer.
    pub fn output(&self, h: &Features) -> Result<Features, ModelError> {
        match &self.hidden {
            Some(hidden) => self.head.forward(&hidden.forward(h).map_err(nn)?),
            None => self.head.forward(h),
        }
        .map_err(nn)
    }

    /// Node features `[N, 6 + S]` → corrections `[N, 3]`, as [`DenseGats`]' forward.
    pub fn forward_features(
        &self,
        x: &Features,
        adjacency: &Adjacency,
    ) -> Result<Features, ModelError> {
        let mut h = self.input.forward(x).map_err(nn)?;
        for k in 0..self.modules.len() {
            h = self.module(k, &h, adjacency)?;
        }
        self.output(&h)
    }
}

impl RefineNet for DenseGatsInference {
    fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> Result<Tensor<2>, ModelError> {
        let device = x.device();
        let x = Features::from_tensor(x).map_err(nn)?;
        Ok(self
            .forward_features(&x, graph.adjacency())?
            .into_tensor(&device))
    }
}

#[cfg(test)]
mod tests {
    use burn::module::{Module, ModuleMapper, Param};
    use burn::tensor::Distribution;
    use weft_mesh::primitives;
    use weft_nn::backend::{cpu, seeded};

    use super::*;
    use crate::densegats::DenseGatsConfig;

    /// Draws every vector parameter and running statistic (γ, β, μ, σ², biases) from
    /// U(0.5, 1.5), as a trained network's are, away from their initial 0 and 1.
    struct Statistics;

    impl ModuleMapper for Statistics {
        fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
            if D > 1 {
                return param;
            }
            param.map(|t| Tensor::random(t.shape(), Distribution::Uniform(0.5, 1.5), &t.device()))
        }
    }

    #[test]
    fn inference_equals_the_network_for_presets_and_ablations() {
        let device = seeded(&cpu(), 11);
        // 150 vertices: more than one row block of the inference passes.
        let mesh = primitives::grid(15, 10, 1.0);
        let graph = GraphBatch::single(&mesh.graph());
        let n = mesh.positions.len();
        let x = Tensor::<2>::random([n, 30], Distribution::Uniform(-1.0, 1.0), &device);
        let cpu_preset = DenseGatsConfig::preset("cpu").unwrap();
        for (what, cfg) in [
            ("paper", DenseGatsConfig::new()),
            ("cpu", cpu_preset.clone()),
            ("no batch norm", cpu_preset.clone().with_batch_norm(false)),
            (
                "no self stream",
                cpu_preset.clone().with_self_reinforced(0.0),
            ),
            ("not dense", cpu_preset.clone().with_dense(false)),
            (
                "original GAT",
                DenseGatsConfig::new()
                    .with_modules(1)
                    .with_blocks(4)
                    .with_self_reinforced(0.0)
                    .with_dense(false)
                    .with_activation(Activation::Elu),
            ),
            (
                "no output MLP",
                cpu_preset.clone().with_output_widths(vec![]),
            ),
        ] {
            let net = cfg.init(&device).unwrap().map(&mut Statistics);
            let want = net.forward(x.clone(), &graph).unwrap();
            let got = net.inference().forward(x.clone(), &graph).unwrap();
            let want: Vec<f32> = want.into_data().try_into_vec().unwrap();
            let got: Vec<f32> = got.into_data().try_into_vec().unwrap();
            let scale = want.iter().fold(1e-3f32, |m, v| m.max(v.abs()));
            let diff = got
                .iter()
                .zip(&want)
                .fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
            assert!(diff <= 1e-4 * scale, "{what}: {diff} of {scale}");
        }
    }
}
