//! Node-wise nonlinearities the papers name, as one serialisable enum so that configs
//! (TOML) can choose them; [`tanh`] fused on flex.

mod tanh;

use burn::tensor::activation;
use burn::tensor::Tensor;

pub use tanh::tanh;

/// A nonlinearity σ applied after a layer.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Activation {
    /// Identity.
    #[default]
    None,
    /// `max(x, 0)`: the encoders of seed 000 (supplement §1).
    Relu,
    /// `tanh x`: the M^mp GAT blocks of seed 000 (supplement §1).
    Tanh,
    /// `x − tanh x`: the GAT blocks of seed 001 (eq. 3.5), which keeps the sign of
    /// displacements and, unlike tanh, does not saturate.
    Tanhshrink,
    /// LeakyReLU with the given negative slope.
    LeakyRelu(f64),
    /// ELU (α = 1), as in the original GAT.
    Elu,
    /// Logistic sigmoid.
    Sigmoid,
}

impl Activation {
    /// Applies σ element-wise.
    pub fn forward<const D: usize>(self, x: Tensor<D>) -> Tensor<D> {
        match self {
            Activation::None => x,
            Activation::Relu => activation::relu(x),
            Activation::Tanh => tanh(x),
            Activation::Tanhshrink => x.clone() - tanh(x),
            Activation::LeakyRelu(slope) => activation::leaky_relu(x, slope),
            Activation::Elu => {
                // elu(x) = max(x, 0) + exp(min(x, 0)) − 1; the clamp before exp keeps the
                // gradient finite for large x.
                activation::relu(x.clone()) + x.clamp_max(0.0).exp() - 1.0
            }
            Activation::Sigmoid => activation::sigmoid(x),
        }
    }
}
