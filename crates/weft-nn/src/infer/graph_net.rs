//! [`Processor`]'s inference form: the message / aggregate / update of
//! [`crate::graph_net`] on host buffers.
//!
//! - every MLP runs a chunk of rows through all its layers while the chunk is in cache
//!   ([`InferMlp::map_rows`]), bias and ReLU in the pass after each product, the layer
//!   normalisation and the residual `+` in the pass that ends the chunk;
//! - the edge MLP's first layer is formed in parts as the burn block forms it
//!   (`graph_net.rs`, `message`): the endpoint nodes' rows multiplied once by `[W_r | W_s]`,
//!   then gathered per edge and added to `e W_e`;
//! - the sums at the receivers are written straight into the node MLP's input rows (per
//!   node, its incoming edges in edge order: the same sums, in the same order, as the burn
//!   block's scatter-add), and every latent is updated in place.
//!
//! Why: on burn's flex backend the paper network's step at 4 000 vertices spent 46 % of
//! its time outside the products, in copies for the concatenations and gathers,
//! zero-filled new tensors and one pass over memory for each bias, ReLU, layer
//! normalisation and residual (docs/hood.md, "Speed").

use super::{matmul, product, Columns, Features, InferMlp};
use crate::adjacency::group_by_key;
use crate::error::{check_shape, NnError};
use crate::graph_net::{check_sets, endpoint_positions, split_edges, GraphNetBlock, Processor};
use crate::real::simd;

/// An [`crate::EdgeSet`] on the host: the edges' endpoints for the messages and each
/// node's incoming edges for the sums.
#[derive(Clone, Debug)]
pub struct InferEdgeSet {
    node_count: usize,
    /// The endpoint nodes, ascending, or `None` when every node is one.
    endpoints: Option<Vec<u32>>,
    /// Sender and receiver of every edge as positions among the endpoints.
    senders: Vec<u32>,
    receivers: Vec<u32>,
    /// Node `i`'s incoming edges, in edge order: `incoming[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<usize>,
    incoming: Vec<u32>,
}

impl InferEdgeSet {
    /// From `[sender, receiver]` pairs; errors on an endpoint `≥ node_count`.
    pub fn new(node_count: usize, edges: &[[u32; 2]]) -> crate::Result<Self> {
        let (senders, receivers) = split_edges(node_count, edges)?;
        let (offsets, incoming) = group_by_key(node_count, &receivers);
        let (endpoints, senders, receivers) = endpoint_positions(node_count, &senders, &receivers);
        Ok(InferEdgeSet {
            node_count,
            endpoints,
            senders,
            receivers,
            offsets,
            incoming,
        })
    }

    /// Nodes of the graph the edges index.
    pub fn node_count(&self) -> usize {
        self.node_count
    }

    /// Edges.
    pub fn edge_count(&self) -> usize {
        self.senders.len()
    }

    /// The incoming edges of node `i`, in edge order.
    fn incoming(&self, i: usize) -> &[u32] {
        &self.incoming[self.offsets[i]..self.offsets[i + 1]]
    }
}

/// The rows `rows` of `x`.
fn gather(x: &Features, rows: &[u32]) -> Features {
    let w = x.width;
    let mut data = Vec::with_capacity(rows.len() * w);
    for &r in rows {
        data.extend_from_slice(&x.data[r as usize * w..(r as usize + 1) * w]);
    }
    Features { data, width: w }
}

/// `rows × width` row-major values as the left operand of a product.
fn whole(data: &[f32], width: usize) -> Columns<'_> {
    Columns {
        data,
        stride: width,
        start: 0,
        width,
    }
}

/// A [`GraphNetBlock`] for inference.
#[derive(Clone, Debug)]
struct InferGraphNetBlock {
    /// Per edge set read: its MLP and its first layer's node blocks `[W_r | W_s]`
    /// (`[L, 2L]` row-major).
    edge_mlps: Vec<(InferMlp, Vec<f32>)>,
    node_mlp: InferMlp,
    latent: usize,
}

impl From<&GraphNetBlock> for InferGraphNetBlock {
    fn from(block: &GraphNetBlock) -> Self {
        let l = block.latent();
        let edge_mlps = block
            .edge_mlps
            .iter()
            .map(|mlp| {
                let mlp = InferMlp::from(mlp);
                // `W₀` is `[3L, L]`: rows `0..L` read the receiver, `L..2L` the sender.
                let w = mlp.first_weight();
                let mut nodes = Vec::with_capacity(2 * l * l);
                for row in 0..l {
                    nodes.extend_from_slice(&w[row * l..(row + 1) * l]);
                    nodes.extend_from_slice(&w[(l + row) * l..(l + row + 1) * l]);
                }
                (mlp, nodes)
            })
            .collect();
        InferGraphNetBlock {
            edge_mlps,
            node_mlp: InferMlp::from(&block.node_mlp),
            latent: l,
        }
    }
}

