//! MultiResGNet (seed 001 §3.3): a multi-resolution graph network that predicts the
//! per-vertex correction from linear blend skinning to a nonlinear deformation,
//! `M = M_coarse + W(G; Ψ)` (eq. 3.1), from translation-invariant node features (the
//! relative skinning descriptor of eq. 3.9 in place of positions).
//!
//! Input transform (64, 32; tanh), then weft-nn's [`MultiResGModule`] on its output `v^[l]`,
//! two branches:
//!
//! - **local**: one dense module of `m` GAT blocks (16 channels × 8 heads plus a
//!   self-reinforced stream of β = 1.0, tanhshrink; eq. 3.6), width `32 + m·256`; `m` is
//!   not given, 6 as thesis-reference M1 recommends;
//! - **global**: edge-contraction pooling (eq. 3.10–3.11, about half the nodes remain),
//!   two GAT blocks in sequence on the pooled graph, unpooling (eq. 3.12), and one more
//!   GAT block on the fine graph, the `f_GATB` of eq. 3.13 (M2).
//!
//! The two are concatenated and the output transform (256, 64; tanh) and a last linear
//! layer give the 3-vector in centimetres (eq. 3.13). Batch normalisation after every
//! layer but the last (D6). Without the global branch (`global = false`) the network is
//! Table 3.4's "single resolution" ablation. The pooling's attention has its own
//! parameters (M3) of the blocks' `F` channels; `score_offset` (M4) is added to its
//! scores, 0 being the thesis' plain division by `α` in eq. 3.12.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Tensor};
use weft_body::Skinning;
use weft_nn::{Activation, GraphBatch, Mlp, MultiResGModule, MultiResGModuleConfig};

use crate::error::ModelError;
use crate::refine::{
    nn_error as nn, output_transform, tanh_mlp, Frame, InputSpec, PositionFeature, RefineNet,
};

mod inference;

pub use inference::MultiResGnetInference;

/// Configuration of [`MultiResGnet`].
#[derive(Config, Debug, PartialEq)]
pub struct MultiResGnetConfig {
    /// Joints of the skeleton `S` (node features are `6 + S` wide).
    #[config(default = 24)]
    pub joints: usize,
    /// What stands in for positions in the node features (§3.3.1: the descriptor).
    #[config(default = "PositionFeature::Descriptor")]
    pub position: PositionFeature,
    /// The frame of the features and corrections (world axes: the thesis; a run whose
    /// config names none is a world-axes run).
    #[config(default = "Frame::World")]
    pub frame: Frame,
    /// The coarse skinning the network corrects: LBS (eq. 3.1, the thesis) or DQS, whose
    /// joints start closer to a volume-keeping truth.
    #[config(default = "Skinning::Lbs")]
    pub coarse: Skinning,
    /// Influences per vertex of the coarse skinning (§3.3.3.1: at most four).
    #[config(default = 4)]
    pub influences: usize,
    /// Widths of the input transform.
    #[config(default = "vec![64, 32]")]
    pub input_widths: Vec<usize>,
    /// GAT blocks `m` of the local branch's dense module (M1).
    #[config(default = 6)]
    pub local_blocks: usize,
    /// Channels per head `F` of every GAT block and of the pooling's attention.
    #[config(default = 16)]
    pub channels: usize,
    /// Heads `K`.
    #[config(default = 8)]
    pub heads: usize,
    /// β of the self-reinforced stream (§3.3.3.2: 128 of 128 channels), or none.
    #[config(default = "Some(1.0)")]
    pub self_reinforced: Option<f64>,
    /// Batch normalisation after every layer but the last.
    #[config(default = true)]
    pub batch_norm: bool,
    /// σ of the GAT blocks.
    #[config(default = "Activation::Tanhshrink")]
    pub activation: Activation,
    /// The global branch (else the "single resolution" ablation of Table 3.4).
    #[config(default = true)]
    pub global: bool,
    /// GAT blocks on the pooled graph (M2; the `f_GATB` after unpooling comes on top).
    #[config(default = 2)]
    pub global_blocks: usize,
    /// Added to the pooling scores `α` (M4): 0 is the thesis, 0.5 PyG's EdgePool.
    #[config(default = 0.0)]
    pub score_offset: f64,
    /// Widths of the output transform's hidden layers (a last linear layer to 3 follows).
    #[config(default = "vec![256, 64]")]
    pub output_widths: Vec<usize>,
}

impl MultiResGnetConfig {
    /// Vertices per training patch (§3.3.3.2: "the surrounding 1024 consecutive
    /// vertices").
    pub const PATCH: usize = 1024;

