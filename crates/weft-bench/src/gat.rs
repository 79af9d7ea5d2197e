//! `weft bench gat`: one GAT layer (the building block of every M^mp submodule) on a
//! skirt's mesh graph: forward on the inference device and forward + backward on the
//! autodiff device (gradients of the input, `W` and both attention vectors), weft-nn's
//! fused CSR kernel against burn's generic tensor path, so that each optimisation of
//! the kernel is measured against the reference it must equal. On `device` = wgpu (the
//! `wgpu` feature) only the generic path runs: the fused kernel is flex's alone. Each
//! timed run waits for the device before the clock is read.

use burn::tensor::{Device, Distribution, Tensor};
use serde::Serialize;
use weft_body::BodyModel;
use weft_nn::{AttentionImpl, GatBlock, GatBlockConfig, GraphBatch};

use crate::device::wait;
use crate::timing::try_median_ms;
use crate::{skirt, BenchDevice, BenchError, Row};

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
    /// The device the layer runs on.
    pub device: BenchDevice,
}

/// What one implementation cost.
#[derive(Clone, Debug, Serialize)]
pub struct GatFigures {
    /// `"gat"`.
    pub bench: &'static str,
    /// The device: `cpu` (flex) or `wgpu`.
    pub device: BenchDevice,
    /// The GPU adapter's name, as its runtime reports it; absent on the CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
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
        self.device.check()?;
        progress("garment");
        let garment = skirt(body, self.vertices)?;
        let batch = GraphBatch::single(&garment.graph());
        let adjacency = batch.adjacency().clone();
        let n = batch.node_count();
        let mut out = Vec::new();
        let implementations: &[(AttentionImpl, &'static str)] = match self.device {
            BenchDevice::Cpu => &[
                (AttentionImpl::Auto, "fused"),
                (AttentionImpl::Reference, "reference"),
            ],
            BenchDevice::Wgpu => &[(AttentionImpl::Reference, "reference")],
        };
        for &(implementation, name) in implementations {
            progress(name);
            let device = self.device.inference()?;
            let block = self.layer(&device, implementation)?;
            let x = Tensor::<2>::random([n, self.input], Distribution::Normal(0.0, 1.0), &device);
            let forward_ms = try_median_ms(self.reps, || {
                let y = block
                    .forward(x.clone(), &adjacency)
                    .map_err(BenchError::stage("GAT layer"))?;
                y.try_into_data()
                    .map(drop)
                    .map_err(|e| BenchError::Device(format!("{e:?}")))
            })?;
            let device = self.device.autodiff()?;
            let block = self.layer(&device, implementation)?;
            let x = Tensor::<2>::random([n, self.input], Distribution::Normal(0.0, 1.0), &device)
                .require_grad();
            let forward_backward_ms = try_median_ms(self.reps, || {
                let y = block
                    .forward(x.clone(), &adjacency)
                    .map_err(BenchError::stage("GAT layer"))?;
                let grads = y.sum().backward();
                wait(&device)?;
                drop(grads);
                Ok::<_, BenchError>(())
            })?;
            out.push(GatFigures {
                bench: "gat",
                device: self.device,
                adapter: weft_nn::backend::adapter_name(&device),
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
            ("device", crate::device::label(self.device, &self.adapter)),
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
