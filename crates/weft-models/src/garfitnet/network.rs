//! The GarFitNet network (seed 001 §4.3, eq. 4.8–4.12, Fig. 4.5–4.6), with the widths
//! thesis-reference G2/G3 recommends where the thesis's do not add up:
//!
//! 1. the garment graph's node features `[r_i, n_i, x_i]` through two GAT blocks (64
//!    channels × 4 heads plus a self stream of β = 1, tanh), both blocks' outputs
//!    concatenated (2 × 512 = 1 024);
//! 2. the **GarFit parameters** `(β, θ, α)` of each frame through an MLP (85 → 256 → 512,
//!    batch norm and ReLU, then a linear layer to 1 024): the "GarFit correction weight",
//!    multiplied element-wise into every node's graph features of that frame;
//! 3. a **direction branch** and a **length branch**, each a [`MultiResGModule`] (local:
//!    four dense blocks of 32 channels × 2 heads plus a self stream; global: pooling, two
//!    blocks, unpooling, one block) and a feature transform (256, 64): the direction
//!    `δ_i = f_norm(tanh(g_i))` (eq. 4.10), the length `Δ'_i = relu(v_i)` (eq. 4.9), and
//!    the correction `Δ_i = Δ'_i δ_i`, trained by plain MSE on it (eq. 4.8).
//!
//! Frames travel as one disjoint graph ([`GraphBatch`]); each frame's GarFit vector
//! reaches its own nodes through the batch's membership. Training needs several frames
//! per step: batch normalisation of a single frame's GarFit vector centres it to zero
//! (thesis-reference G7).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Tensor};
use weft_nn::{
    Activation, GatBlockConfig, GraphBatch, Mlp, MlpConfig, MultiResGModule, MultiResGModuleConfig,
    NormedGat, NormedGatConfig,
};

use crate::error::ModelError;
use crate::refine::{nn_error as nn, output_transform};

/// Lengths below this make a direction of zero length: `f_norm` divides by at least it.
const MIN_NORM: f64 = 1e-6;

/// Configuration of [`GarFitNet`].
#[derive(Config, Debug, PartialEq)]
pub struct GarFitNetConfig {
    /// Node features per garment vertex: `r_i`, `n_i` and one distance per joint (`6 + S`).
    #[config(default = 30)]
    pub node_features: usize,
    /// GarFit parameters per frame: `|β| + |θ| + |α|` (10 + 72 + 3 for SMPL).
    #[config(default = 85)]
    pub garfit_features: usize,
    /// Channels per head of the two graph-feature GAT blocks.
    #[config(default = 64)]
    pub graph_channels: usize,
    /// Heads of the two graph-feature GAT blocks.
    #[config(default = 4)]
    pub graph_heads: usize,
    /// Hidden widths of the GarFit parameter MLP (its last linear layer matches the graph
    /// features' width).
    #[config(default = "vec![256, 512]")]
    pub garfit_widths: Vec<usize>,
    /// Local dense blocks of each branch's multi-resolution module.
    #[config(default = 4)]
    pub branch_blocks: usize,
    /// Channels per head of the branches' GAT blocks.
    #[config(default = 32)]
    pub branch_channels: usize,
    /// Heads of the branches' GAT blocks.
    #[config(default = 2)]
    pub branch_heads: usize,
    /// Blocks on the pooled graph in each branch.
    #[config(default = 2)]
    pub global_blocks: usize,
    /// Hidden widths of each branch's output transform.
    #[config(default = "vec![256, 64]")]
    pub output_widths: Vec<usize>,
    /// Batch normalisation after every layer but the last.
    #[config(default = true)]
    pub batch_norm: bool,
    /// The GarFit parameter branch (§4.3.3); off: the graph features go to the branches
    /// unweighted (Fig. 4.12's "without GarFit branch").
    #[config(default = true)]
    pub garfit_branch: bool,
    /// The output as a length and a unit direction (§4.3.2); off: the direction branch's
    /// three outputs are the correction itself (Fig. 4.12's "without decomposition").
    #[config(default = true)]
    pub decomposed: bool,
}

