//! Multilayer perceptrons: the garment-style and body-shape encoders of seed 000
//! (supplement §1: linear layers [256, 256, 128] and [512, 256, 128] with ReLU) and the
//! feature transformation modules of seed 001 (§3.2–3.3: tanh, with 1-D batch
//! normalisation after every layer).
//!
//! Kaiming-initialised ([`crate::init::kaiming`]).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{BatchNorm, BatchNormConfig, Linear, LinearConfig};
use burn::tensor::{Device, Tensor};

use crate::activation::Activation;
use crate::error::{check_shape, NnError, ANY};
use crate::init::kaiming;

/// Configuration of an [`Mlp`].
#[derive(Config, Debug)]
pub struct MlpConfig {
    /// Input width.
    pub d_input: usize,
    /// Output width of every layer, in order (the last is the MLP's output).
    pub widths: Vec<usize>,
    /// σ after every hidden layer.
    #[config(default = "Activation::Relu")]
    pub activation: Activation,
    /// σ after the last layer.
    #[config(default = "Activation::Relu")]
    pub output_activation: Activation,
    /// Batch normalisation (over the rows) after every layer, before σ.
    #[config(default = false)]
    pub batch_norm: bool,
}

/// A stack of linear layers; see the module documentation.
#[derive(Module, Debug)]
pub struct Mlp {
    /// The layers.
    pub layers: Vec<Linear>,
    /// One batch normalisation per layer, or none.
    pub norms: Vec<BatchNorm>,
    #[module(skip)]
    pub(crate) activation: Activation,
    #[module(skip)]
    pub(crate) output_activation: Activation,
}

impl MlpConfig {
    /// Builds the MLP; errors on no layers or a zero width.
    pub fn init(&self, device: &Device) -> crate::Result<Mlp> {
        if self.widths.is_empty() || self.d_input == 0 || self.widths.contains(&0) {
            return Err(NnError::Config(format!(
                "an MLP needs a positive input width and at least one positive layer width, got {} → {:?}",
                self.d_input, self.widths
            )));
        }
        let mut layers = Vec::with_capacity(self.widths.len());
        let mut norms = Vec::new();
        let mut d = self.d_input;
        for &w in &self.widths {
            layers.push(
                LinearConfig::new(d, w)
                    .with_initializer(kaiming())
                    .init(device),
            );
            if self.batch_norm {
                norms.push(BatchNormConfig::new(w).init(device));
            }
            d = w;
        }
        Ok(Mlp {
            layers,
            norms,
            activation: self.activation,
            output_activation: self.output_activation,
        })
    }
}

impl Mlp {
    /// Input width.
    pub fn input_width(&self) -> usize {
        self.layers
            .first()
            .map_or(0, |l| l.weight.shape().dims::<2>()[0])
    }

    /// Output width.
    pub fn output_width(&self) -> usize {
        self.layers
            .last()
            .map_or(0, |l| l.weight.shape().dims::<2>()[1])
    }

    /// `x`: `[B, d_input]` → `[B, widths.last]`.
    pub fn forward(&self, x: Tensor<2>) -> crate::Result<Tensor<2>> {
        check_shape("MLP input", &[ANY, self.input_width()], &x.dims())?;
        let last = self.layers.len() - 1;
        let mut h = x;
        for (k, layer) in self.layers.iter().enumerate() {
            h = layer.forward(h);
            if let Some(norm) = self.norms.get(k) {
                h = norm.forward(h);
            }
            h = if k == last {
                self.output_activation.forward(h)
            } else {
                self.activation.forward(h)
            };
        }
        Ok(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::cpu_autodiff;

    #[test]
    fn widths_batch_norm_and_errors() {
        let device = cpu_autodiff();
        let mlp = MlpConfig::new(6, vec![16, 8, 4])
            .with_batch_norm(true)
            .with_activation(Activation::Tanh)
            .with_output_activation(Activation::None)
            .init(&device)
            .unwrap();
        assert_eq!((mlp.input_width(), mlp.output_width()), (6, 4));
        let y = mlp.forward(Tensor::<2>::ones([5, 6], &device)).unwrap();
        assert_eq!(y.dims(), [5, 4]);
        assert!(mlp.forward(Tensor::<2>::ones([5, 7], &device)).is_err());
        assert!(MlpConfig::new(6, vec![]).init(&device).is_err());
        assert!(MlpConfig::new(6, vec![3, 0]).init(&device).is_err());
    }
}
