//! Edge-contraction pooling and its unpooling: MultiResGNet's global branch (seed 001
//! eq. 3.10–3.12), in substance Diehl's EdgePool (PyG `EdgePooling`).
//!
//! The thesis scores every edge with the GAT attention coefficient `α_ij` (eq. 3.4), sorts
//! all edges by score and contracts them greedily from the highest, skipping any edge with
//! an endpoint already merged, until every node is merged or has no free neighbour (about
//! half the nodes remain). A merged pair becomes `g = α_ij (v_i + v_j)` (eq. 3.11, width
//! unchanged) and unpooling hands `g / α_ij` back to both members (eq. 3.12).
//!
//! What the thesis leaves open is decided as design note M3/M4 recommends:
//!
//! - **Scores**: a dedicated single-head attention with its own parameters (`W: d → F`,
//!   `a_src`, `a_dst ∈ R^F`, Glorot), so pooling does not depend on which GAT block feeds
//!   it. The softmax runs over `N(i)` *without* `i`: with the self-loop a node's best
//!   "partner" could be itself. The score of the directed edge `j → i` is `α_ij`, `i` the
//!   destination as everywhere in weft's GAT ([`crate::gat::attention_coefficients`]); both
//!   directions of a mesh edge are candidates and the first one sorted decides.
//! - **Greedy contraction on the host**, recomputed every forward pass (as PyG): all
//!   directed edges sorted by score descending, ties by `(i, j)` so the result is
//!   deterministic. Nodes left without a free neighbour become singleton clusters with
//!   score 1 (their feature passes unchanged). No edge joins two graphs of a
//!   [`GraphBatch`], so no cluster does either.
//! - **Clusters** are numbered by their smallest member, which keeps each graph's clusters
//!   contiguous; the coarse graph joins two clusters when any of their members are
//!   adjacent, and is returned as a [`GraphBatch`] for the GAT blocks that follow.
//! - **Merged feature** `s (v_i + v_j)` with `s = α_ij + score_offset`: 0 is the thesis,
//!   0.5 PyG's default (which keeps `s ≥ 0.5`). `s` is a tensor, so the pooling is
//!   differentiable in `v` and, through `s`, in the attention parameters; the matching
//!   itself is a discrete choice without gradient.
//! - **Unpooling** divides by `s` clamped to at least [`MIN_SCORE`]: once GAT blocks have
//!   transformed the pooled features, `g / s` no longer cancels the `s` of eq. 3.11, and a
//!   score near zero (a late contraction at a high-degree node, or an `α` that underflows)
//!   would amplify the features and their gradients without bound.

use burn::config::Config;
use burn::module::{Module, Param};
use burn::tensor::{Device, IndexingUpdateOp, Tensor};
use weft_mesh::Graph;

use crate::adjacency::{index_tensor, Adjacency};
use crate::batch::GraphBatch;
use crate::error::{check_shape, NnError, ANY};
use crate::gat::{attention_coefficients, DEFAULT_NEGATIVE_SLOPE};

/// The smallest score unpooling divides by (see the module documentation).
pub const MIN_SCORE: f64 = 1e-3;

/// Configuration of an [`EdgePool`].
#[derive(Config, Debug)]
pub struct EdgePoolConfig {
    /// Features per node `d` (unchanged by pooling).
    pub d_input: usize,
    /// Width `F` of the scoring attention's transform (16, as MultiResGNet's GAT blocks).
    #[config(default = 16)]
    pub channels: usize,
    /// LeakyReLU slope of the attention logits.
    #[config(default = "DEFAULT_NEGATIVE_SLOPE")]
    pub negative_slope: f64,
    /// Added to `α` to make the score `s`: 0 (the thesis) or 0.5 (PyG's default).
    #[config(default = 0.0)]
    pub score_offset: f64,
}

