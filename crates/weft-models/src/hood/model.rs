//! HOOD's network (seed 004 §3): encoders for nodes, the mesh edges of every level and
//! the body edges; the multi-level processor (weft-nn's [`Processor`]); a decoder to the
//! garment's acceleration. Encode–process–decode as in MeshGraphNets.
//!
//! [`HoodBatch`] turns one or several [`StepGraph`]s into one disjoint graph's normalised
//! inputs, so a batch of garments or sequences advances in one forward pass (HOOD's code
//! runs batch size 1); [`HoodInput`] puts them in tensors for training. Rollouts run
//! [`InferHood`], the same network in weft-nn's inference forms: a forward pass with no
//! autodiff graph to keep, about twice as fast (docs/hood.md, "Speed").

use burn::module::Module;
use burn::tensor::{Device, Int, Tensor, TensorData};
use weft_nn::infer::{Features, InferEdgeSet, InferMlp, InferProcessor};
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

/// One forward pass's inputs on the host, normalised (one or several steps as a disjoint
/// graph): what [`HoodInput`] puts in tensors for training, and what [`InferHood`] reads
/// as it is.
#[derive(Clone, Debug)]
pub struct HoodBatch {
    /// Node features, `[nodes, node_width]` row-major.
    nodes: Vec<f32>,
    node_width: usize,
    /// Per edge set (the mesh levels, then the body's): its `[sender, receiver]` pairs and
    /// their features, row-major, [`set_width`] wide.
    sets: Vec<(Vec<[u32; 2]>, Vec<f32>)>,
    /// Rows of the garment nodes, in order.
    garment_rows: Vec<u32>,
    /// Nodes of the disjoint graph.
    node_count: usize,
    /// Garment vertices of each graph, in order (the output's rows split by these).
    pub garment_counts: Vec<usize>,
}

/// Width of edge set `k`'s features in a graph of `levels` mesh levels.
fn set_width(k: usize, levels: usize) -> usize {
    if k < levels {
        StepGraph::MESH_WIDTH
    } else {
        StepGraph::BODY_WIDTH
    }
}

