//! Message passing over typed edge sets: the processor of MeshGraphNets and HOOD (seed 004),
//! in PyTorch Geometric's message / aggregate / update terms.
//!
//! One [`GraphNetBlock`] (MeshGraphNets' `GraphNetBlock`) reads one or more directed
//! [`EdgeSet`]s over the same nodes, each with its own edge latents `e_k`:
//!
//! - message, per set: `e_k' = e_k + f_k([x_receiver, x_sender, e_k])`;
//! - aggregate, per set: `a_k(i) = Σ_{edges of set k into i} e_k'` (zero for a node with no
//!   incoming edge of that set);
//! - update: `x' = x + f_node([x, a_1, …, a_K])`.
//!
//! Every `f` is an [`Mlp`] of `hidden_layers` ReLU layers and an identity output layer, all
//! of width `latent`, then layer normalisation; both updates are residual, so many steps
//! keep the latents at one scale.
//!
//! Sum, not mean: HOOD's paper writes the aggregation as a mean, but its code (as
//! MeshGraphNets') sums; the sum keeps the node count of a neighbourhood visible to the
//! update (a vertex touching the body through three edges gets three messages' worth).
//!
//! The [`Processor`] holds the multi-level schedule as data: one block per message-passing
//! step (no parameters shared between steps), each step naming the edge sets it reads. A
//! step rewrites only the latents of the sets it reads; the others persist unchanged for
//! later steps. With the sets numbered fine = 0, coarse c0 = 1, c1 = 2, HOOD's 15 steps are
//! one schedule,
//!
//! ```text
//! [0, 1] ×3, [1, 2] ×3, [2] ×3, [1, 2] ×3, [0, 1] ×3
//! ```
//!
//! and its single-level baselines Fine15 / Fine48 are `[0]` repeated 15 / 48 times. The
//! body edges (rebuilt every step from nearest body points) are one more set that the
//! steps read alongside the mesh edges; an [`EdgeSet`] is two index tensors, cheap to
//! build each time.

use burn::config::Config;
use burn::module::Module;
use burn::tensor::{Device, IndexingUpdateOp, Int, Tensor};

use crate::activation::Activation;
use crate::adjacency::index_tensor;
use crate::error::{check_shape, NnError, ANY};
use crate::mlp::{Mlp, MlpConfig};

/// A directed edge list `(sender, receiver)` over `node_count` nodes, as index tensors.
#[derive(Clone, Debug)]
pub struct EdgeSet {
    senders: Tensor<1, Int>,
    receivers: Tensor<1, Int>,
    node_count: usize,
    edge_count: usize,
    /// The nodes that are an endpoint of some edge, ascending, with the edges' endpoints
    /// as positions in that list: the block's messages multiply only these nodes' rows
    /// (a coarse level's edges touch a quarter of the nodes, the body edges few).
    endpoints: Endpoints,
}

/// The endpoint nodes of an [`EdgeSet`] (see [`message`]).
#[derive(Clone, Debug)]
struct Endpoints {
    /// The endpoint nodes, or `None` when every node is one (the edges then index the
    /// nodes directly).
    nodes: Option<Tensor<1, Int>>,
    /// Sender and receiver of every edge as positions in `nodes`.
    senders: Tensor<1, Int>,
    receivers: Tensor<1, Int>,
}

impl Endpoints {
    fn new(node_count: usize, senders: &[u32], receivers: &[u32], device: &Device) -> Self {
        let (nodes, senders, receivers) = endpoint_positions(node_count, senders, receivers);
        Endpoints {
            nodes: nodes.map(|nodes| index_tensor(&nodes, device)),
            senders: index_tensor(&senders, device),
            receivers: index_tensor(&receivers, device),
        }
    }
}

/// The endpoint nodes of the edges `(senders[i], receivers[i])`, ascending, and every
/// edge's sender and receiver as positions among them; `None` and the nodes themselves
/// when every node is an endpoint.
pub(crate) fn endpoint_positions(
    node_count: usize,
    senders: &[u32],
    receivers: &[u32],
) -> (Option<Vec<u32>>, Vec<u32>, Vec<u32>) {
    let mut position = vec![u32::MAX; node_count];
    for &v in senders.iter().chain(receivers) {
        position[v as usize] = 0;
    }
    let mut nodes = Vec::new();
    for (v, p) in position.iter_mut().enumerate() {
        if *p == 0 {
            *p = nodes.len() as u32;
            nodes.push(v as u32);
        }
    }
    if nodes.len() == node_count {
        return (None, senders.to_vec(), receivers.to_vec());
    }
    let local = |ends: &[u32]| -> Vec<u32> { ends.iter().map(|&v| position[v as usize]).collect() };
    (Some(nodes), local(senders), local(receivers))
}