impl InferGraphNetBlock {
    /// One step: the sets `step` names (in the order of the edge MLPs), their latents and
    /// the nodes updated in place.
    fn forward(
        &self,
        nodes: &mut Features,
        sets: &[InferEdgeSet],
        edges: &mut [Features],
        step: &[usize],
    ) {
        for (j, &k) in step.iter().enumerate() {
            self.message(j, nodes, &sets[k], &mut edges[k]);
        }
        self.update(nodes, sets, edges, step);
    }

    /// `e' = e + f_j([x_receiver, x_sender, e])` for every edge of `set`.
    fn message(&self, j: usize, nodes: &Features, set: &InferEdgeSet, e: &mut Features) {
        if set.edge_count() == 0 {
            return;
        }
        let l = self.latent;
        let (mlp, w_nodes) = &self.edge_mlps[j];
        let at_nodes = match &set.endpoints {
            Some(endpoints) => matmul(gather(nodes, endpoints).columns(0..l), w_nodes, 2 * l),
            None => matmul(nodes.columns(0..l), w_nodes, 2 * l),
        };
        let w_edge = &mlp.first_weight()[2 * l * l..];
        let (receivers, senders) = (&set.receivers, &set.senders);
        mlp.map_rows(e, true, |rows, before, _, h| {
            product(h, whole(before, l), w_edge, l, gemm::Parallelism::None);
            simd(
                #[inline(always)]
                || {
                    for (i, out) in rows.zip(h.chunks_exact_mut(l)) {
                        let r = receivers[i] as usize * 2 * l;
                        let s = senders[i] as usize * 2 * l + l;
                        let (r, s) = (&at_nodes.data[r..r + l], &at_nodes.data[s..s + l]);
                        for ((o, a), b) in out.iter_mut().zip(r).zip(s) {
                            *o = *o + a + b;
                        }
                    }
                },
            );
        });
    }

    /// `x' = x + f_node([x, a_1, …, a_K])`, each `a_j` summed into the input rows.
    fn update(
        &self,
        nodes: &mut Features,
        sets: &[InferEdgeSet],
        edges: &[Features],
        step: &[usize],
    ) {
        let l = self.latent;
        let width = (1 + step.len()) * l;
        let w_first = self.node_mlp.first_weight();
        self.node_mlp
            .map_rows(nodes, true, |rows, before, input, h| {
                input.resize(rows.len() * width, 0.0);
                simd(
                    #[inline(always)]
                    || {
                        for ((i, row), x) in rows
                            .clone()
                            .zip(input.chunks_exact_mut(width))
                            .zip(before.chunks_exact(l))
                        {
                            row[..l].copy_from_slice(x);
                            for (j, &k) in step.iter().enumerate() {
                                let sum = &mut row[(1 + j) * l..(2 + j) * l];
                                sum.fill(0.0);
                                for &edge in sets[k].incoming(i) {
                                    let e = &edges[k].data[edge as usize * l..][..l];
                                    sum.iter_mut().zip(e).for_each(|(s, v)| *s += v);
                                }
                            }
                        }
                    },
                );
                product(h, whole(input, width), w_first, l, gemm::Parallelism::None);
            });
    }
}

/// [`Processor`] for inference; equal to its forward up to float rounding.
#[derive(Clone, Debug)]
pub struct InferProcessor {
    blocks: Vec<InferGraphNetBlock>,
    schedule: Vec<Vec<usize>>,
    edge_sets: usize,
    latent: usize,
}

impl From<&Processor> for InferProcessor {
    fn from(processor: &Processor) -> Self {
        InferProcessor {
            blocks: processor
                .blocks
                .iter()
                .map(InferGraphNetBlock::from)
                .collect(),
            schedule: processor.schedule().to_vec(),
            edge_sets: processor.edge_sets(),
            latent: processor.latent(),
        }
    }
}

impl InferProcessor {
    /// Latent width `L`.
    pub fn latent(&self) -> usize {
        self.latent
    }

    /// `nodes` `[N, L]`; all the graph's `sets` with their latents `edges[k]` `[E_k, L]`.
    /// Runs the steps in order, updating the nodes and the latents of the sets each step
    /// reads in place.
    pub fn forward(
        &self,
        nodes: &mut Features,
        sets: &[InferEdgeSet],
        edges: &mut [Features],
    ) -> crate::Result<()> {
        check_sets(self.edge_sets, sets.len(), edges.len())?;
        nodes.check_width("processor nodes", self.latent)?;
        for (set, e) in sets.iter().zip(edges.iter()) {
            if set.node_count != nodes.rows() {
                return Err(NnError::NodeCount {
                    what: "processor edge set",
                    graph: set.node_count,
                    features: nodes.rows(),
                });
            }
            check_shape(
                "processor edge latents",
                &[set.edge_count(), self.latent],
                &[e.rows(), e.width()],
            )?;
        }
        for (block, step) in self.blocks.iter().zip(&self.schedule) {
            block.forward(nodes, sets, edges, step);
        }
        Ok(())
    }
}