impl EdgePoolConfig {
    /// Builds the layer (Glorot-uniform parameters, as weft's GAT blocks); errors on zero
    /// sizes or a negative or non-finite offset.
    pub fn init(&self, device: &Device) -> crate::Result<EdgePool> {
        if self.d_input == 0 || self.channels == 0 {
            return Err(NnError::Config(format!(
                "edge pooling needs d_input and channels > 0, got {} and {}",
                self.d_input, self.channels
            )));
        }
        if !(self.score_offset >= 0.0 && self.score_offset.is_finite()) {
            return Err(NnError::Config(format!(
                "edge pooling score offset must be finite and ≥ 0, got {}",
                self.score_offset
            )));
        }
        let (d, f) = (self.d_input, self.channels);
        let glorot = |shape, fan_in, fan_out| {
            crate::init::glorot().init_with(shape, Some(fan_in), Some(fan_out), device)
        };
        Ok(EdgePool {
            weight: glorot([d, f], d, f),
            att_src: glorot([1, f], 1, f),
            att_dst: glorot([1, f], 1, f),
            negative_slope: self.negative_slope,
            score_offset: self.score_offset,
        })
    }
}

/// Edge-contraction pooling; see the module documentation.
#[derive(Module, Debug)]
pub struct EdgePool {
    /// `W` of the scoring attention: `[d, F]`.
    pub weight: Param<Tensor<2>>,
    /// Source half of the attention vector: `[1, F]`.
    pub att_src: Param<Tensor<2>>,
    /// Destination half of the attention vector: `[1, F]`.
    pub att_dst: Param<Tensor<2>>,
    /// LeakyReLU slope of the logits.
    pub negative_slope: f64,
    /// Added to `α` to make the score.
    pub score_offset: f64,
}

/// How the fine nodes were contracted.
#[derive(Clone, Debug)]
pub struct Clusters {
    /// For every fine row, its cluster (coarse row).
    pub assignment: Vec<u32>,
    /// Members of every cluster, the smaller row first; the second is `None` for a
    /// singleton.
    pub members: Vec<(u32, Option<u32>)>,
    /// Score `s` of every cluster, `[clusters, 1]`: `α + score_offset` of the contracted
    /// edge, 1 for a singleton. Tracked by autodiff.
    pub scores: Tensor<2>,
    /// The coarse graphs as a batch (row `c` is cluster `c`).
    pub coarse: GraphBatch,
}

/// The output of [`EdgePool::forward`].
#[derive(Clone, Debug)]
pub struct EdgePooled {
    /// Coarse features `[clusters, d]`: `s (v_i + v_j)`, or `v_i` for a singleton.
    pub features: Tensor<2>,
    /// The contraction, for [`edge_unpool`] and the coarse GAT blocks.
    pub clusters: Clusters,
}

impl EdgePool {
    /// Input (and output) features per node.
    pub fn input_width(&self) -> usize {
        self.weight.shape().dims::<2>()[0]
    }

    /// The scores `α_ij` `[entries, 1]` of the directed edges `j → i` of `batch`: softmax
    /// over `N(i)` without `i`, rows in the CSR order of the self-loop-free adjacency
    /// returned alongside ([`attention_coefficients`]). Errors as [`EdgePool::forward`].
    pub fn edge_scores(
        &self,
        x: Tensor<2>,
        batch: &GraphBatch,
    ) -> crate::Result<(Tensor<2>, Adjacency)> {
        self.check_input(&x, batch)?;
        let graph = batch.graph();
        let adjacency = Adjacency::from_csr(
            graph.vertex_count(),
            graph.offsets(),
            graph.adjacency(),
            false,
        )?;
        let z = x.matmul(self.weight.val());
        let alpha = attention_coefficients(
            z,
            self.att_src.val(),
            self.att_dst.val(),
            &adjacency,
            self.negative_slope,
        )?;
        Ok((alpha, adjacency))
    }

