//! The coarse regressor (seed 001 §4.2.2, eq. 4.5–4.6): the garment moved with the body.
//!
//! Each garment vertex is associated with its nearest body vertex in the rest pose (the
//! indicator `I` of eq. 4.3, thesis-reference G5); the graph `G_b'` has one node per
//! garment vertex, placed on its body vertex, with the garment's edges. Node features
//! `[r_b'(θ), n_b', α]`; four GAT blocks (64 channels × 4 heads plus a self stream,
//! tanh) and the decomposed head of §4.3.2 (a unit direction and a non-negative length)
//! give `Δ_coarse`, and `M_coarse = M_b' + Δ_coarse`. It is trained on Laplacian-smoothed
//! simulated garments ([`coarse_target`]): the fit without the folds, which GarFitNet
//! adds after.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Tensor};
use weft_body::query::VertexTree;
use weft_mesh::TriMesh;
use weft_nn::{Activation, GatBlockConfig, GraphBatch, Mlp, NormedGat, NormedGatConfig};

use super::network::{positive_bias, Correction};
use crate::error::ModelError;
use crate::refine::{nn_error as nn, output_transform};

/// A garment vertex farther than this from every body vertex (rest pose, m) means the
/// garment is not dressed on this body: its association would be meaningless.
pub const MAX_ASSOCIATION_DISTANCE: f64 = 0.5;

/// For every garment vertex (rest pose), its nearest body vertex (rest pose, the body the
/// garment sits on). Errors: a non-finite garment vertex, or one farther than
/// [`MAX_ASSOCIATION_DISTANCE`] from the body (a garment with no body region under it).
pub fn association(body: &[[f64; 3]], garment: &[[f64; 3]]) -> Result<Vec<u32>, ModelError> {
    let tree = VertexTree::new(body).map_err(|e| ModelError::Body(e.to_string()))?;
    garment
        .iter()
        .enumerate()
        .map(|(i, &p)| match tree.nearest(p) {
            None => Err(ModelError::NonFinite {
                what: "garment vertex",
                index: i,
            }),
            Some((_, d)) if d > MAX_ASSOCIATION_DISTANCE => Err(ModelError::Garment(format!(
                "garment vertex {i} is {d:.2} m from the nearest body vertex (at most {MAX_ASSOCIATION_DISTANCE} m expected): the garment is not dressed on this body in its rest pose"
            ))),
            Some((v, _)) => Ok(v),
        })
        .collect()
}

/// The coarse regressor's target for a simulated frame: the garment's positions after
/// `rounds` Jacobi rounds of Laplacian smoothing over its edges (G5: 10).
pub fn coarse_target(garment: &TriMesh, simulated: &[[f64; 3]], rounds: usize) -> Vec<[f64; 3]> {
    garment.graph().jacobi_smooth(simulated, rounds)
}

/// Configuration of [`CoarseRegressor`].
#[derive(Config, Debug, PartialEq)]
pub struct CoarseRegressorConfig {
    /// Node features: the descriptor, the normal and α (3 + 3 + 3).
    #[config(default = 9)]
    pub node_features: usize,
    /// GAT blocks (the thesis's "4-layer" network).
    #[config(default = 4)]
    pub blocks: usize,
    /// Channels per head.
    #[config(default = 64)]
    pub channels: usize,
    /// Heads.
    #[config(default = 4)]
    pub heads: usize,
    /// Hidden widths of the output transform before the two heads.
    #[config(default = "vec![64]")]
    pub output_widths: Vec<usize>,
    /// Batch normalisation after every block.
    #[config(default = true)]
    pub batch_norm: bool,
}

impl CoarseRegressorConfig {
    /// Builds the network; errors name the field.
    pub fn init(&self, device: &Device) -> Result<CoarseRegressor, ModelError> {
        ModelError::check_positive(&[
            ("node_features", self.node_features),
            ("blocks", self.blocks),
            ("channels", self.channels),
            ("heads", self.heads),
        ])?;
        let mut d = self.node_features;
        let mut blocks = Vec::with_capacity(self.blocks);
        for _ in 0..self.blocks {
            let block = NormedGatConfig::new(
                GatBlockConfig::new(d, self.channels)
                    .with_heads(self.heads)
                    .with_self_reinforced(Some(1.0))
                    .with_activation(Activation::Tanh),
            )
            .with_batch_norm(self.batch_norm)
            .init(device)
            .map_err(nn)?;
            d = block.output_width();
            blocks.push(block);
        }
        let (hidden, d) = output_transform(d, &self.output_widths, self.batch_norm, device)?;
        Ok(CoarseRegressor {
            blocks,
            hidden,
            direction: LinearConfig::new(d, 3).init(device),
            length: positive_bias(LinearConfig::new(d, 1).init(device)),
        })
    }
}