impl GarFitNetConfig {
    /// Width of the graph features (both blocks concatenated) and of the GarFit weight.
    pub fn graph_width(&self) -> usize {
        2 * self.block(self.node_features).gat.output_width()
    }

    fn block(&self, d_input: usize) -> NormedGatConfig {
        NormedGatConfig::new(
            GatBlockConfig::new(d_input, self.graph_channels)
                .with_heads(self.graph_heads)
                .with_self_reinforced(Some(1.0))
                .with_activation(Activation::Tanh),
        )
        .with_batch_norm(self.batch_norm)
    }

    fn branch(&self) -> MultiResGModuleConfig {
        MultiResGModuleConfig::new(self.graph_width())
            .with_local_blocks(self.branch_blocks)
            .with_channels(self.branch_channels)
            .with_heads(self.branch_heads)
            .with_batch_norm(self.batch_norm)
            .with_global_blocks(self.global_blocks)
    }

    /// Builds the network; errors name the field.
    pub fn init(&self, device: &Device) -> Result<GarFitNet, ModelError> {
        ModelError::check_positive(&[
            ("node_features", self.node_features),
            ("garfit_features", self.garfit_features),
            ("graph_channels", self.graph_channels),
            ("graph_heads", self.graph_heads),
            ("branch_blocks", self.branch_blocks),
            ("branch_channels", self.branch_channels),
            ("branch_heads", self.branch_heads),
            ("global_blocks", self.global_blocks),
        ])?;
        if self.garfit_widths.is_empty() || self.garfit_widths.contains(&0) {
            return Err(ModelError::Config(
                "garfit_widths needs at least one layer and no width may be 0".into(),
            ));
        }
        let first = self.block(self.node_features).init(device).map_err(nn)?;
        let second = self.block(first.output_width()).init(device).map_err(nn)?;
        let (garfit, weight) = if self.garfit_branch {
            let garfit = MlpConfig::new(self.garfit_features, self.garfit_widths.clone())
                .with_activation(Activation::Relu)
                .with_output_activation(Activation::Relu)
                .with_batch_norm(self.batch_norm)
                .init(device)
                .map_err(nn)?;
            let weight = LinearConfig::new(garfit.output_width(), self.graph_width()).init(device);
            (Some(garfit), Some(weight))
        } else {
            (None, None)
        };
        let branch = |out: usize| -> Result<Branch, ModelError> {
            let multires = self.branch().init(device).map_err(nn)?;
            let (hidden, d_head) = output_transform(
                multires.output_width(),
                &self.output_widths,
                self.batch_norm,
                device,
            )?;
            Ok(Branch {
                multires,
                hidden,
                head: LinearConfig::new(d_head, out).init(device),
            })
        };
        let length = if self.decomposed {
            let mut length = branch(1)?;
            length.head = positive_bias(length.head);
            Some(length)
        } else {
            None
        };
        Ok(GarFitNet {
            blocks: vec![first, second],
            garfit,
            weight,
            direction: branch(3)?,
            length,
        })
    }
}

/// One output branch: a multi-resolution module and its feature transform.
#[derive(Module, Debug)]
pub struct Branch {
    /// The local and global branches.
    pub multires: MultiResGModule,
    /// The feature transform's hidden layers.
    pub hidden: Option<Mlp>,
    /// The last linear layer (3 for the direction, 1 for the length).
    pub head: Linear,
}

impl Branch {
    fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> Result<Tensor<2>, ModelError> {
        let mut h = self.multires.forward(x, graph).map_err(nn)?;
        if let Some(hidden) = &self.hidden {
            h = hidden.forward(h).map_err(nn)?;
        }
        Ok(self.head.forward(h))
    }
}

/// GarFitNet's output for every node of a batch.
#[derive(Clone, Debug)]
pub struct Correction {
    /// Unit directions `δ`, `[N, 3]`.
    pub direction: Tensor<2>,
    /// Lengths `Δ' ≥ 0`, `[N, 1]`.
    pub length: Tensor<2>,
}

