//! The GAT block: linear transform, multi-head masked attention, heads concatenated or
//! averaged, optional self-reinforced stream, activation.
//!
//! - Seed 000 eq. 4: `x'_i = σ((1/K) Σ_k Σ_{j∈N_i} α^k_ij H^k x_j)` — heads averaged
//!   ([`HeadMerge::Mean`], the final blend-shape GAT of M^mp) or concatenated
//!   ([`HeadMerge::Concat`], every other block).
//! - Seed 001 eq. 3.3–3.5: `v'_i = σ(‖_k Σ_j α^k_ij W^k v_j ‖ c_i)` with the
//!   self-reinforced stream `c_i = H v_i`, `H ∈ R^{βKF×d}`, β = 0.125 and σ = tanhshrink
//!   in DenseGATs: the stream keeps a node's own features, which plain aggregation
//!   dilutes.
//!
//! Initialisation: Glorot (Xavier uniform) for the transform, the attention vectors and the
//! self-reinforced stream, as seed 000 supplement §4 prescribes for GAT blocks; zero bias.

use std::sync::Arc;

use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::{Device, Tensor};

use super::{attention, AttentionImpl, DEFAULT_NEGATIVE_SLOPE};
use crate::activation::Activation;
use crate::adjacency::Adjacency;
use crate::error::{check_shape, NnError, ANY};

/// How the heads of one block are combined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HeadMerge {
    /// `‖_k`: output width `K·F`.
    #[default]
    Concat,
    /// `(1/K) Σ_k`: output width `F`.
    Mean,
}

/// Configuration of a [`GatBlock`].
#[derive(Config, Debug)]
pub struct GatBlockConfig {
    /// Input features per node `d`.
    pub d_input: usize,
    /// Channels per head `F`.
    pub channels: usize,
    /// Heads `K`.
    #[config(default = 1)]
    pub heads: usize,
    /// Head combination.
    #[config(default = "HeadMerge::Concat")]
    pub merge: HeadMerge,
    /// σ after the block.
    #[config(default = "Activation::None")]
    pub activation: Activation,
    /// β of the self-reinforced stream (seed 001 eq. 3.3; 0.125 in DenseGATs), or none.
    #[config(default = "None")]
    pub self_reinforced: Option<f64>,
    /// LeakyReLU slope of the attention logits.
    #[config(default = "DEFAULT_NEGATIVE_SLOPE")]
    pub negative_slope: f64,
    /// Whether the aggregation stream has a bias.
    #[config(default = true)]
    pub bias: bool,
    /// Fused kernel or generic path.
    #[config(default = "AttentionImpl::Auto")]
    pub implementation: AttentionImpl,
}

/// One GAT block; see the module documentation.
#[derive(Module, Debug)]
pub struct GatBlock {
    /// `W` (all heads side by side): `[d, K·F]`.
    pub weight: Param<Tensor<2>>,
    /// Source half of the attention vectors: `[K, F]`.
    pub att_src: Param<Tensor<2>>,
    /// Destination half of the attention vectors: `[K, F]`.
    pub att_dst: Param<Tensor<2>>,
    /// Bias of the aggregation stream (after merging heads).
    pub bias: Option<Param<Tensor<1>>>,
    /// The self-reinforced stream `H` (no bias, eq. 3.3).
    pub self_stream: Option<Linear>,
    /// Heads `K`.
    pub heads: usize,
    /// Channels per head `F`.
    pub channels: usize,
    /// Whether heads are averaged (else concatenated).
    pub mean_heads: bool,
    /// LeakyReLU slope of the logits.
    pub negative_slope: f64,
    #[module(skip)]
    activation: Activation,
    #[module(skip)]
    implementation: AttentionImpl,
}

/// Glorot (Xavier) uniform with the given fans.
pub(crate) fn glorot<const D: usize>(
    shape: [usize; D],
    fan_in: usize,
    fan_out: usize,
    device: &Device,
) -> Param<Tensor<D>> {
    crate::init::glorot().init_with(shape, Some(fan_in), Some(fan_out), device)
}

