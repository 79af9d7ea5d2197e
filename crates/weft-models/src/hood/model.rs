//! HOOD's network (seed 004 §3): encoders for nodes, the mesh edges of every level and
//! the body edges; the multi-level processor (weft-nn's [`Processor`]); a decoder to the
//! garment's acceleration. Encode–process–decode as in MeshGraphNets.
//!
//! [`HoodInput`] turns one or several [`StepGraph`]s into tensors: several garments or
//! sequences become one disjoint graph, so a batch advances in one forward pass (HOOD's
//! code runs batch size 1).

use burn::module::Module;
use burn::tensor::{Device, Int, Tensor, TensorData};
use weft_nn::{EdgeSet, Mlp, Processor};

use super::features::StepGraph;
use super::stats::HoodStats;
use crate::error::ModelError;

/// HOOD's trainable parts; see the module documentation.
#[derive(Module, Debug)]
pub struct Hood {
    /// Node encoder (garment and body nodes share it, as in HOOD).
    pub node_encoder: Mlp,
    /// One edge encoder per mesh level.
    pub mesh_encoders: Vec<Mlp>,
    /// The body-edge encoder (both directions).
    pub body_encoder: Mlp,
    /// Message passing over the levels' edge sets and the body edges, by schedule.
    pub processor: Processor,
    /// Garment node latents to the normalised acceleration.
    pub decoder: Mlp,
    /// Mesh levels (the edge sets before the body's).
    #[module(skip)]
    pub levels: usize,
}

/// One forward pass's inputs as tensors (one or several steps as a disjoint graph).
#[derive(Clone, Debug)]
pub struct HoodInput {
    nodes: Tensor<2>,
    sets: Vec<EdgeSet>,
    edges: Vec<Tensor<2>>,
    garment_rows: Tensor<1, Int>,
    /// Garment vertices of each graph, in order (the output's rows split by these).
    pub garment_counts: Vec<usize>,
}

fn tensor(rows: Vec<f32>, width: usize, device: &Device) -> Tensor<2> {
    let n = rows.len() / width;
    Tensor::from_data(TensorData::new(rows, [n, width]), device)
}

impl HoodInput {
    /// The normalised inputs of `graphs` as one disjoint graph on `device`.
    pub fn new(
        graphs: &[&StepGraph],
        stats: &HoodStats,
        device: &Device,
    ) -> Result<Self, ModelError> {
        let levels = graphs.first().map_or(0, |g| g.mesh.len());
        if graphs.is_empty() || graphs.iter().any(|g| g.mesh.len() != levels) {
            return Err(ModelError::Config(
                "a HOOD batch needs at least one step graph, all with the same levels".into(),
            ));
        }
        let node_width = StepGraph::node_width(levels);
        let mut nodes = Vec::new();
        let mut mesh: Vec<(Vec<[u32; 2]>, Vec<f32>)> = vec![(Vec::new(), Vec::new()); levels];
        let mut body: (Vec<[u32; 2]>, Vec<f32>) = (Vec::new(), Vec::new());
        let mut garment_rows = Vec::new();
        let mut offset = 0u32;
        let shift = |edges: &[[u32; 2]], offset: u32| -> Vec<[u32; 2]> {
            edges
                .iter()
                .map(|&[a, b]| [a + offset, b + offset])
                .collect()
        };
        for g in graphs {
            nodes.extend_from_slice(&g.nodes);
            garment_rows.extend((0..g.garment_nodes as u32).map(|i| (i + offset) as i64));
            for (l, (edges, feats)) in g.mesh.iter().enumerate() {
                mesh[l].0.extend(shift(edges, offset));
                mesh[l].1.extend_from_slice(feats);
            }
            body.0.extend(shift(&g.body.0, offset));
            body.1.extend_from_slice(&g.body.1);
            offset += g.node_count() as u32;
        }
        let count = offset as usize;
        stats.node.apply(&mut nodes)?;
        let mut sets = Vec::with_capacity(levels + 1);
        let mut edges = Vec::with_capacity(levels + 1);
        for (list, mut feats) in mesh {
            stats.mesh.apply(&mut feats)?;
            sets.push(EdgeSet::new(count, &list, device)?);
            edges.push(tensor(feats, StepGraph::MESH_WIDTH, device));
        }
        let (list, mut feats) = body;
        stats.body.apply(&mut feats)?;
        sets.push(EdgeSet::new(count, &list, device)?);
        edges.push(tensor(feats, StepGraph::BODY_WIDTH, device));
        let rows = garment_rows.len();
        Ok(HoodInput {
            nodes: tensor(nodes, node_width, device),
            sets,
            edges,
            garment_rows: Tensor::from_data(TensorData::new(garment_rows, [rows]), device),
            garment_counts: graphs.iter().map(|g| g.garment_nodes).collect(),
        })
    }
}

impl Hood {
    /// The garment nodes' normalised accelerations, `[Σ garment vertices, 3]`, in the
    /// order of the input's graphs.
    pub fn forward(&self, input: HoodInput) -> Result<Tensor<2>, ModelError> {
        if input.sets.len() != self.levels + 1 {
            return Err(ModelError::mismatch(
                "HOOD edge sets",
                format!("{} mesh levels and the body's", self.levels),
                input.sets.len(),
            ));
        }
        let nodes = self.node_encoder.forward(input.nodes)?;
        let mut edges = input.edges;
        let body = edges
            .pop()
            .map(|e| self.body_encoder.forward(e))
            .transpose()?;
        let mut latents = edges
            .into_iter()
            .zip(&self.mesh_encoders)
            .map(|(e, encoder)| encoder.forward(e))
            .collect::<Result<Vec<_>, _>>()?;
        latents.extend(body);
        let (nodes, _) = self.processor.forward(nodes, &input.sets, latents)?;
        Ok(self.decoder.forward(nodes.select(0, input.garment_rows))?)
    }
}