impl Correction {
    /// The decomposed output of two heads (§4.3.2): `δ = f_norm(tanh(g))` (eq. 4.10) from
    /// the direction head's `[N, 3]`, `Δ' = relu(v)` (eq. 4.9) from the length head's
    /// `[N, 1]`.
    pub fn from_heads(g: Tensor<2>, v: Tensor<2>) -> Self {
        let g = g.tanh();
        let norm = g
            .clone()
            .powi_scalar(2)
            .sum_dim(1)
            .sqrt()
            .clamp_min(MIN_NORM);
        Correction {
            direction: g / norm,
            length: burn::tensor::activation::relu(v),
        }
    }

    /// An undecomposed correction `v` (`[N, 3]`) in the same form: `Δ' = ‖v‖`, `δ = v / ‖v‖`,
    /// so [`Correction::vector`] gives `v` back (the ablation without decomposition).
    pub fn direct(v: Tensor<2>) -> Self {
        // The small constant keeps the square root's gradient finite at v = 0.
        let length = (v.clone().powi_scalar(2).sum_dim(1) + MIN_NORM * MIN_NORM).sqrt();
        Correction {
            direction: v / length.clone(),
            length,
        }
    }

    /// The correction `Δ = Δ' δ`, `[N, 3]`.
    pub fn vector(&self) -> Tensor<2> {
        self.direction.clone() * self.length.clone()
    }

    /// Eq. 4.8: the mean over nodes of the squared distance between `Δ` and `target`.
    pub fn loss(&self, target: Tensor<2>) -> Tensor<1> {
        let n = target.dims()[0].max(1) as f64;
        (self.vector() - target).powi_scalar(2).sum().div_scalar(n)
    }
}

/// The GarFitNet network; see the module documentation.
#[derive(Module, Debug)]
pub struct GarFitNet {
    /// The two graph-feature GAT blocks.
    pub blocks: Vec<NormedGat>,
    /// The GarFit parameter MLP's hidden layers (none without the GarFit branch).
    pub garfit: Option<Mlp>,
    /// Its last layer: the GarFit correction weight.
    pub weight: Option<Linear>,
    /// The direction branch.
    pub direction: Branch,
    /// The length branch (none without decomposition).
    pub length: Option<Branch>,
}

impl GarFitNet {
    /// `x`: normalised node features `[N, node_features]` of the frames in `graph`;
    /// `garfit`: each frame's `(β, θ, α)`, `[frames, garfit_features]`, in the batch's
    /// graph order.
    pub fn forward(
        &self,
        x: Tensor<2>,
        garfit_rows: Tensor<2>,
        graph: &GraphBatch,
    ) -> Result<Correction, ModelError> {
        let frames = garfit_rows.dims()[0];
        if frames != graph.graph_count() {
            return Err(ModelError::mismatch(
                "GarFit parameter rows (one per frame)",
                graph.graph_count(),
                frames,
            ));
        }
        let adjacency = graph.adjacency();
        let a = self.blocks[0].forward(x, adjacency).map_err(nn)?;
        let b = self.blocks[1].forward(a.clone(), adjacency).map_err(nn)?;
        let features = Tensor::cat(vec![a, b], 1);
        let h = match (&self.garfit, &self.weight) {
            (Some(garfit), Some(weight)) => {
                let w = weight.forward(garfit.forward(garfit_rows).map_err(nn)?);
                let membership = graph.membership_tensor(&features.device());
                features * w.select(0, membership)
            }
            _ => features,
        };
        let g = self.direction.forward(h.clone(), graph)?;
        Ok(match &self.length {
            Some(length) => Correction::from_heads(g, length.forward(h, graph)?),
            None => Correction::direct(g),
        })
    }
}

/// `linear` with its bias set to one: the length head starts at lengths of about one
/// unit, so the ReLU of eq. 4.9 passes gradients from the first step (G8) instead of
/// cutting a whole frame to zero.
pub(crate) fn positive_bias(mut linear: Linear) -> Linear {
    if let Some(bias) = linear.bias.take() {
        linear.bias = Some(bias.map(|b| b.ones_like()));
    }
    linear
}

#[cfg(test)]
mod tests {
    use burn::tensor::Distribution;
    use weft_mesh::primitives::grid;
    use weft_nn::backend::{cpu, cpu_autodiff};

    use super::*;