    /// The preset `name`: `paper` (§3.3.3.2's widths) or `cpu` (the same shape, narrower:
    /// 3 local blocks, 8 channels × 4 heads, output (128, 64)), so a tiny dataset trains
    /// in minutes on two cores Read in the skinning frame: on the tiny set it took the
    /// joints well below LBS where world axes stayed near it (docs/characters.md).
    pub fn preset(name: &str) -> Result<Self, ModelError> {
        match name {
            "paper" => Ok(Self::new()),
            "cpu" => Ok(Self::new()
                .with_frame(Frame::Skinning)
                .with_local_blocks(3)
                .with_channels(8)
                .with_heads(4)
                .with_output_widths(vec![128, 64])),
            other => Err(ModelError::Config(format!(
                "unknown preset `{other}`; expected cpu or paper"
            ))),
        }
    }

    /// Checks the values; errors name the field.
    pub fn validate(&self) -> Result<(), ModelError> {
        let global_blocks = if self.global { self.global_blocks } else { 1 };
        ModelError::check_positive(&[
            ("joints", self.joints),
            ("influences", self.influences),
            ("local_blocks", self.local_blocks),
            ("channels", self.channels),
            ("heads", self.heads),
            ("global_blocks", global_blocks),
        ])?;
        if self.input_widths.is_empty() || self.input_widths.contains(&0) {
            return Err(ModelError::Config(
                "input_widths needs at least one layer and no width may be 0".into(),
            ));
        }
        if self.output_widths.contains(&0) {
            return Err(ModelError::Config(
                "output_widths: no width may be 0".into(),
            ));
        }
        if let Some(b) = self.self_reinforced {
            if !(b.is_finite() && b > 0.0) {
                return Err(ModelError::Config(format!(
                    "self_reinforced = {b}; expected a positive β or none"
                )));
            }
        }
        if !(self.score_offset.is_finite() && self.score_offset >= 0.0) {
            return Err(ModelError::Config(format!(
                "score_offset = {}; expected a finite value ≥ 0",
                self.score_offset
            )));
        }
        Ok(())
    }

    /// The multi-resolution module of this network's widths reading `d_input` features.
    fn multires(&self, d_input: usize) -> MultiResGModuleConfig {
        MultiResGModuleConfig::new(d_input)
            .with_local_blocks(self.local_blocks)
            .with_channels(self.channels)
            .with_heads(self.heads)
            .with_self_reinforced(self.self_reinforced)
            .with_batch_norm(self.batch_norm)
            .with_activation(self.activation)
            .with_global(self.global)
            .with_global_blocks(self.global_blocks)
            .with_score_offset(self.score_offset)
    }

    /// Builds the network.
    pub fn init(&self, device: &Device) -> Result<MultiResGnet, ModelError> {
        self.validate()?;
        let input = tanh_mlp(6 + self.joints, &self.input_widths, self.batch_norm, device)?;
        let multires = self
            .multires(input.output_width())
            .init(device)
            .map_err(nn)?;
        let (hidden, d_head) = output_transform(
            multires.output_width(),
            &self.output_widths,
            self.batch_norm,
            device,
        )?;
        Ok(MultiResGnet {
            input,
            multires,
            hidden,
            head: LinearConfig::new(d_head, 3).init(device),
        })
    }
}

/// The MultiResGNet network; see the module documentation.
#[derive(Module, Debug)]
pub struct MultiResGnet {
    /// Input transform.
    pub input: Mlp,
    /// The local and global branches.
    pub multires: MultiResGModule,
    /// Output transform's hidden layers.
    pub hidden: Option<Mlp>,
    /// The last linear layer to the 3-vector (no normalisation, no σ).
    pub head: Linear,
}

impl RefineNet for MultiResGnet {
    fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> Result<Tensor<2>, ModelError> {
        let v = self.input.forward(x).map_err(nn)?;
        let mut h = self.multires.forward(v, graph).map_err(nn)?;
        if let Some(hidden) = &self.hidden {
            h = hidden.forward(h).map_err(nn)?;
        }
        Ok(self.head.forward(h))
    }
}

impl crate::refine::RefineConfig for MultiResGnetConfig {
    type Net = MultiResGnet;

    fn defaults() -> Self {
        Self::new()
    }

    fn check(&self) -> Result<(), ModelError> {
        self.validate()
    }

    fn build(&self, device: &Device) -> Result<MultiResGnet, ModelError> {
        self.init(device)
    }

    fn inputs(&self) -> InputSpec {
        InputSpec {
            coarse: self.coarse,
            position: self.position,
            frame: self.frame,
        }
    }

    fn influences(&self) -> usize {
        self.influences
    }

    fn joints(&self) -> usize {
        self.joints
    }

    fn inference(&self, net: MultiResGnet) -> Box<dyn RefineNet + Send + Sync> {
        Box::new(net.inference())
    }
}

#[cfg(test)]
mod tests;