/// The coarse regressor network; see the module documentation.
#[derive(Module, Debug)]
pub struct CoarseRegressor {
    /// The GAT blocks, in sequence.
    pub blocks: Vec<NormedGat>,
    /// The output transform's hidden layers.
    pub hidden: Option<Mlp>,
    /// The direction head (tanh, then normalised).
    pub direction: Linear,
    /// The length head (ReLU).
    pub length: Linear,
}

impl CoarseRegressor {
    /// `x`: normalised node features `[N, node_features]` on `graph` (the garment's
    /// edges between the associated body vertices) → `Δ_coarse`.
    pub fn forward(&self, x: Tensor<2>, graph: &GraphBatch) -> Result<Correction, ModelError> {
        let mut h = x;
        for block in &self.blocks {
            h = block.forward(h, graph.adjacency()).map_err(nn)?;
        }
        if let Some(hidden) = &self.hidden {
            h = hidden.forward(h).map_err(nn)?;
        }
        Ok(Correction::from_heads(
            self.direction.forward(h.clone()),
            self.length.forward(h),
        ))
    }
}

#[cfg(test)]
mod tests {
    use burn::tensor::Distribution;
    use weft_mesh::primitives::{cylinder, grid};
    use weft_nn::backend::cpu;

    use super::*;

    #[test]
    fn each_garment_vertex_finds_its_nearest_body_vertex() {
        let leg = cylinder(10, 16, 0.1, 0.02);
        let tube = cylinder(4, 16, 0.12, 0.02);
        let a = association(&leg.positions, &tube.positions).unwrap();
        // Same rings and angles: vertex k of the tube sits outside vertex k of the leg.
        assert_eq!(a, (0..64).collect::<Vec<u32>>());
        assert!(association(&leg.positions, &[[f64::NAN; 3]]).is_err());
        assert!(association(&[], &tube.positions).is_err());
    }

    #[test]
    fn coarse_targets_lose_the_folds_and_keep_the_shape() {
        let flat = grid(9, 9, 0.01);
        // A fold: every other row lifted by 5 mm.
        let folded: Vec<[f64; 3]> = flat
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                [
                    p[0],
                    p[1] + if (i / 9) % 2 == 1 { 0.005 } else { 0.0 },
                    p[2],
                ]
            })
            .collect();
        let smooth = coarse_target(&flat, &folded, 10);
        let spread = |v: &[[f64; 3]]| {
            let (lo, hi) = v.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                (lo.min(p[1]), hi.max(p[1]))
            });
            hi - lo
        };
        assert!(spread(&smooth) < 0.5 * spread(&folded));
        // In-plane positions barely move inside the sheet.
        assert!((smooth[40][0] - folded[40][0]).abs() < 1e-3);
    }

    #[test]
    fn the_regressor_gives_unit_directions_and_non_negative_lengths() {
        let device = cpu();
        let net = CoarseRegressorConfig::new()
            .with_channels(4)
            .with_heads(2)
            .init(&device)
            .unwrap();
        assert_eq!(net.blocks.len(), 4);
        let mesh = grid(5, 4, 1.0);
        let graph = GraphBatch::single(&mesh.graph());
        let x = Tensor::<2>::random([20, 9], Distribution::Default, &device);
        let out = net.forward(x, &graph).unwrap();
        let norms = out.direction.clone().powi_scalar(2).sum_dim(1).sqrt();
        assert!((norms - 1.0).abs().max().into_scalar::<f32>() < 1e-5);
        assert!(out.length.min().into_scalar::<f32>() >= 0.0);
        assert!(CoarseRegressorConfig::new()
            .with_blocks(0)
            .init(&device)
            .is_err());
    }
}