impl GatBlockConfig {
    /// Width of the attention stream after merging heads.
    fn aggregation_width(&self) -> usize {
        match self.merge {
            HeadMerge::Concat => self.heads * self.channels,
            HeadMerge::Mean => self.channels,
        }
    }

    /// Width of the self-reinforced stream: `round(β · aggregation width)`, at least 1.
    fn self_width(&self) -> Option<usize> {
        self.self_reinforced
            .map(|beta| ((beta * self.aggregation_width() as f64).round() as usize).max(1))
    }

    /// Output features per node.
    pub fn output_width(&self) -> usize {
        self.aggregation_width() + self.self_width().unwrap_or(0)
    }

    /// Builds the block; errors on zero sizes or a non-positive β.
    pub fn init(&self, device: &Device) -> crate::Result<GatBlock> {
        if self.d_input == 0 || self.channels == 0 || self.heads == 0 {
            return Err(NnError::Config(format!(
                "GAT block needs d_input, channels and heads > 0, got {}, {}, {}",
                self.d_input, self.channels, self.heads
            )));
        }
        if let Some(beta) = self.self_reinforced {
            if !(beta > 0.0 && beta.is_finite()) {
                return Err(NnError::Config(format!(
                    "self-reinforced β must be positive, got {beta}"
                )));
            }
        }
        let (k, f) = (self.heads, self.channels);
        let self_stream = self.self_width().map(|width| {
            LinearConfig::new(self.d_input, width)
                .with_bias(false)
                .with_initializer(crate::init::glorot())
                .init(device)
        });
        Ok(GatBlock {
            weight: glorot([self.d_input, k * f], self.d_input, k * f, device),
            att_src: glorot([k, f], k, f, device),
            att_dst: glorot([k, f], k, f, device),
            bias: self
                .bias
                .then(|| Initializer::Zeros.init([self.aggregation_width()], device)),
            self_stream,
            heads: k,
            channels: f,
            mean_heads: self.merge == HeadMerge::Mean,
            negative_slope: self.negative_slope,
            activation: self.activation,
            implementation: self.implementation,
        })
    }
}

impl GatBlock {
    /// Input features per node.
    pub fn input_width(&self) -> usize {
        self.weight.shape().dims::<2>()[0]
    }

    /// Output features per node.
    pub fn output_width(&self) -> usize {
        let agg = if self.mean_heads {
            self.channels
        } else {
            self.heads * self.channels
        };
        agg + self
            .self_stream
            .as_ref()
            .map_or(0, |l| l.weight.shape().dims::<2>()[1])
    }

    /// Switches between the fused kernel and the generic path (for tests and benchmarks).
    pub fn with_implementation(mut self, implementation: AttentionImpl) -> Self {
        self.implementation = implementation;
        self
    }

    /// `x`: `[N, d]` node features on the graph of `adjacency`; returns `[N, output_width]`.
    pub fn forward(&self, x: Tensor<2>, adjacency: &Arc<Adjacency>) -> crate::Result<Tensor<2>> {
        check_shape("GAT block input", &[ANY, self.input_width()], &x.dims())?;
        let n = x.dims()[0];
        let z = x.clone().matmul(self.weight.val());
        let att = attention(
            z,
            self.att_src.val(),
            self.att_dst.val(),
            adjacency,
            self.negative_slope,
            self.implementation,
        )?;
        let mut agg = if self.mean_heads {
            att.reshape([n, self.heads, self.channels])
                .mean_dim(1)
                .reshape([n, self.channels])
        } else {
            att
        };
        if let Some(bias) = &self.bias {
            agg = agg + bias.val().unsqueeze_dim(0);
        }
        let out = match &self.self_stream {
            Some(stream) => Tensor::cat(vec![agg, stream.forward(x)], 1),
            None => agg,
        };
        Ok(self.activation.forward(out))
    }
}
