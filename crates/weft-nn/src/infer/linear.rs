//! The per-channel epilogue (bias, batch normalisation, σ) and the linear layers and MLPs
//! that use it.

use std::ops::Range;

use burn::nn::{BatchNorm, LayerNorm, Linear};
use rayon::prelude::*;

use super::{host, math, matmul, product, Columns, Features, BLOCK};
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

    /// Applies the map to every row of `rows` (a whole number of rows), on this thread.
    fn apply_serial(&self, rows: &mut [f32]) {
        let w = self.width();
        simd(
            #[inline(always)]
            || rows.chunks_exact_mut(w).for_each(|row| self.apply(row)),
        )
    }

    /// Applies the map to every row of `x` (its width), in parallel blocks of rows.
    fn apply_rows(&self, x: &mut Features) {
        let w = x.width;
        x.data
            .par_chunks_mut(BLOCK * w)
            .for_each(|rows| self.apply_serial(rows));
    }
}

/// A linear layer with its [`Epilogue`]: `σ(BN(x W + b))`.
#[derive(Clone, Debug)]
pub struct InferLinear {
    /// `W`, `[d_in, d_out]` row-major.
    pub(super) weight: Vec<f32>,
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
/// biased variance (burn's `layer_norm`). In f32 with sixteen partial sums, so the passes
/// vectorise: HOOD normalises every MLP's output, about 80 M values a step at 4 000
/// vertices.
#[derive(Clone, Debug)]
struct RowNorm {
    gamma: Vec<f32>,
    beta: Vec<f32>,
    epsilon: f32,
}

/// `Σ f(v)` over `row`, in sixteen lanes.
#[inline(always)]
fn lane_sum(row: &[f32], f: impl Fn(f32) -> f32) -> f32 {
    let mut lanes = [0.0f32; 16];
    let mut chunks = row.chunks_exact(16);
    for chunk in &mut chunks {
        for (acc, &v) in lanes.iter_mut().zip(chunk) {
            *acc += f(v);
        }
    }
    chunks.remainder().iter().map(|&v| f(v)).sum::<f32>() + lanes.iter().sum::<f32>()
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
            epsilon: LAYER_NORM_EPSILON as f32,
        }
    }

    /// Normalises every row of `rows` (a whole number of rows), on this thread.
    fn apply_serial(&self, rows: &mut [f32]) {
        let w = self.gamma.len();
        simd(
            #[inline(always)]
            || {
                for row in rows.chunks_exact_mut(w) {
                    let mean = lane_sum(row, |v| v) / w as f32;
                    let var = lane_sum(row, |v| (v - mean) * (v - mean)) / w as f32;
                    let inv = 1.0 / (var + self.epsilon).sqrt();
                    for ((v, g), b) in row.iter_mut().zip(&self.gamma).zip(&self.beta) {
                        *v = (*v - mean) * inv * g + b;
                    }
                }
            },
        )
    }

    fn apply_rows(&self, x: &mut Features) {
        let w = x.width;
        assert_eq!(self.gamma.len(), w, "layer norm of {w} channels");
        x.data
            .par_chunks_mut(BLOCK * w)
            .for_each(|rows| self.apply_serial(rows));
    }
}

/// Rows per chunk of [`InferMlp::map_rows`]: a chunk's activations (256 × 128 f32, 128 KiB
/// at HOOD's width) stay in the core's L2 cache through all the MLP's layers.
const CHUNK: usize = 256;

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

    /// The first layer's weight `W₀`, `[input_width, width₀]` row-major, for callers of
    /// [`Self::map_rows`] that form its product in parts.
    pub(super) fn first_weight(&self) -> &[f32] {
        &self.layers[0].weight
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

    /// The MLP on the rows of `out`, [`CHUNK`] rows at a time in parallel, each chunk
    /// through every layer while it is in cache (one thread's `gemm` per product).
    ///
    /// `first(rows, before, scratch, h)` writes the first layer's product `x W₀` for the
    /// rows `rows` into `h` (`rows.len() × width₀`), without the bias (the epilogue adds
    /// it), from whatever input the caller has: `before` is `out`'s rows before they are
    /// written, `scratch` a buffer it may reuse. The output is written to `out`, or added
    /// to it when `residual` (the graph net's `x' = x + f(…)`).
    pub(super) fn map_rows<F>(&self, out: &mut Features, residual: bool, first: F)
    where
        F: Fn(Range<usize>, &[f32], &mut Vec<f32>, &mut [f32]) + Sync,
    {
        let width = self.output_width();
        assert_eq!(out.width, width, "MLP output of width {width}");
        let widest = self.layers.iter().map(InferLinear::output_width).max();
        let widest = widest.unwrap_or(width);
        out.data
            .par_chunks_mut(CHUNK * width)
            .enumerate()
            .for_each_init(
                || {
                    (
                        vec![0.0; CHUNK * widest],
                        vec![0.0; CHUNK * widest],
                        Vec::new(),
                    )
                },
                |(a, b, scratch), (c, out_rows)| {
                    let m = out_rows.len() / width;
                    let mut d = self.layers[0].output_width();
                    let (mut h, mut next) = (&mut a[..], &mut b[..]);
                    first(c * CHUNK..c * CHUNK + m, out_rows, scratch, &mut h[..m * d]);
                    self.layers[0].epilogue.apply_serial(&mut h[..m * d]);
                    for layer in &self.layers[1..] {
                        let n = layer.output_width();
                        let x = Columns {
                            data: &h[..m * d],
                            stride: d,
                            start: 0,
                            width: d,
                        };
                        let y = &mut next[..m * n];
                        product(y, x, &layer.weight, n, gemm::Parallelism::None);
                        layer.epilogue.apply_serial(y);
                        std::mem::swap(&mut h, &mut next);
                        d = n;
                    }
                    let y = &mut h[..m * width];
                    if let Some(norm) = &self.layer_norm {
                        norm.apply_serial(y);
                    }
                    if residual {
                        out_rows.iter_mut().zip(&*y).for_each(|(o, v)| *o += v);
                    } else {
                        out_rows.copy_from_slice(y);
                    }
                },
            );
    }
}
