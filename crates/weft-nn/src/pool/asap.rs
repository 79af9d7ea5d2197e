//! ASAP (Ranjan et al. 2020, adaptive structure aware pooling), as PyTorch Geometric's
//! `ASAPooling` without the optional intra-cluster GNN and dropout:
//!
//! 1. every node `i` is the center of the cluster `c_i = N(i) ∪ {i}`;
//! 2. **master2token attention**: the master query is the cluster's element-wise max
//!    `m_i = max_{j∈c_i} x_j`, projected `q_i = W_q m_i`; the member scores are
//!    `e_ij = LeakyReLU(a_qᵀ q_i + a_xᵀ x_j + b)`, softmax-normalised over `j ∈ c_i`, and the
//!    cluster representation is `x^c_i = Σ_j α_ij x_j`;
//! 3. **fitness** by a local-extremum convolution (LEConv),
//!    `φ_i = σ(x^c_i Θ₁ + Σ_{j∈N(i)} (x^c_i Θ₂ − x^c_j Θ₃))`;
//! 4. each graph keeps its `⌈ratio · N⌉` fittest clusters, gated: `X' = X^c[idx] ⊙ φ[idx]`;
//! 5. the pooled adjacency is the pattern of `Sᵀ (A + I) S` with `S_ji = α_ij` restricted to
//!    the kept clusters: two clusters are joined when a member of one is a member of, or
//!    adjacent to, a member of the other (centers within three hops).
//!
//! The max in step 2 is taken on the host per channel and gathered back with `select`, so
//! its gradient (to the arg-max member) is exact.

use std::sync::Arc;

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::activation::{leaky_relu, sigmoid};
use burn::tensor::{Device, IndexingUpdateOp, Tensor, TensorData};

use super::{batch_on, check_ratio, host_scores, top_k, Pooled, Selection};
use crate::adjacency::index_tensor;
use crate::batch::GraphBatch;
use crate::error::{check_shape, NnError};
use crate::sparse::{sparse_matmul, SparseImpl, SparseMatrix};

/// Configuration of an [`AsapPool`].
#[derive(Config, Debug)]
pub struct AsapPoolConfig {
    /// Features per node.
    pub channels: usize,
    /// Fraction of clusters kept per graph, in (0, 1].
    #[config(default = 0.5)]
    pub ratio: f64,
    /// LeakyReLU slope of the master2token scores.
    #[config(default = 0.2)]
    pub negative_slope: f64,
}

impl AsapPoolConfig {
    /// Builds the layer (Kaiming-uniform linear maps, as `nn.Linear`).
    pub fn init(&self, device: &Device) -> crate::Result<AsapPool> {
        check_ratio(self.ratio)?;
        let c = self.channels;
        if c == 0 {
            return Err(NnError::Config("ASAP needs channels > 0".into()));
        }
        let lin = |i, o, bias| LinearConfig::new(i, o).with_bias(bias).init(device);
        Ok(AsapPool {
            query: lin(c, c, true),
            att_query: lin(c, 1, true),
            att_member: lin(c, 1, false),
            le_self: lin(c, 1, true),
            le_center: lin(c, 1, false),
            le_neighbour: lin(c, 1, false),
            ratio: self.ratio,
            negative_slope: self.negative_slope,
        })
    }
}

/// ASAP pooling; see the module documentation.
#[derive(Module, Debug)]
pub struct AsapPool {
    /// `W_q`: master query projection.
    pub query: Linear,
    /// `a_q` (with the score bias).
    pub att_query: Linear,
    /// `a_x`.
    pub att_member: Linear,
    /// LEConv Θ₁ (with bias).
    pub le_self: Linear,
    /// LEConv Θ₂.
    pub le_center: Linear,
    /// LEConv Θ₃.
    pub le_neighbour: Linear,
    /// Fraction kept.
    pub ratio: f64,
    /// LeakyReLU slope of the scores.
    pub negative_slope: f64,
}

