//! `weft bench gat`: one GAT layer (the building block of every M^mp submodule) on a
//! skirt's mesh graph: forward on the inference device and forward + backward on the
//! autodiff device (gradients of the input, `W` and both attention vectors), weft-nn's
//! fused CSR kernel against burn's generic tensor path, so that each optimisation of
//! the kernel is measured against the reference it must equal.

use burn::tensor::{Device, Distribution, Tensor};
use serde::Serialize;
use weft_body::BodyModel;
use weft_nn::backend::{cpu, cpu_autodiff};
use weft_nn::{AttentionImpl, GatBlock, GatBlockConfig, GraphBatch};

use crate::timing::try_median_ms;
use crate::{skirt, BenchError, Row};

/// What to measure.
#[derive(Clone, Debug)]
pub struct GatBench {
    /// Vertices of the skirt whose mesh graph the layer runs on.
    pub vertices: usize,
    /// Input channels.
    pub input: usize,
    /// Attention heads (concatenated).
    pub heads: usize,
    /// Output channels per head.
    pub channels: usize,
    /// Timed runs per figure.
    pub reps: usize,
}

/// What one implementation cost.
#[derive(Clone, Debug, Serialize)]
pub struct GatFigures {
    /// `"gat"`.
    pub bench: &'static str,
    /// `fused` or `reference`.
    pub implementation: &'static str,
    /// Nodes of the graph.
    pub vertices: usize,
    /// Directed edges (self-loops included) the attention runs over.
    pub edges: usize,
    /// Input channels.
    pub input: usize,
    /// Heads.
    pub heads: usize,
    /// Channels per head.
    pub channels: usize,
    /// Threads of the pool.
    pub threads: usize,
    /// Forward, ms.
    pub forward_ms: f64,
    /// Forward and backward, ms.
    pub forward_backward_ms: f64,
}

impl GatBench {
    /// Runs the bench on a skirt fitted to `body`: one result per implementation.
    pub fn run(
        &self,
        body: &BodyModel,
        progress: &mut dyn FnMut(&str),
    ) -> Result<Vec<GatFigures>, BenchError> {
        for (what, value) in [
            ("--input", self.input),
            ("--heads", self.heads),
            ("--channels", self.channels),
        ] {
            if !(1..=4096).contains(&value) {
                return Err(BenchError::Option {
                    what,
                    message: format!("{value}; expected 1 to 4096"),
                });
            }
        }
        progress("garment");
        let garment = skirt(body, self.vertices)?;
        let batch = GraphBatch::single(&garment.graph());
        let adjacency = batch.adjacency().clone();
        let n = batch.node_count();
        let mut out = Vec::new();
        for (implementation, name) in [
            (AttentionImpl::Auto, "fused"),
            (AttentionImpl::Reference, "reference"),
        ] {
            progress(name);
            let device = cpu();
            let block = self.layer(&device, implementation)?;
            let x = Tensor::<2>::random([n, self.input], Distribution::Normal(0.0, 1.0), &device);
            let forward_ms = try_median_ms(self.reps, || {
                block.forward(x.clone(), &adjacency).map(|y| {
                    let _ = y.into_data();
                })
            })
            .map_err(BenchError::stage("GAT layer"))?;
            let device = cpu_autodiff();
            let block = self.layer(&device, implementation)?;
            let x = Tensor::<2>::random([n, self.input], Distribution::Normal(0.0, 1.0), &device)
                .require_grad();
            let forward_backward_ms = try_median_ms(self.reps, || {
                block.forward(x.clone(), &adjacency).map(|y| {
                    let _ = y.sum().backward();
                })
            })
            .map_err(BenchError::stage("GAT layer"))?;
            out.push(GatFigures {
                bench: "gat",
                implementation: name,
                vertices: n,
                edges: adjacency.entry_count(),
                input: self.input,
                heads: self.heads,
                channels: self.channels,
                threads: rayon::current_num_threads(),
                forward_ms,
                forward_backward_ms,
            });
        }
        Ok(out)
    }

    fn layer(
        &self,
        device: &Device,
        implementation: AttentionImpl,
    ) -> Result<GatBlock, BenchError> {
        device.seed(1);
        Ok(GatBlockConfig::new(self.input, self.channels)
            .with_heads(self.heads)
            .init(device)
            .map_err(BenchError::stage("GAT layer"))?
            .with_implementation(implementation))
    }
}

impl Row for GatFigures {
    fn cells(&self) -> Vec<(&'static str, String)> {
        vec![
            ("implementation", self.implementation.to_string()),
            ("N", self.vertices.to_string()),
            ("edges", self.edges.to_string()),
            (
                "layer",
                format!("{} → {}×{}", self.input, self.heads, self.channels),
            ),
            ("forward ms", format!("{:.2}", self.forward_ms)),
            (
                "forward+backward ms",
                format!("{:.2}", self.forward_backward_ms),
            ),
        ]
    }
}