/// The senders and receivers of `[sender, receiver]` pairs; errors on an endpoint
/// `≥ node_count`.
pub(crate) fn split_edges(
    node_count: usize,
    edges: &[[u32; 2]],
) -> crate::Result<(Vec<u32>, Vec<u32>)> {
    let mut senders = Vec::with_capacity(edges.len());
    let mut receivers = Vec::with_capacity(edges.len());
    for &[s, r] in edges {
        for v in [s, r] {
            if v as usize >= node_count {
                return Err(NnError::Index {
                    what: "edge set endpoint",
                    index: v as usize,
                    len: node_count,
                });
            }
        }
        senders.push(s);
        receivers.push(r);
    }
    Ok((senders, receivers))
}

impl EdgeSet {
    /// From `[sender, receiver]` pairs; errors on an endpoint `≥ node_count`.
    pub fn new(node_count: usize, edges: &[[u32; 2]], device: &Device) -> crate::Result<Self> {
        let (senders, receivers) = split_edges(node_count, edges)?;
        Ok(EdgeSet {
            senders: index_tensor(&senders, device),
            receivers: index_tensor(&receivers, device),
            node_count,
            edge_count: edges.len(),
            endpoints: Endpoints::new(node_count, &senders, &receivers, device),
        })
    }

    /// Nodes of the graph the edges index.
    pub fn node_count(&self) -> usize {
        self.node_count
    }

    /// Edges.
    pub fn edge_count(&self) -> usize {
        self.edge_count
    }

    /// Sender of every edge, `[E]`.
    pub fn senders(&self) -> &Tensor<1, Int> {
        &self.senders
    }

    /// Receiver of every edge, `[E]`.
    pub fn receivers(&self) -> &Tensor<1, Int> {
        &self.receivers
    }

    /// Sum of the rows of `messages` (`[E, C]`) at their receivers: `[node_count, C]`, zero
    /// rows for nodes without an incoming edge.
    pub fn aggregate(&self, messages: Tensor<2>) -> crate::Result<Tensor<2>> {
        check_shape("edge messages", &[self.edge_count, ANY], &messages.dims())?;
        Ok(self.sum_at_receivers(messages))
    }

    /// [`Self::aggregate`] without the shape check. A scatter-add (`select_assign(Add)`):
    /// one pass over `E × C` values, which flex runs serially in edge order, hence
    /// deterministically; its backward is a gather. Measured on flex (2 cores, E = 60 000,
    /// N = 10 000, C = 128, forward + backward): 6–10 ms, against 16 ms for the CSR
    /// [`crate::sparse_matmul`] plus 5 ms to build its matrix each step, and 0.7 s for the
    /// edge MLP that made the messages.
    fn sum_at_receivers(&self, messages: Tensor<2>) -> Tensor<2> {
        let [_, width] = messages.dims();
        let zeros = Tensor::<2>::zeros(
            [self.node_count, width],
            (&messages.device(), messages.dtype()),
        );
        if self.edge_count == 0 {
            return zeros;
        }
        zeros.select_assign(0, self.receivers.clone(), messages, IndexingUpdateOp::Add)
    }
}

/// The MLP of every block: `hidden_layers` ReLU layers and an identity output layer, all of
/// width `latent`, then layer normalisation.
fn latent_mlp(
    d_input: usize,
    latent: usize,
    hidden_layers: usize,
    device: &Device,
) -> crate::Result<Mlp> {
    MlpConfig::new(d_input, vec![latent; hidden_layers + 1])
        .with_activation(Activation::Relu)
        .with_output_activation(Activation::None)
        .with_layer_norm(true)
        .init(device)
}

/// Configuration of a [`GraphNetBlock`].
#[derive(Config, Debug)]
pub struct GraphNetBlockConfig {
    /// Width of node and edge latents `L`.
    pub latent: usize,
    /// Edge sets the block reads `K` (one edge MLP each).
    pub edge_sets: usize,
    /// Hidden layers of every MLP (MeshGraphNets: 2).
    #[config(default = 2)]
    pub hidden_layers: usize,
}

/// One message-passing step over `K` edge sets; see the module documentation.
#[derive(Module, Debug)]
pub struct GraphNetBlock {
    /// `f_k`: `[x_receiver, x_sender, e_k]` (`3L`) → `L`, one per edge set read.
    pub edge_mlps: Vec<Mlp>,
    /// `f_node`: `[x, a_1, …, a_K]` (`(1 + K) L`) → `L`.
    pub node_mlp: Mlp,
}