    /// Pools `x` (`[N, d]` on `batch`).
    pub fn forward(&self, x: Tensor<2>, batch: &GraphBatch) -> crate::Result<EdgePooled> {
        let (alpha, adjacency) = self.edge_scores(x.clone(), batch)?;
        let host: Vec<f64> = alpha
            .clone()
            .into_data()
            .convert::<f64>()
            .try_into_vec::<f64>()
            .unwrap_or_default();
        let partner = greedy_matching(&host, &adjacency);
        let entries = alpha.dims()[0];

        // Clusters by smallest member; `edge[c]` is the contracted entry, or the padding
        // row `entries` for a singleton.
        let n = batch.node_count();
        let mut assignment = vec![u32::MAX; n];
        let mut members = Vec::with_capacity(n / 2 + 1);
        let mut edge = Vec::with_capacity(n / 2 + 1);
        for v in 0..n {
            if assignment[v] != u32::MAX {
                continue;
            }
            let c = members.len() as u32;
            assignment[v] = c;
            match partner[v] {
                Some((u, e)) => {
                    assignment[u as usize] = c;
                    members.push((v as u32, Some(u)));
                    edge.push(e);
                }
                None => {
                    members.push((v as u32, None));
                    edge.push(entries as u32);
                }
            }
        }

        // s = α + offset for contracted edges, 1 (the padding row) for singletons.
        let device = x.device();
        let dtype = x.dtype();
        let padded = Tensor::cat(
            vec![
                alpha.add_scalar(self.score_offset),
                Tensor::<2>::ones([1, 1], (&device, dtype)),
            ],
            0,
        );
        let scores = padded.select(0, index_tensor(&edge, &device));
        let width = x.dims()[1];
        let sums = Tensor::<2>::zeros([members.len(), width], (&device, dtype)).select_assign(
            0,
            index_tensor(&assignment, &device),
            x,
            IndexingUpdateOp::Add,
        );
        let features = sums * scores.clone();
        let coarse = coarse_batch(batch, &assignment, &members);
        Ok(EdgePooled {
            features,
            clusters: Clusters {
                assignment,
                members,
                scores,
                coarse,
            },
        })
    }

    fn check_input(&self, x: &Tensor<2>, batch: &GraphBatch) -> crate::Result<()> {
        check_shape("edge pooling input", &[ANY, self.input_width()], &x.dims())?;
        let rows = x.dims()[0];
        if rows != batch.node_count() {
            return Err(NnError::NodeCount {
                what: "edge pooling",
                graph: batch.node_count(),
                features: rows,
            });
        }
        Ok(())
    }
}

/// Unpooling (eq. 3.12): every fine node gets its cluster's row divided by the cluster's
/// score (clamped to at least [`MIN_SCORE`]), so a merged pair's members both get
/// `v_i + v_j` back from an unchanged `s (v_i + v_j)` and a singleton its own row.
pub fn edge_unpool(coarse: Tensor<2>, clusters: &Clusters) -> crate::Result<Tensor<2>> {
    check_shape(
        "edge unpooling input",
        &[clusters.members.len(), ANY],
        &coarse.dims(),
    )?;
    let device = coarse.device();
    let scores = clusters
        .scores
        .clone()
        .cast(coarse.dtype())
        .clamp_min(MIN_SCORE);
    Ok((coarse / scores).select(0, index_tensor(&clusters.assignment, &device)))
}

/// For every node, its partner and the contracted entry, from the greedy contraction of
/// the entries of `adjacency` sorted by `scores` descending (ties by entry index, which is
/// `(i, j)` order).
fn greedy_matching(scores: &[f64], adjacency: &Adjacency) -> Vec<Option<(u32, u32)>> {
    let mut order: Vec<u32> = (0..scores.len() as u32).collect();
    order.sort_by(|&a, &b| {
        scores[b as usize]
            .total_cmp(&scores[a as usize])
            .then(a.cmp(&b))
    });
    let mut partner = vec![None; adjacency.node_count()];
    let (sources, targets) = (adjacency.sources(), adjacency.targets());
    for e in order {
        let (j, i) = (sources[e as usize], targets[e as usize]);
        if partner[i as usize].is_none() && partner[j as usize].is_none() {
            partner[i as usize] = Some((j, e));
            partner[j as usize] = Some((i, e));
        }
    }
    partner
}

/// The coarse batch: clusters joined when any of their members are adjacent.
fn coarse_batch(
    batch: &GraphBatch,
    assignment: &[u32],
    members: &[(u32, Option<u32>)],
) -> GraphBatch {
    let fine = batch.graph();
    let mut edges = Vec::new();
    for (v, &cv) in assignment.iter().enumerate() {
        for &u in fine.neighbors(v) {
            let cu = assignment[u as usize];
            if cv < cu {
                edges.push([cv, cu]);
            }
        }
    }
    // Clusters are numbered by smallest member, so each graph's clusters are contiguous.
    let mut offsets = vec![0usize];
    let mut c = 0usize;
    for g in 0..batch.graph_count() {
        let end = batch.nodes(g).end;
        while c < members.len() && (members[c].0 as usize) < end {
            c += 1;
        }
        offsets.push(c);
    }
    GraphBatch::from_union(Graph::from_edges(members.len(), &edges), offsets)
}

#[cfg(test)]
mod tests;