    /// Narrow widths, so the tests run in a blink.
    fn small() -> GarFitNetConfig {
        GarFitNetConfig::new()
            .with_graph_channels(4)
            .with_graph_heads(2)
            .with_garfit_widths(vec![8, 16])
            .with_branch_blocks(2)
            .with_branch_channels(4)
            .with_output_widths(vec![16])
    }

    #[test]
    fn the_thesis_widths_add_up() {
        let cfg = GarFitNetConfig::new();
        // Two blocks of 64 × 4 + a self stream of 256: 512 each, 1 024 concatenated.
        assert_eq!(cfg.graph_width(), 1024);
        let net = cfg.init(&cpu()).unwrap();
        assert_eq!(net.weight.as_ref().unwrap().weight.dims(), [512, 1024]);
        // Local: 1 024 + 4 × 128; global: 128.
        assert_eq!(net.direction.multires.output_width(), 1024 + 5 * 128);
        assert!(GarFitNetConfig::new()
            .with_branch_heads(0)
            .init(&cpu())
            .is_err());
    }

    #[test]
    fn directions_are_unit_lengths_non_negative_and_each_frame_reads_its_own_fit() {
        let device = cpu();
        let net = small().init(&device).unwrap();
        let mesh = grid(6, 5, 1.0);
        let g = mesh.graph();
        let graph = GraphBatch::new(&[&g, &g]).unwrap();
        let n = graph.node_count();
        let x = Tensor::<2>::random([30, 30], Distribution::Default, &device);
        let x = Tensor::cat(vec![x.clone(), x], 0);
        let garfit = Tensor::<2>::random([2, 85], Distribution::Default, &device);
        let out = net.forward(x.clone(), garfit.clone(), &graph).unwrap();
        assert_eq!(out.direction.dims(), [n, 3]);
        assert_eq!(out.length.dims(), [n, 1]);
        let norms = out.direction.clone().powi_scalar(2).sum_dim(1).sqrt();
        let off = (norms - 1.0).abs().max().into_scalar::<f32>();
        assert!(off < 1e-5, "{off}");
        assert!(out.length.clone().min().into_scalar::<f32>() >= 0.0);
        // The same graph and node features, another fit: the two frames differ (in the
        // direction: with initial parameters the lengths may all be cut to 0 by the ReLU,
        // thesis-reference G8).
        let first = out.direction.clone().slice([0..30, 0..3]);
        let second = out.direction.clone().slice([30..60, 0..3]);
        assert!(first.sub(second).abs().max().into_scalar::<f32>() > 1e-6);
        // One fit row per frame, or an error naming it.
        let one = garfit.slice([0..1, 0..85]);
        let e = net.forward(x, one, &graph).unwrap_err().to_string();
        assert!(e.contains("GarFit"), "{e}");
    }

    #[test]
    fn the_loss_trains() {
        let device = cpu_autodiff();
        let net = small().init(&device).unwrap();
        // Lengths start positive, so that the ReLU passes gradients (G8).
        let bias = net
            .length
            .as_ref()
            .unwrap()
            .head
            .bias
            .as_ref()
            .expect("a bias");
        assert_eq!(bias.val().min().into_scalar::<f32>(), 1.0);
        // Two frames: batch normalisation of one frame's GarFit vector would centre it to
        // zero (thesis-reference G7), and the weight would get no gradient.
        let g = grid(5, 4, 1.0).graph();
        let graph = GraphBatch::new(&[&g, &g]).unwrap();
        let x = Tensor::<2>::random([40, 30], Distribution::Default, &device);
        let garfit = Tensor::<2>::random([2, 85], Distribution::Default, &device);
        let target = Tensor::<2>::random([40, 3], Distribution::Default, &device);
        let out = net.forward(x, garfit, &graph).unwrap();
        let loss = out.loss(target.clone());
        let expected = (out.vector() - target)
            .powi_scalar(2)
            .sum()
            .div_scalar(40.0);
        assert!((loss.clone().into_scalar::<f32>() - expected.into_scalar::<f32>()).abs() < 1e-6);
        let grads = loss.backward();
        let g = net
            .weight
            .as_ref()
            .unwrap()
            .weight
            .grad(&grads)
            .expect("the GarFit weight gets a gradient");
        assert!(g.abs().max().into_scalar::<f32>() > 0.0);
    }
}