impl GraphNetBlockConfig {
    /// Builds the block; errors on a zero latent width or no edge set.
    pub fn init(&self, device: &Device) -> crate::Result<GraphNetBlock> {
        if self.latent == 0 || self.edge_sets == 0 {
            return Err(NnError::Config(format!(
                "a graph net block needs latent > 0 and at least one edge set, got latent {} and {} edge sets",
                self.latent, self.edge_sets
            )));
        }
        let (l, h) = (self.latent, self.hidden_layers);
        let edge_mlps = (0..self.edge_sets)
            .map(|_| latent_mlp(3 * l, l, h, device))
            .collect::<crate::Result<_>>()?;
        Ok(GraphNetBlock {
            edge_mlps,
            node_mlp: latent_mlp((1 + self.edge_sets) * l, l, h, device)?,
        })
    }
}

impl GraphNetBlock {
    /// Latent width `L`.
    pub fn latent(&self) -> usize {
        self.node_mlp.output_width()
    }

    /// Edge sets the block reads.
    pub fn edge_sets(&self) -> usize {
        self.edge_mlps.len()
    }

    /// `nodes` `[N, L]`; `sets[k]` over the same `N` nodes with `edges[k]` `[E_k, L]`, in the
    /// order of the edge MLPs. Returns the new nodes `[N, L]` and edge latents `[E_k, L]`.
    pub fn forward(
        &self,
        nodes: Tensor<2>,
        sets: &[&EdgeSet],
        edges: Vec<Tensor<2>>,
    ) -> crate::Result<(Tensor<2>, Vec<Tensor<2>>)> {
        let latent = self.latent();
        check_shape("graph net block nodes", &[ANY, latent], &nodes.dims())?;
        let n = nodes.dims()[0];
        if sets.len() != self.edge_sets() || edges.len() != self.edge_sets() {
            return Err(NnError::Config(format!(
                "a graph net block of {} edge sets got {} edge sets and {} edge latents",
                self.edge_sets(),
                sets.len(),
                edges.len()
            )));
        }
        let mut new_edges = Vec::with_capacity(edges.len());
        let mut node_input = Vec::with_capacity(edges.len() + 1);
        node_input.push(nodes.clone());
        for ((mlp, set), e) in self.edge_mlps.iter().zip(sets).zip(edges) {
            if set.node_count != n {
                return Err(NnError::NodeCount {
                    what: "graph net block edge set",
                    graph: set.node_count,
                    features: n,
                });
            }
            check_shape(
                "graph net block edges",
                &[set.edge_count, latent],
                &e.dims(),
            )?;
            // No edges (a body far from the garment): nothing to send, and no zero-row
            // products for the backend to handle.
            // Message: e' = e + f_k([x_receiver, x_sender, e]), the product split by
            // input block (see `message`).
            let e = if set.edge_count == 0 {
                e
            } else {
                let message = message(mlp, &nodes, set, e.clone());
                e + message
            };
            // Aggregate: the sum of e' at the receivers.
            node_input.push(set.sum_at_receivers(e.clone()));
            new_edges.push(e);
        }
        // Update: x' = x + f_node([x, a_1, …, a_K]).
        let update = self.node_mlp.forward(Tensor::cat(node_input, 1))?;
        Ok((nodes + update, new_edges))
    }
}

/// The message `f([x_receiver, x_sender, e])` of every edge of `set` (`[E, L]`).
///
/// Written out, this is `mlp.forward(cat([x.select(receivers), x.select(senders), e]))`
/// (`plain_message` in the tests). It is computed in the equal form
///
/// ```text
/// [x_r, x_s, e] W + b = (x_U W_r + b)[receivers] + (x_U W_s)[senders] + e W_e,
/// ```
///
/// with `W_r, W_s, W_e` the row blocks of the first layer's `[3L, L]` weight and `x_U` the
/// rows of the set's endpoint nodes, because the node rows are then multiplied once per
/// endpoint node instead of once per edge inside gathered `[E, 3L]` rows: with E ≈ 6 N on
/// a mesh level that takes 2 of the edge MLP's 5 `L × L` products per edge away, and the
/// `[E, 3L]` concatenation with it. The rest of the MLP runs as in [`Mlp::forward`]. Same
/// result up to float rounding (the sum is associated differently); autodiff
/// differentiates through the gathers and the weight's row slices, so the parameters and
/// their record are the plain MLP's.
fn message(mlp: &Mlp, nodes: &Tensor<2>, set: &EdgeSet, e: Tensor<2>) -> Tensor<2> {
    let first = &mlp.layers[0];
    let [d_input, width] = first.weight.dims();
    let l = d_input / 3;
    let w = first.weight.val();
    let block = |k: usize| w.clone().slice([k * l..(k + 1) * l, 0..width]);
    let ends = &set.endpoints;
    let x = match &ends.nodes {
        Some(endpoints) => nodes.clone().select(0, endpoints.clone()),
        None => nodes.clone(),
    };
    let mut at_receiver = x.clone().matmul(block(0));
    if let Some(bias) = &first.bias {
        at_receiver = at_receiver + bias.val().unsqueeze::<2>();
    }
    let at_sender = x.matmul(block(1));
    let first_layer = e.matmul(block(2))
        + at_receiver.select(0, ends.receivers.clone())
        + at_sender.select(0, ends.senders.clone());
    mlp.after_first_linear(first_layer)
}