impl HoodBatch {
    /// The normalised inputs of `graphs` as one disjoint graph.
    pub fn new(graphs: &[&StepGraph], stats: &HoodStats) -> Result<Self, ModelError> {
        let levels = graphs.first().map_or(0, |g| g.mesh.len());
        if graphs.is_empty() || graphs.iter().any(|g| g.mesh.len() != levels) {
            return Err(ModelError::Config(
                "a HOOD batch needs at least one step graph, all with the same levels".into(),
            ));
        }
        let mut nodes = Vec::new();
        let mut sets: Vec<(Vec<[u32; 2]>, Vec<f32>)> = vec![(Vec::new(), Vec::new()); levels + 1];
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
            garment_rows.extend((0..g.garment_nodes as u32).map(|i| i + offset));
            for (set, (edges, feats)) in sets.iter_mut().zip(g.mesh.iter().chain([&g.body])) {
                set.0.extend(shift(edges, offset));
                set.1.extend_from_slice(feats);
            }
            offset += g.node_count() as u32;
        }
        stats.node.apply(&mut nodes)?;
        for (k, (_, feats)) in sets.iter_mut().enumerate() {
            match k < levels {
                true => stats.mesh.apply(feats)?,
                false => stats.body.apply(feats)?,
            }
        }
        Ok(HoodBatch {
            nodes,
            node_width: StepGraph::node_width(levels),
            sets,
            garment_rows,
            node_count: offset as usize,
            garment_counts: graphs.iter().map(|g| g.garment_nodes).collect(),
        })
    }

    /// Mesh levels.
    fn levels(&self) -> usize {
        self.sets.len() - 1
    }
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
        let batch = HoodBatch::new(graphs, stats)?;
        let levels = batch.levels();
        let mut sets = Vec::with_capacity(levels + 1);
        let mut edges = Vec::with_capacity(levels + 1);
        for (k, (list, feats)) in batch.sets.into_iter().enumerate() {
            sets.push(EdgeSet::new(batch.node_count, &list, device)?);
            edges.push(tensor(feats, set_width(k, levels), device));
        }
        let rows: Vec<i64> = batch.garment_rows.iter().map(|&r| i64::from(r)).collect();
        let count = rows.len();
        Ok(HoodInput {
            nodes: tensor(batch.nodes, batch.node_width, device),
            sets,
            edges,
            garment_rows: Tensor::from_data(TensorData::new(rows, [count]), device),
            garment_counts: batch.garment_counts,
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

/// [`Hood`] for inference (rollouts): every part's inference form (weft-nn's `infer`),
/// equal to [`Hood::forward`] up to float rounding.
#[derive(Clone, Debug)]
pub struct InferHood {
    node_encoder: InferMlp,
    mesh_encoders: Vec<InferMlp>,
    body_encoder: InferMlp,
    processor: InferProcessor,
    decoder: InferMlp,
    levels: usize,
}

impl From<&Hood> for InferHood {
    fn from(hood: &Hood) -> Self {
        InferHood {
            node_encoder: InferMlp::from(&hood.node_encoder),
            mesh_encoders: hood.mesh_encoders.iter().map(InferMlp::from).collect(),
            body_encoder: InferMlp::from(&hood.body_encoder),
            processor: InferProcessor::from(&hood.processor),
            decoder: InferMlp::from(&hood.decoder),
            levels: hood.levels,
        }
    }
}

impl InferHood {
    /// As [`Hood::forward`]: the garment nodes' normalised accelerations, `[Σ garment
    /// vertices, 3]` row-major, in the order of the batch's graphs.
    pub fn forward(&self, batch: &HoodBatch) -> Result<Vec<f32>, ModelError> {
        if batch.levels() != self.levels {
            return Err(ModelError::mismatch(
                "HOOD edge sets",
                format!("{} mesh levels and the body's", self.levels),
                batch.sets.len(),
            ));
        }
        let features = |values: &[f32], width: usize| Features::new(values.to_vec(), width);
        let mut nodes = self
            .node_encoder
            .forward(&features(&batch.nodes, batch.node_width)?)?;
        let mut sets = Vec::with_capacity(batch.sets.len());
        let mut edges = Vec::with_capacity(batch.sets.len());
        let encoders = self.mesh_encoders.iter().chain([&self.body_encoder]);
        for (k, ((list, feats), encoder)) in batch.sets.iter().zip(encoders).enumerate() {
            sets.push(InferEdgeSet::new(batch.node_count, list)?);
            edges.push(encoder.forward(&features(feats, set_width(k, self.levels))?)?);
        }
        self.processor.forward(&mut nodes, &sets, &mut edges)?;
        let latent = self.processor.latent();
        let mut garment = Vec::with_capacity(batch.garment_rows.len() * latent);
        for &r in &batch.garment_rows {
            let r = r as usize;
            garment.extend_from_slice(&nodes.values()[r * latent..(r + 1) * latent]);
        }
        let out = self.decoder.forward(&Features::new(garment, latent)?)?;
        Ok(out.into_values())
    }
}

#[cfg(test)]
mod tests {
    use weft_sim::{Attachment, Material};

    use super::*;
    use crate::hood::testutil::{body_and_skirt, clip, still};
    use crate::hood::{HoodConfig, Materials, Scene, StepAt};

    /// The inference form equals the burn forward on a batch of two step graphs of a
    /// skirt touching the body (mesh levels and body edges all in use).
    #[test]
    fn inference_form_equals_the_forward() {
        let (body, skirt) = body_and_skirt(320);
        let (poses, trans) = still(4);
        let clip = clip(&poses, &trans);
        let device = weft_nn::backend::cpu();
        let config = HoodConfig::preset("cpu").unwrap();
        let hood = Materials::Uniform(Material::hood());
        let scene =
            Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &config).unwrap();
        let start = scene.start(1, false).unwrap();
        let at = StepAt {
            t: 1,
            settle: false,
            dt: scene.dt,
            buttoned: true,
        };
        let (graph, _) = scene.step(start.as_ref(), at, &config).unwrap();
        assert!(!graph.body.0.is_empty(), "the skirt touches the body");
        let model = config.init(&device).unwrap();
        let stats = HoodStats::identity(config.levels);
        let graphs = [&graph, &graph];
        let want: Vec<f32> = model
            .forward(HoodInput::new(&graphs, &stats, &device).unwrap())
            .unwrap()
            .into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .unwrap();
        let got = InferHood::from(&model)
            .forward(&HoodBatch::new(&graphs, &stats).unwrap())
            .unwrap();
        assert_eq!(got.len(), 2 * 3 * graph.garment_nodes);
        let scale = want.iter().fold(1.0f32, |m, v| m.max(v.abs()));
        let diff = got
            .iter()
            .zip(&want)
            .fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-4 * scale, "{diff} (scale {scale})");
    }
}
