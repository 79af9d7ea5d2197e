//! HOOD's four normalisers (hood-reference §1.3): node, mesh-edge and body-edge features,
//! and the acceleration the decoder's output is scaled back by.
//!
//! HOOD accumulates them online during its first iterations, from the skinned garment
//! its samples start from; the output's from the skinned garment's accelerations. weft
//! fits them the same way, on skinned states of the training samples, before the first
//! step ([`HoodStatsFit`]), and keeps them in the run directory (`hood.json`) so a
//! resumed run and inference read the very statistics training used. The material
//! columns stay raw, as in HOOD (their [0, 1] scale is the input's meaning).

use std::path::Path;

use serde::{Deserialize, Serialize};
use weft_nn::{FeatureNormalizer, NormalizerFit};

use super::config::widths;
use super::features::StepGraph;
use crate::error::ModelError;
use crate::run::read_json;

/// The statistics file of a HOOD run.
pub const STATS_FILE: &str = "hood.json";

/// HOOD's normalisers; see the module documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HoodStats {
    /// Node features.
    pub node: FeatureNormalizer,
    /// Mesh-edge features (every level).
    pub mesh: FeatureNormalizer,
    /// Body-edge features (both directions).
    pub body: FeatureNormalizer,
    /// Accelerations (m per frame²): the decoder predicts them normalised.
    pub output: FeatureNormalizer,
}

/// The streaming fit of [`HoodStats`].
#[derive(Clone, Debug)]
pub struct HoodStatsFit {
    node: NormalizerFit,
    mesh: NormalizerFit,
    body: NormalizerFit,
    output: NormalizerFit,
}

/// `n` with its last `raw` columns left as they are (mean 0, std 1).
fn keep_raw(mut n: FeatureNormalizer, raw: usize) -> FeatureNormalizer {
    let w = n.mean.len();
    for k in w.saturating_sub(raw)..w {
        n.mean[k] = 0.0;
        n.std[k] = 1.0;
    }
    n
}

/// `n` with its means at zero (scale only): the decoder's zero is then "coast", and an
/// untrained or uncertain network adds nothing. The fitted mean of the first steps from
/// a skinned start is a sag of 4 mm per frame² downward (0.4 g), which an undertrained
/// network returns everywhere and every frame: its garments fell off the body.
fn centred_at_zero(mut n: FeatureNormalizer) -> FeatureNormalizer {
    n.mean.iter_mut().for_each(|m| *m = 0.0);
    n
}

impl HoodStatsFit {
    /// An empty fit for a hierarchy of `levels` levels.
    pub fn new(levels: usize) -> Result<Self, ModelError> {
        Ok(HoodStatsFit {
            node: NormalizerFit::new(StepGraph::node_width(levels))?,
            mesh: NormalizerFit::new(StepGraph::MESH_WIDTH)?,
            body: NormalizerFit::new(StepGraph::BODY_WIDTH)?,
            output: NormalizerFit::new(3)?,
        })
    }

    /// Adds one step's inputs and the acceleration of the skinned garment over it
    /// (`x_{t+1} − 2x_t + x_{t−1}`, free vertices only), flattened.
    pub fn observe(&mut self, graph: &StepGraph, acceleration: &[f32]) -> Result<(), ModelError> {
        self.node.observe(&graph.nodes)?;
        for (_, feats) in &graph.mesh {
            self.mesh.observe(feats)?;
        }
        self.body.observe(&graph.body.1)?;
        self.output.observe(acceleration)?;
        Ok(())
    }

    /// The normalisers; errors when nothing was observed.
    pub fn finish(&self) -> Result<HoodStats, ModelError> {
        // No body edge at all (a garment far from the body in every sample) leaves the
        // body normaliser unfitted: it then passes the features through.
        let body = if self.body.rows() == 0 {
            FeatureNormalizer {
                mean: vec![0.0; StepGraph::BODY_WIDTH],
                std: vec![1.0; StepGraph::BODY_WIDTH],
            }
        } else {
            self.body.finish()?
        };
        Ok(HoodStats {
            node: keep_raw(self.node.finish()?, widths::MATERIAL),
            mesh: keep_raw(self.mesh.finish()?, widths::MATERIAL),
            body,
            output: centred_at_zero(self.output.finish()?),
        })
    }
}

impl HoodStats {
    /// Normalisers that change nothing, for a hierarchy of `levels` levels: where only
    /// the cost of a step matters (benchmarks, timing, tests), not its statistics.
    pub fn identity(levels: usize) -> Self {
        let n = |w: usize| FeatureNormalizer {
            mean: vec![0.0; w],
            std: vec![1.0; w],
        };
        HoodStats {
            node: n(StepGraph::node_width(levels)),
            mesh: n(StepGraph::MESH_WIDTH),
            body: n(StepGraph::BODY_WIDTH),
            output: n(3),
        }
    }

    /// Reads `dir/hood.json`; errors name the file.
    pub fn read(dir: &Path) -> Result<Self, ModelError> {
        let path = dir.join(STATS_FILE);
        let stats: HoodStats = read_json(&path, "HOOD's normalisers")?;
        for n in [&stats.node, &stats.mesh, &stats.body, &stats.output] {
            n.validate().map_err(|e| ModelError::Run {
                path: path.clone(),
                message: e.to_string(),
            })?;
        }
        Ok(stats)
    }

    /// The hierarchy levels the node normaliser was fitted for.
    pub fn levels(&self) -> usize {
        self.node
            .mean
            .len()
            .saturating_sub(StepGraph::node_width(0))
    }
}