/// Errors unless a processor over `edge_sets` sets got that many sets and latents.
pub(crate) fn check_sets(edge_sets: usize, sets: usize, latents: usize) -> crate::Result<()> {
    if sets != edge_sets || latents != edge_sets {
        return Err(NnError::Config(format!(
            "a processor over {edge_sets} edge sets got {sets} edge sets and {latents} edge latents"
        )));
    }
    Ok(())
}

/// Configuration of a [`Processor`].
#[derive(Config, Debug)]
pub struct ProcessorConfig {
    /// Width of node and edge latents `L`.
    pub latent: usize,
    /// Edge sets of the graph.
    pub edge_sets: usize,
    /// For each message-passing step, in order, the edge sets it reads (indices into the
    /// graph's sets; in each step's block, its edge MLPs follow this order).
    pub schedule: Vec<Vec<usize>>,
    /// Hidden layers of every MLP (MeshGraphNets: 2).
    #[config(default = 2)]
    pub hidden_layers: usize,
}

impl ProcessorConfig {
    /// Errors (naming the step) on no step, an empty step, a set index `≥ edge_sets` or a
    /// set read twice in one step.
    pub fn validate(&self) -> crate::Result<()> {
        if self.schedule.is_empty() {
            return Err(NnError::Config(
                "a processor needs at least one message-passing step".into(),
            ));
        }
        for (step, sets) in self.schedule.iter().enumerate() {
            if sets.is_empty() {
                return Err(NnError::Config(format!(
                    "processor step {step} reads no edge set"
                )));
            }
            for (i, &k) in sets.iter().enumerate() {
                if k >= self.edge_sets {
                    return Err(NnError::Config(format!(
                        "processor step {step} reads edge set {k}, but the graph has {} edge sets",
                        self.edge_sets
                    )));
                }
                if sets[..i].contains(&k) {
                    return Err(NnError::Config(format!(
                        "processor step {step} reads edge set {k} twice"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Builds one block per step; errors as [`Self::validate`] and on a zero latent width.
    pub fn init(&self, device: &Device) -> crate::Result<Processor> {
        self.validate()?;
        let blocks = self
            .schedule
            .iter()
            .map(|sets| {
                GraphNetBlockConfig::new(self.latent, sets.len())
                    .with_hidden_layers(self.hidden_layers)
                    .init(device)
            })
            .collect::<crate::Result<_>>()?;
        Ok(Processor {
            blocks,
            schedule: self.schedule.clone(),
            edge_sets: self.edge_sets,
        })
    }
}

/// Message-passing steps over a multi-level graph; see the module documentation.
#[derive(Module, Debug)]
pub struct Processor {
    /// One block per step.
    pub blocks: Vec<GraphNetBlock>,
    #[module(skip)]
    schedule: Vec<Vec<usize>>,
    #[module(skip)]
    edge_sets: usize,
}

impl Processor {
    /// The edge sets each step reads.
    pub fn schedule(&self) -> &[Vec<usize>] {
        &self.schedule
    }

    /// Edge sets of the graph.
    pub fn edge_sets(&self) -> usize {
        self.edge_sets
    }

    /// Latent width `L`.
    pub fn latent(&self) -> usize {
        self.blocks.first().map_or(0, GraphNetBlock::latent)
    }

    /// `nodes` `[N, L]`; all the graph's `sets` with their latents `edges[k]` `[E_k, L]`.
    /// Runs the steps in order and returns the new nodes and the latents of every set.
    pub fn forward(
        &self,
        nodes: Tensor<2>,
        sets: &[EdgeSet],
        edges: Vec<Tensor<2>>,
    ) -> crate::Result<(Tensor<2>, Vec<Tensor<2>>)> {
        check_sets(self.edge_sets, sets.len(), edges.len())?;
        let mut nodes = nodes;
        let mut edges = edges;
        for (block, step) in self.blocks.iter().zip(&self.schedule) {
            let step_sets: Vec<&EdgeSet> = step.iter().map(|&k| &sets[k]).collect();
            let step_edges = step.iter().map(|&k| edges[k].clone()).collect();
            let (x, updated) = block.forward(nodes, &step_sets, step_edges)?;
            nodes = x;
            for (&k, e) in step.iter().zip(updated) {
                edges[k] = e;
            }
        }
        Ok((nodes, edges))
    }
}

#[cfg(test)]
mod tests {
    use burn::module::{ModuleVisitor, Param};
    use burn::tensor::{DType, Gradients, TensorData};

    use super::*;
    use crate::backend::{cpu, cpu_autodiff, seeded};
    use crate::testutil::{host, max_diff, tensor, Rng};

    /// Four nodes; node 3 receives no edge of either set.
    const SET_A: [[u32; 2]; 4] = [[0, 1], [2, 1], [1, 2], [3, 0]];
    const SET_B: [[u32; 2]; 3] = [[3, 1], [1, 0], [0, 2]];

    fn random(rng: &mut Rng, rows: usize, cols: usize, device: &Device) -> Tensor<2> {
        tensor(rng.values(rows * cols), [rows, cols], device, DType::F32)
    }

    fn bits(t: &Tensor<2>) -> TensorData {
        t.to_data()
    }

    #[test]
    fn edge_set_checks_endpoints() {
        let device = cpu();
        let set = EdgeSet::new(4, &SET_A, &device).unwrap();
        assert_eq!((set.node_count(), set.edge_count()), (4, 4));
        assert_eq!(
            set.senders()
                .to_data()
                .convert::<i64>()
                .try_to_vec::<i64>()
                .unwrap(),
            vec![0, 2, 1, 3]
        );
        assert_eq!(
            set.receivers()
                .to_data()
                .convert::<i64>()
                .try_to_vec::<i64>()
                .unwrap(),
            vec![1, 1, 2, 0]
        );
        assert_eq!(
            EdgeSet::new(3, &SET_A, &device).unwrap_err(),
            NnError::Index {
                what: "edge set endpoint",
                index: 3,
                len: 3
            }
        );
        assert_eq!(EdgeSet::new(0, &[], &device).unwrap().edge_count(), 0);
    }

    /// The sum at receivers, against sums written out by hand.
    #[test]
    fn aggregation_sums_at_receivers() {
        let device = cpu();
        let set = EdgeSet::new(4, &SET_A, &device).unwrap();
        let m = [[1.0, 2.0], [10.0, 20.0], [100.0, 200.0], [1000.0, 2000.0]];
        let messages = Tensor::<2>::from_data(m, &device);
        let sum = host(&set.aggregate(messages).unwrap());
        let want = [
            1000.0, 2000.0, // node 0 ← 3
            11.0, 22.0, // node 1 ← 0, 2
            100.0, 200.0, // node 2 ← 1
            0.0, 0.0, // node 3: no incoming edge
        ];
        assert_eq!(sum, want);
        assert!(set.aggregate(Tensor::<2>::zeros([3, 2], &device)).is_err());
    }

    /// `forward` equals the message / aggregate / update arithmetic done on the host, with
    /// the block's own MLPs applied to host-assembled rows.
    #[test]
    fn block_matches_host_reference() {
        let device = seeded(&cpu(), 5);
        // Five nodes: node 4 is no endpoint of either set, so the messages multiply the
        // rows of a subset of the nodes.
        let (n, l) = (5, 3);
        let block = GraphNetBlockConfig::new(l, 2)
            .with_hidden_layers(1)
            .init(&device)
            .unwrap();
        let mut rng = Rng::new(7);
        let x = rng.values(n * l);
        let edge_lists: [&[[u32; 2]]; 2] = [&SET_A, &SET_B];
        let e: Vec<Vec<f64>> = edge_lists
            .iter()
            .map(|list| rng.values(list.len() * l))
            .collect();
        let sets: Vec<EdgeSet> = edge_lists
            .iter()
            .map(|list| EdgeSet::new(n, list, &device).unwrap())
            .collect();
        let (nodes, edges) = block
            .forward(
                tensor(x.clone(), [n, l], &device, DType::F32),
                &[&sets[0], &sets[1]],
                e.iter()
                    .zip(edge_lists)
                    .map(|(v, list)| tensor(v.clone(), [list.len(), l], &device, DType::F32))
                    .collect(),
            )
            .unwrap();
        assert!(sets.iter().all(|s| s.endpoints.nodes.is_some()));

        let row = |v: &[f64], i: usize| v[i * l..(i + 1) * l].to_vec();
        let mut node_rows: Vec<Vec<f64>> = (0..n).map(|i| row(&x, i)).collect();
        for (k, list) in edge_lists.iter().enumerate() {
            let input: Vec<f64> = list
                .iter()
                .enumerate()
                .flat_map(|(j, &[s, r])| {
                    [row(&x, r as usize), row(&x, s as usize), row(&e[k], j)].concat()
                })
                .collect();
            let m = host(
                &block.edge_mlps[k]
                    .forward(tensor(input, [list.len(), 3 * l], &device, DType::F32))
                    .unwrap(),
            );
            let new_e: Vec<f64> = e[k].iter().zip(&m).map(|(a, b)| a + b).collect();
            assert!(
                max_diff(&host(&edges[k]), &new_e) < 1e-5,
                "edges of set {k}"
            );
            let mut agg = vec![0.0; n * l];
            for (j, &[_, r]) in list.iter().enumerate() {
                for c in 0..l {
                    agg[r as usize * l + c] += new_e[j * l + c];
                }
            }
            assert_eq!(row(&agg, 3), vec![0.0; l]);
            assert_eq!(row(&agg, 4), vec![0.0; l]);
            for (i, node_row) in node_rows.iter_mut().enumerate() {
                node_row.extend(row(&agg, i));
            }
        }
        let u = host(
            &block
                .node_mlp
                .forward(tensor(node_rows.concat(), [n, 3 * l], &device, DType::F32))
                .unwrap(),
        );
        let want: Vec<f64> = x.iter().zip(&u).map(|(a, b)| a + b).collect();
        assert!(max_diff(&host(&nodes), &want) < 1e-5);
    }

    /// The block written out as the module documentation states it: the edge MLPs on
    /// concatenated `[x_receiver, x_sender, e]` rows, the node MLP on `[x, a_1, …, a_K]`.
    fn plain_forward(
        block: &GraphNetBlock,
        nodes: Tensor<2>,
        sets: &[&EdgeSet],
        edges: Vec<Tensor<2>>,
    ) -> (Tensor<2>, Vec<Tensor<2>>) {
        let mut node_input = vec![nodes.clone()];
        let mut new_edges = Vec::new();
        for ((mlp, set), e) in block.edge_mlps.iter().zip(sets).zip(edges) {
            let input = Tensor::cat(
                vec![
                    nodes.clone().select(0, set.receivers().clone()),
                    nodes.clone().select(0, set.senders().clone()),
                    e.clone(),
                ],
                1,
            );
            let e = e + mlp.forward(input).unwrap();
            node_input.push(set.aggregate(e.clone()).unwrap());
            new_edges.push(e);
        }
        let update = block.node_mlp.forward(Tensor::cat(node_input, 1)).unwrap();
        (nodes + update, new_edges)
    }

    /// `forward` (edge MLPs' first layer split, node rows multiplied once per endpoint
    /// node) equals the plain form in values and in the gradients of the inputs and of
    /// every parameter, on sets whose endpoints are all nodes, some nodes, and none.
    #[test]
    fn fused_forward_equals_plain_form_with_gradients() {
        let device = seeded(&cpu_autodiff(), 21);
        let mut rng = Rng::new(9);
        let (n, l) = (7, 5);
        let lists: [&[[u32; 2]]; 3] = [
            &[
                [0, 1],
                [1, 2],
                [2, 3],
                [3, 4],
                [4, 5],
                [5, 6],
                [6, 0],
                [2, 0],
                [0, 2],
            ],
            // Nodes 1, 4, 5 only; node 4 receives twice.
            &[[1, 4], [5, 4], [4, 1], [4, 5]],
            &[],
        ];
        let sets: Vec<EdgeSet> = lists
            .iter()
            .map(|list| EdgeSet::new(n, list, &device).unwrap())
            .collect();
        assert!(sets[0].endpoints.nodes.is_none());
        assert!(sets[1].endpoints.nodes.is_some());
        let set_refs: Vec<&EdgeSet> = sets.iter().collect();
        let block = GraphNetBlockConfig::new(l, 3).init(&device).unwrap();
        let x = random(&mut rng, n, l, &device).require_grad();
        let e: Vec<Tensor<2>> = sets
            .iter()
            .map(|s| random(&mut rng, s.edge_count(), l, &device).require_grad())
            .collect();
        let r = random(&mut rng, n, l, &device);
        let r_e: Vec<Tensor<2>> = sets
            .iter()
            .map(|s| random(&mut rng, s.edge_count(), l, &device))
            .collect();
        let loss = |(y, out): (Tensor<2>, Vec<Tensor<2>>)| {
            let mut loss = (y * r.clone()).sum();
            for (o, w) in out.into_iter().zip(&r_e).take(2) {
                loss = loss + (o * w.clone()).sum();
            }
            loss
        };
        let fused = block.forward(x.clone(), &set_refs, e.clone()).unwrap();
        let plain = plain_forward(&block, x.clone(), &set_refs, e.clone());
        assert!(max_diff(&host(&fused.0), &host(&plain.0)) < 1e-5);
        for (a, b) in fused.1.iter().zip(&plain.1) {
            assert!(max_diff(&host(a), &host(b)) < 1e-5);
        }
        let (gf, gp) = (loss(fused).backward(), loss(plain).backward());
        let grads = |g: &Gradients| -> Vec<Vec<f64>> {
            let mut all = vec![host(&x.grad(g).unwrap())];
            all.extend(e[..2].iter().map(|t| host(&t.grad(g).unwrap())));
            let mut params = CollectGradients {
                grads: g,
                all: &mut all,
            };
            block.visit(&mut params);
            all
        };
        let (a, b) = (grads(&gf), grads(&gp));
        // x, two edge latents; 4 MLPs of 3 layers (weight, bias) and γ, β. The third
        // set's MLP (no edges) has no gradient in either form.
        assert_eq!(a.len(), 3 + 4 * (3 * 2 + 2));
        assert_eq!(a.iter().filter(|g| g.is_empty()).count(), 8);
        for (i, (a, b)) in a.iter().zip(&b).enumerate() {
            let scale = b.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            assert!(max_diff(a, b) < 1e-5 * scale, "gradient {i}");
        }
    }

    /// Every float parameter's gradient, flattened, in visiting order (empty for a
    /// parameter without one: the MLP of a set without edges).
    struct CollectGradients<'a> {
        grads: &'a Gradients,
        all: &'a mut Vec<Vec<f64>>,
    }

    impl ModuleVisitor for CollectGradients<'_> {
        fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
            let flat = param
                .val()
                .grad(self.grads)
                .map_or_else(Vec::new, |g| host(&g.reshape([-1]).unsqueeze::<2>()));
            self.all.push(flat);
        }
    }

    #[test]
    fn shapes_and_input_errors() {
        let device = cpu();
        let mut rng = Rng::new(1);
        let (n, l) = (4, 8);
        let sets = [
            EdgeSet::new(n, &SET_A, &device).unwrap(),
            EdgeSet::new(n, &SET_B, &device).unwrap(),
            EdgeSet::new(n, &[], &device).unwrap(),
        ];
        let edges = |rng: &mut Rng| -> Vec<Tensor<2>> {
            sets.iter()
                .map(|s| random(rng, s.edge_count(), l, &device))
                .collect()
        };
        let p = ProcessorConfig::new(l, 3, vec![vec![0, 1], vec![2], vec![1, 2, 0]])
            .init(&device)
            .unwrap();
        assert_eq!((p.latent(), p.edge_sets(), p.blocks.len()), (l, 3, 3));
        assert_eq!(
            p.blocks.iter().map(|b| b.edge_sets()).collect::<Vec<_>>(),
            [2, 1, 3]
        );
        assert_eq!(p.blocks[2].node_mlp.input_width(), 4 * l);
        assert_eq!(p.blocks[0].edge_mlps[0].layers.len(), 3);
        let x = random(&mut rng, n, l, &device);
        let (y, out) = p.forward(x.clone(), &sets, edges(&mut rng)).unwrap();
        assert_eq!(y.dims(), [n, l]);
        assert_eq!(
            out.iter().map(|e| e.dims()).collect::<Vec<_>>(),
            [[4, l], [3, l], [0, l]]
        );
        // Wrong widths, counts and node counts are errors, not panics.
        assert!(p
            .forward(random(&mut rng, n, l + 1, &device), &sets, edges(&mut rng))
            .is_err());
        assert!(p.forward(x.clone(), &sets[..2], edges(&mut rng)).is_err());
        let mut bad = edges(&mut rng);
        bad[1] = random(&mut rng, 2, l, &device);
        assert!(p.forward(x.clone(), &sets, bad).is_err());
        let other = [
            EdgeSet::new(5, &SET_A, &device).unwrap(),
            sets[1].clone(),
            sets[2].clone(),
        ];
        assert!(matches!(
            p.forward(x, &other, edges(&mut rng)),
            Err(NnError::NodeCount { .. })
        ));
        assert!(GraphNetBlockConfig::new(0, 1).init(&device).is_err());
        assert!(GraphNetBlockConfig::new(4, 0).init(&device).is_err());
    }

    #[test]
    fn schedule_validation_names_the_step() {
        let device = cpu();
        let err =
            |schedule: Vec<Vec<usize>>| match ProcessorConfig::new(4, 2, schedule).init(&device) {
                Err(NnError::Config(message)) => message,
                other => panic!("expected a config error, got {other:?}"),
            };
        let m = err(vec![vec![0], vec![1], vec![0, 2]]);
        assert!(m.contains("step 2") && m.contains("edge set 2"), "{m}");
        let m = err(vec![vec![0, 1], vec![]]);
        assert!(m.contains("step 1") && m.contains("no edge set"), "{m}");
        let m = err(vec![vec![1, 0, 1]]);
        assert!(m.contains("step 0") && m.contains("twice"), "{m}");
        assert!(err(vec![]).contains("at least one"));
        assert!(ProcessorConfig::new(4, 2, vec![vec![1, 0], vec![1]])
            .validate()
            .is_ok());
    }

    /// A set that a step does not read passes through it bit for bit, also between steps
    /// that do read it.
    #[test]
    fn unread_edge_sets_persist() {
        let device = cpu();
        let mut rng = Rng::new(3);
        let l = 4;
        let sets = [
            EdgeSet::new(4, &SET_A, &device).unwrap(),
            EdgeSet::new(4, &SET_B, &device).unwrap(),
        ];
        let x = random(&mut rng, 4, l, &device);
        let e = vec![
            random(&mut rng, 4, l, &device),
            random(&mut rng, 3, l, &device),
        ];
        let p = ProcessorConfig::new(l, 2, vec![vec![0], vec![0]])
            .init(&device)
            .unwrap();
        let (_, out) = p.forward(x.clone(), &sets, e.clone()).unwrap();
        assert_eq!(bits(&out[1]), bits(&e[1]));
        assert_ne!(bits(&out[0]), bits(&e[0]));

        // Steps [0, 1], [0], [0]: set 1's latents after all three are its latents after
        // the first step alone (a processor of that step's block only).
        let p = ProcessorConfig::new(l, 2, vec![vec![0, 1], vec![0], vec![0]])
            .init(&device)
            .unwrap();
        let (_, out) = p.forward(x.clone(), &sets, e.clone()).unwrap();
        let (_, first) = p.blocks[0]
            .forward(x, &[&sets[0], &sets[1]], e.clone())
            .unwrap();
        assert_eq!(bits(&out[1]), bits(&first[1]));
        assert_ne!(bits(&out[1]), bits(&e[1]));
    }

    /// Checks that every float parameter has a non-zero gradient.
    struct AllGradients<'a> {
        grads: &'a Gradients,
        seen: usize,
        without: usize,
    }

    impl ModuleVisitor for AllGradients<'_> {
        fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
            self.seen += 1;
            let nonzero = param
                .val()
                .grad(self.grads)
                .is_some_and(|g| g.abs().max().into_scalar::<f32>().is_normal());
            if !nonzero {
                self.without += 1;
            }
        }
    }

    #[test]
    fn gradients_reach_every_block() {
        let device = seeded(&cpu_autodiff(), 11);
        let mut rng = Rng::new(4);
        let l = 6;
        let sets = [
            EdgeSet::new(4, &SET_A, &device).unwrap(),
            EdgeSet::new(4, &SET_B, &device).unwrap(),
        ];
        let p = ProcessorConfig::new(l, 2, vec![vec![0, 1], vec![1], vec![0]])
            .init(&device)
            .unwrap();
        let x = random(&mut rng, 4, l, &device).require_grad();
        let e = vec![
            random(&mut rng, 4, l, &device),
            random(&mut rng, 3, l, &device),
        ];
        let (y, _) = p.forward(x.clone(), &sets, e).unwrap();
        let r = random(&mut rng, 4, l, &device);
        let grads = (y * r).sum().backward();
        assert!(x.grad(&grads).is_some());
        let mut check = AllGradients {
            grads: &grads,
            seen: 0,
            without: 0,
        };
        p.visit(&mut check);
        // Per block: (sets + 1) MLPs of 3 linear layers (weight, bias) and γ, β.
        assert_eq!(check.seen, (3 + 2 + 2) * 8);
        assert_eq!(check.without, 0, "parameters without a gradient");
    }
}
