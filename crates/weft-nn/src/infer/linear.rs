//! The per-channel epilogue (bias, batch normalisation, σ) and the linear layers and MLPs
//! that use it.

use burn::nn::{BatchNorm, LayerNorm, Linear};
use rayon::prelude::*;

use super::{host, math, matmul, Columns, Features, BLOCK};
use crate::activation::Activation;
use crate::mlp::{Mlp, LAYER_NORM_EPSILON};
use crate::real::simd;

/// `σ(x · scale + shift)` per channel: a layer's bias `b` and its batch normalisation at
/// inference, `γ (x + b − μ) / √(v + ε) + β`, as one affine map, then σ.
///
/// The scale is applied to the layer's output rather than folded into its weights: a
/// GAT block's attention scores read the unscaled `z = W x`, so folding would need the
/// attention vectors divided by a scale that may be zero. Applied in the pass that writes
/// the output it costs one multiply-add per value either way.
#[derive(Clone, Debug)]
pub struct Epilogue {
    scale: Vec<f32>,
    shift: Vec<f32>,
    activation: Activation,
}

impl Epilogue {
    /// From the bias (`width` values, or none), the normalisation (or none) and σ.
    pub(crate) fn new(
        width: usize,
        bias: Option<Vec<f32>>,
        norm: Option<&BatchNorm>,
        activation: Activation,
    ) -> Self {
        let bias = bias.unwrap_or_else(|| vec![0.0; width]);
        assert_eq!(bias.len(), width, "bias of {width} channels");
        let (scale, shift) = match norm {
            None => (vec![1.0; width], bias),
            Some(norm) => {
                let gamma = host(norm.gamma.val());
                let beta = host(norm.beta.val());
                let mean = host(norm.running_mean.value());
                let var = host(norm.running_var.value());
                assert_eq!(gamma.len(), width, "batch norm of {width} channels");
                (0..width)
                    .map(|c| {
                        let s = f64::from(gamma[c]) / (f64::from(var[c]) + norm.epsilon).sqrt();
                        let t = (f64::from(bias[c]) - f64::from(mean[c])) * s + f64::from(beta[c]);
                        (s as f32, t as f32)
                    })
                    .unzip()
            }
        };
        Epilogue {
            scale,
            shift,
            activation,
        }
    }

    /// Channels.
    pub fn width(&self) -> usize {
        self.scale.len()
    }

    /// Applies the map to one row of [`Self::width`] values, in place.
    #[inline(always)]
    pub(crate) fn apply(&self, row: &mut [f32]) {
        for ((v, s), t) in row.iter_mut().zip(&self.scale).zip(&self.shift) {
            *v = *v * s + t;
        }
        math::activate(self.activation, row);
    }

    /// Applies the map to every row of `x` (its width), in parallel blocks of rows.
    fn apply_rows(&self, x: &mut Features) {
        let w = x.width;
        x.data.par_chunks_mut(BLOCK * w).for_each(|rows| {
            simd(
                #[inline(always)]
                || rows.chunks_exact_mut(w).for_each(|row| self.apply(row)),
            )
        });
    }
}

/// A linear layer with its [`Epilogue`]: `σ(BN(x W + b))`.
#[derive(Clone, Debug)]
pub struct InferLinear {
    /// `W`, `[d_in, d_out]` row-major.
    weight: Vec<f32>,
    d_input: usize,
    epilogue: Epilogue,
}

impl InferLinear {
    /// `linear`, then `norm` (running statistics) and σ.
    pub fn new(linear: &Linear, norm: Option<&BatchNorm>, activation: Activation) -> Self {
        let [d_input, d_output] = linear.weight.dims();
        let bias = linear.bias.as_ref().map(|b| host(b.val()));
        InferLinear {
            weight: host(linear.weight.val()),
            d_input,
            epilogue: Epilogue::new(d_output, bias, norm, activation),
        }
    }

    /// Input width.
    pub fn input_width(&self) -> usize {
        self.d_input
    }

    /// Output width.
    pub fn output_width(&self) -> usize {
        self.epilogue.width()
    }

    /// `x`: `[N, input_width]` → `[N, output_width]`.
    pub fn forward(&self, x: &Features) -> crate::Result<Features> {
        x.check_width("linear layer input", self.d_input)?;
        Ok(self.forward_columns(x.columns(0..x.width)))
    }

    fn forward_columns(&self, x: Columns<'_>) -> Features {
        let mut y = matmul(x, &self.weight, self.output_width());
        self.epilogue.apply_rows(&mut y);
        y
    }
}

/// Layer normalisation of each row, `γ (x − μ) / √(σ² + ε) + β` with the row's mean and
/// biased variance (burn's `layer_norm`), computed in f64 per row.
#[derive(Clone, Debug)]
struct RowNorm {
    gamma: Vec<f32>,
    beta: Vec<f32>,
    epsilon: f64,
}

impl RowNorm {
    fn new(norm: &LayerNorm) -> Self {
        let gamma = host(norm.gamma.val());
        let beta = norm
            .beta
            .as_ref()
            .map_or_else(|| vec![0.0; gamma.len()], |b| host(b.val()));
        RowNorm {
            gamma,
            beta,
            epsilon: LAYER_NORM_EPSILON,
        }
    }

    fn apply_rows(&self, x: &mut Features) {
        let w = x.width;
        assert_eq!(self.gamma.len(), w, "layer norm of {w} channels");
        x.data.par_chunks_mut(BLOCK * w).for_each(|rows| {
            for row in rows.chunks_exact_mut(w) {
                let mean = row.iter().map(|&v| f64::from(v)).sum::<f64>() / w as f64;
                let var = row
                    .iter()
                    .map(|&v| (f64::from(v) - mean).powi(2))
                    .sum::<f64>()
                    / w as f64;
                let inv = 1.0 / (var + self.epsilon).sqrt();
                for ((v, g), b) in row.iter_mut().zip(&self.gamma).zip(&self.beta) {
                    *v = ((f64::from(*v) - mean) * inv) as f32 * g + b;
                }
            }
        });
    }
}

/// An [`Mlp`] as [`InferLinear`] layers, then its output layer normalisation, if any.
#[derive(Clone, Debug)]
pub struct InferMlp {
    layers: Vec<InferLinear>,
    layer_norm: Option<RowNorm>,
}

impl From<&Mlp> for InferMlp {
    fn from(mlp: &Mlp) -> Self {
        let last = mlp.layers.len() - 1;
        let layers = mlp
            .layers
            .iter()
            .enumerate()
            .map(|(k, layer)| {
                let activation = if k == last {
                    mlp.output_activation
                } else {
                    mlp.activation
                };
                InferLinear::new(layer, mlp.norms.get(k), activation)
            })
            .collect();
        InferMlp {
            layers,
            layer_norm: mlp.layer_norm.as_ref().map(RowNorm::new),
        }
    }
}

impl InferMlp {
    /// Input width.
    pub fn input_width(&self) -> usize {
        self.layers[0].input_width()
    }

    /// Output width.
    pub fn output_width(&self) -> usize {
        self.layers[self.layers.len() - 1].output_width()
    }

    /// `x`: `[N, input_width]` → `[N, output_width]`, as [`Mlp::forward`].
    pub fn forward(&self, x: &Features) -> crate::Result<Features> {
        x.check_width("MLP input", self.input_width())?;
        let mut h = self.layers[0].forward_columns(x.columns(0..x.width));
        for layer in &self.layers[1..] {
            h = layer.forward_columns(h.columns(0..h.width));
        }
        if let Some(norm) = &self.layer_norm {
            norm.apply_rows(&mut h);
        }
        Ok(h)
    }
}
