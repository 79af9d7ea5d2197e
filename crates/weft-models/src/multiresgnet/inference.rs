//! [`MultiResGnetInference`]: MultiResGNet as evaluation and animation run it, on
//! weft-nn's inference forms ([`weft_nn::infer`]). Same values as [`MultiResGnet`]'s
//! forward on the inference device (to f32 rounding; test below); training keeps
//! [`MultiResGnet`].

use burn::tensor::Tensor;
use weft_nn::infer::{Features, InferLinear, InferMlp, InferMultiRes};
use weft_nn::{Activation, GraphBatch};

use super::MultiResGnet;
use crate::error::ModelError;
use crate::refine::{nn_error as nn, RefineNet};

/// MultiResGNet for inference; built by [`MultiResGnet::inference`].
#[derive(Clone, Debug)]
pub struct MultiResGnetInference {
    /// Input transform.
    pub input: InferMlp,
    /// The local and global branches.
    pub multires: InferMultiRes,
    /// Output transform's hidden layers.
    pub hidden: Option<InferMlp>,
    /// The last linear layer to the 3-vector.
    pub head: InferLinear,
}

impl MultiResGnet {
    /// This network's inference form (its parameters and running statistics as they are
    /// now).
    pub fn inference(&self) -> MultiResGnetInference {
        MultiResGnetInference {
            input: InferMlp::from(&self.input),
            multires: InferMultiRes::from(&self.multires),
            hidden: self.hidden.as_ref().map(InferMlp::from),
            head: InferLinear::new(&self.head, None, Activation::None),
        }
    }
}

impl MultiResGnetInference {
    /// Node features `[N, 6 + S]` → corrections `[N, 3]`, as [`MultiResGnet`]'s forward.
    pub fn forward_features(
        &self,
        x: &Features,
        graph: &GraphBatch,
    ) -> Result<Features, ModelError> {
        let v = self.input.forward(x).map_err(nn)?;
        let h = self.multires.forward(&v, graph).map_err(nn)?;
        match &self.hidden {
            Some(hidden) => self.head.forward(&hidden.forward(&h).map_err(nn)?),
            None => self.head.forward(&h),
        }
        .map_err(nn)
    }
}

impl RefineNet for MultiResGnetInference {
    fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> Result<Tensor<2>, ModelError> {
        let device = x.device();
        let x = Features::from_tensor(x).map_err(nn)?;
        Ok(self.forward_features(&x, graph)?.into_tensor(&device))
    }
}

#[cfg(test)]
mod tests {
    use burn::tensor::Distribution;
    use weft_mesh::primitives;
    use weft_nn::backend::{cpu, seeded};

    use super::*;
    use crate::multiresgnet::MultiResGnetConfig;

    #[test]
    fn inference_equals_the_network_with_and_without_the_global_branch() {
        let device = seeded(&cpu(), 5);
        let mesh = primitives::grid(15, 10, 1.0);
        let graph = GraphBatch::single(&mesh.graph());
        let n = mesh.positions.len();
        for global in [true, false] {
            let net = MultiResGnetConfig::preset("cpu")
                .unwrap()
                .with_global(global)
                .init(&device)
                .unwrap();
            let x = Tensor::<2>::random([n, 30], Distribution::Default, &device);
            let want = net.forward(x.clone(), &graph).unwrap();
            let got = net.inference().forward(x, &graph).unwrap();
            let diff = (want - got).abs().max().into_scalar::<f32>();
            assert!(diff < 1e-4, "global {global}: {diff}");
        }
    }
}