impl AsapPool {
    /// Pools `x` (`[N, C]` on `batch`).
    pub fn forward(&self, x: Tensor<2>, batch: &GraphBatch) -> crate::Result<Pooled> {
        let channels = self.query.weight.shape().dims::<2>()[0];
        let n = batch.node_count();
        check_shape("ASAP input", &[n, channels], &x.dims())?;
        let device = x.device();
        let adj = batch.adjacency();
        let (sources, targets) = adj.index_tensors(&device);
        let entries = adj.entry_count();

        // Master query: per-channel max over the cluster, gathered by arg-max.
        let host = x
            .clone()
            .into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .unwrap_or_default();
        let mut argmax = vec![0u32; n * channels];
        for i in 0..n {
            for c in 0..channels {
                let mut best = (f32::NEG_INFINITY, i);
                for &j in adj.incoming(i) {
                    let v = host[j as usize * channels + c];
                    if v > best.0 {
                        best = (v, j as usize);
                    }
                }
                argmax[i * channels + c] = (best.1 * channels + c) as u32;
            }
        }
        let master = x
            .clone()
            .reshape([n * channels])
            .select(0, index_tensor(&argmax, &device))
            .reshape([n, channels]);
        let q = self.query.forward(master);

        // Master2token attention over each cluster.
        let logits = leaky_relu(
            self.att_query.forward(q).select(0, targets.clone())
                + self
                    .att_member
                    .forward(x.clone())
                    .select(0, sources.clone()),
            self.negative_slope,
        );
        let dtype = x.dtype();
        let max = Tensor::<2>::full([n, 1], f32::MIN, (&device, dtype)).select_assign(
            0,
            targets.clone(),
            logits.clone().detach(),
            IndexingUpdateOp::Max,
        );
        let weights = (logits - max.select(0, targets.clone()).detach()).exp();
        let total = Tensor::<2>::zeros([n, 1], (&device, dtype)).select_assign(
            0,
            targets.clone(),
            weights.clone(),
            IndexingUpdateOp::Add,
        );
        let alpha = weights / total.select(0, targets.clone());
        let clusters = Tensor::<2>::zeros([n, channels], (&device, dtype)).select_assign(
            0,
            targets,
            x.select(0, sources) * alpha,
            IndexingUpdateOp::Add,
        );
        debug_assert_eq!(entries, adj.sources().len());

        // Fitness by LEConv on the cluster features (neighbours without self-loops).
        let graph = batch.graph();
        let degree: Vec<f64> = (0..n).map(|i| graph.degree(i) as f64).collect();
        let neighbours = Arc::new(
            SparseMatrix::from_triplets(
                n,
                n,
                (0..n).flat_map(|i| graph.neighbors(i).iter().map(move |&j| (i as u32, j, 1.0))),
            )
            .expect("graph indices are in range"),
        );
        let degree = Tensor::<2>::from_data(TensorData::new(degree, [n, 1]), (&device, dtype));
        let fitness = sigmoid(
            self.le_self.forward(clusters.clone())
                + self.le_center.forward(clusters.clone()) * degree
                - sparse_matmul(
                    &neighbours,
                    self.le_neighbour.forward(clusters.clone()),
                    SparseImpl::Auto,
                )?,
        );

        let kept = top_k(&host_scores(&fitness), batch, self.ratio);
        let idx = index_tensor(&kept, &device);
        let features = clusters.select(0, idx.clone()) * fitness.select(0, idx);
        Ok(Pooled {
            features,
            selection: Selection {
                coarse: cluster_graph(batch, &kept),
                fine_count: n,
                kept,
            },
        })
    }
}

/// The pattern of `Sᵀ (A + I) S` on the kept cluster centers: each center joined to the
/// kept centers within three hops. A breadth-first search per center with a visit stamp
/// reaches each vertex once; enumerating the three-hop *paths* instead grows with the
/// cube of the degree, which on the second ASAP level (already three-hop dense) cost
/// seconds per forward pass.
fn cluster_graph(batch: &GraphBatch, kept: &[u32]) -> GraphBatch {
    let fine = batch.graph();
    let mut coarse_index = vec![u32::MAX; fine.vertex_count()];
    for (c, &v) in kept.iter().enumerate() {
        coarse_index[v as usize] = c as u32;
    }
    let mut stamp = vec![u32::MAX; fine.vertex_count()];
    let (mut frontier, mut next) = (Vec::new(), Vec::new());
    let mut edges = Vec::new();
    for (c, &center) in kept.iter().enumerate() {
        let c = c as u32;
        stamp[center as usize] = c;
        frontier.clear();
        frontier.push(center);
        for _hop in 0..3 {
            next.clear();
            for &v in &frontier {
                for &u in fine.neighbors(v as usize) {
                    if stamp[u as usize] != c {
                        stamp[u as usize] = c;
                        next.push(u);
                        let co = coarse_index[u as usize];
                        if co != u32::MAX && c < co {
                            edges.push([c, co]);
                        }
                    }
                }
            }
            std::mem::swap(&mut frontier, &mut next);
        }
    }
    batch_on(batch, kept, &edges)
}
