//! `weft bench densegats`: one frame of DenseGATs on a character of about `vertices`
//! vertices (the benchmark skirt bound to the default body, as `weft animate --character`
//! binds any mesh), per stage: the pose inputs (coarse LBS, normals, features), the
//! input transform, each dense module with its transition, the output transform, and
//! the whole frame; beside the dense-layer floor, the multiply–adds of every linear map
//! (`W`, the self stream, the MLPs) at the rate this CPU's GEMM reaches. The stages are
//! those of the inference form evaluation and animation run ([`DenseGatsInference`]);
//! the network's reference forward (burn layers, as training runs them) is timed whole
//! beside them.
//!
//! The thesis reports about 31 ms per frame on a GPU for a 10 220-vertex character
//! (§3.2.3.2); the target here is 50 ms on two CPU cores at paper widths.

use serde::Serialize;
use weft_body::BodyModel;
use weft_models::densegats::{DenseGats, DenseGatsConfig, DenseGatsInference};
use weft_models::refine::RefineConfig;
use weft_nn::backend::cpu;

use crate::refine::Setup;
use crate::timing::try_median_ms;
use crate::{BenchError, Row};

/// The GEMM rate the floor assumes, GFLOP/s: what burn's flex GEMM reached on this
/// machine's two AVX-512 cores (docs/benchmarks.md, `weft bench multilevel`).
pub const GEMM_GFLOPS: f64 = 300.0;

/// What to measure.
#[derive(Clone, Debug)]
pub struct DenseGatsBench {
    /// Model preset: cpu or paper.
    pub preset: String,
    /// Vertices of the character.
    pub vertices: usize,
    /// Timed runs per figure.
    pub reps: usize,
}

/// One frame, per stage, ms.
#[derive(Clone, Debug, Serialize)]
pub struct DenseGatsFigures {
    /// `"densegats"`.
    pub bench: &'static str,
    /// The preset.
    pub preset: String,
    /// Vertices of the character.
    pub vertices: usize,
    /// Threads of the pool.
    pub threads: usize,
    /// Parameters of the network.
    pub parameters: usize,
    /// Coarse LBS, normals and node features (host).
    pub inputs_ms: f64,
    /// Input transform.
    pub input_mlp_ms: f64,
    /// Each dense module, with the transition block before it.
    pub modules_ms: Vec<f64>,
    /// Output transform.
    pub output_mlp_ms: f64,
    /// The network alone.
    pub network_ms: f64,
    /// The network alone, by its reference forward (burn layers).
    pub reference_ms: f64,
    /// Inputs and network: one frame.
    pub frame_ms: f64,
    /// Multiply–adds of the linear maps at [`GEMM_GFLOPS`], ms.
    pub floor_ms: f64,
}

impl Row for DenseGatsFigures {
    fn cells(&self) -> Vec<(&'static str, String)> {
        vec![
            ("preset", self.preset.clone()),
            ("N", self.vertices.to_string()),
            ("params", self.parameters.to_string()),
            ("inputs", format!("{:.1}", self.inputs_ms)),
            ("in MLP", format!("{:.1}", self.input_mlp_ms)),
            (
                "modules",
                self.modules_ms
                    .iter()
                    .map(|m| format!("{m:.1}"))
                    .collect::<Vec<_>>()
                    .join(" + "),
            ),
            ("out MLP", format!("{:.1}", self.output_mlp_ms)),
            ("network", format!("{:.1}", self.network_ms)),
            ("reference", format!("{:.1}", self.reference_ms)),
            ("frame ms", format!("{:.1}", self.frame_ms)),
            ("floor ms", format!("{:.1}", self.floor_ms)),
        ]
    }
}

/// Multiply–adds per node of the network's linear maps, times 2.
fn flops_per_node(cfg: &DenseGatsConfig, net: &DenseGats) -> f64 {
    let mut f = 0.0;
    let mut d = 6 + cfg.joints;
    for &w in &cfg.input_widths {
        f += (d * w) as f64;
        d = w;
    }
    for t in &net.transitions {
        f += (t.input_width() * t.output_width()) as f64;
    }
    for m in &net.modules {
        for b in &m.blocks {
            f += (b.input_width() * b.output_width()) as f64;
        }
        d = m.output_width();
    }
    for &w in &cfg.output_widths {
        f += (d * w) as f64;
        d = w;
    }
    2.0 * (f + (d * 3) as f64)
}

impl DenseGatsBench {
    /// Runs the bench on a character bound to `body`.
    pub fn run(
        &self,
        body: &BodyModel,
        progress: &mut dyn FnMut(&str),
    ) -> Result<DenseGatsFigures, BenchError> {
        let cfg = DenseGatsConfig::preset(&self.preset).map_err(|e| BenchError::Option {
            what: "--preset",
            message: e.to_string(),
        })?;
        progress("character");
        let setup = Setup::new(body, self.vertices, cfg.influences, cfg.inputs(), self.reps)?;
        let device = cpu();
        let net = cfg
            .init(&device)
            .map_err(BenchError::stage("the network"))?;
        let (x, reps) = (&setup.x, self.reps);
        let adjacency = setup.character.batch().adjacency();
        progress("network");
        let fast: DenseGatsInference = net.inference();
        let input_mlp_ms = try_median_ms(reps, || fast.input.forward(x).map(drop))
            .map_err(BenchError::stage("input transform"))?;
        let mut h = fast
            .input
            .forward(x)
            .map_err(BenchError::stage("input transform"))?;
        let mut modules_ms = Vec::new();
        for k in 0..fast.modules.len() {
            modules_ms.push(
                try_median_ms(reps, || fast.module(k, &h, adjacency).map(drop))
                    .map_err(BenchError::stage("dense module"))?,
            );
            h = fast
                .module(k, &h, adjacency)
                .map_err(BenchError::stage("dense module"))?;
        }
        let output_mlp_ms = try_median_ms(reps, || fast.output(&h).map(drop))
            .map_err(BenchError::stage("output transform"))?;
        let network_ms = try_median_ms(reps, || fast.forward_features(x, adjacency).map(drop))
            .map_err(BenchError::stage("network"))?;
        let (reference_ms, frame_ms) = setup.whole_ms(reps, &net, &fast, &device)?;
        let n = setup.character.vertex_count();
        let parameters = burn::module::Module::num_params(&net);
        Ok(DenseGatsFigures {
            bench: "densegats",
            preset: self.preset.clone(),
            vertices: n,
            threads: rayon::current_num_threads(),
            parameters,
            inputs_ms: setup.inputs_ms,
            input_mlp_ms,
            modules_ms,
            output_mlp_ms,
            network_ms,
            reference_ms,
            frame_ms,
            floor_ms: flops_per_node(&cfg, &net) * n as f64 / (GEMM_GFLOPS * 1e6),
        })
    }
}
