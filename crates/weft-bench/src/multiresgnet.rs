//! `weft bench multiresgnet`: one frame of MultiResGNet on the character of `weft bench
//! densegats` (the benchmark skirt bound to the default body), per stage of the
//! inference form evaluation and animation run ([`MultiResGnetInference`]): the pose
//! inputs (coarse LBS, the relative skinning descriptor, normals), the input transform,
//! the local branch, the global branch (pooling, blocks on the pooled graph, unpooling,
//! `f_GATB`), the output transform, and the whole frame; the reference forward (burn
//! layers, as training runs them) is timed whole beside them. The target: no
//! slower than 1.5× DenseGATs at the same widths' preset and size.

use serde::Serialize;
use weft_body::BodyModel;
use weft_models::multiresgnet::{MultiResGnetConfig, MultiResGnetInference};
use weft_models::refine::RefineConfig;
use weft_nn::backend::cpu;

use crate::refine::Setup;
use crate::timing::try_median_ms;
use crate::{BenchError, Row};

/// What to measure.
#[derive(Clone, Debug)]
pub struct MultiResGnetBench {
    /// Model preset: cpu or paper.
    pub preset: String,
    /// Vertices of the character.
    pub vertices: usize,
    /// Timed runs per figure.
    pub reps: usize,
}

/// One frame, per stage, ms.
#[derive(Clone, Debug, Serialize)]
pub struct MultiResGnetFigures {
    /// `"multiresgnet"`.
    pub bench: &'static str,
    /// The preset.
    pub preset: String,
    /// Vertices of the character.
    pub vertices: usize,
    /// Threads of the pool.
    pub threads: usize,
    /// Parameters of the network.
    pub parameters: usize,
    /// Coarse LBS, descriptor, normals and node features (host).
    pub inputs_ms: f64,
    /// Input transform.
    pub input_mlp_ms: f64,
    /// The local branch's dense module.
    pub local_ms: f64,
    /// The global branch, pooling to `f_GATB` (0 without it).
    pub global_ms: f64,
    /// Output transform.
    pub output_mlp_ms: f64,
    /// The network alone.
    pub network_ms: f64,
    /// The network alone, by its reference forward (burn layers).
    pub reference_ms: f64,
    /// Inputs and network: one frame.
    pub frame_ms: f64,
}

impl Row for MultiResGnetFigures {
    fn cells(&self) -> Vec<(&'static str, String)> {
        vec![
            ("preset", self.preset.clone()),
            ("N", self.vertices.to_string()),
            ("params", self.parameters.to_string()),
            ("inputs", format!("{:.1}", self.inputs_ms)),
            ("in MLP", format!("{:.1}", self.input_mlp_ms)),
            ("local", format!("{:.1}", self.local_ms)),
            ("global", format!("{:.1}", self.global_ms)),
            ("out MLP", format!("{:.1}", self.output_mlp_ms)),
            ("network", format!("{:.1}", self.network_ms)),
            ("reference", format!("{:.1}", self.reference_ms)),
            ("frame ms", format!("{:.1}", self.frame_ms)),
        ]
    }
}

impl MultiResGnetBench {
    /// Runs the bench on a character bound to `body`.
    pub fn run(
        &self,
        body: &BodyModel,
        progress: &mut dyn FnMut(&str),
    ) -> Result<MultiResGnetFigures, BenchError> {
        let cfg = MultiResGnetConfig::preset(&self.preset).map_err(|e| BenchError::Option {
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
        let batch = setup.character.batch();
        progress("network");
        let fast: MultiResGnetInference = net.inference();
        let input_mlp_ms = try_median_ms(reps, || fast.input.forward(x).map(drop))
            .map_err(BenchError::stage("input transform"))?;
        let v = fast
            .input
            .forward(x)
            .map_err(BenchError::stage("input transform"))?;
        let local_ms = try_median_ms(reps, || {
            fast.multires.local.forward(&v, batch.adjacency()).map(drop)
        })
        .map_err(BenchError::stage("local branch"))?;
        let global_ms = match &fast.multires.global {
            Some(global) => try_median_ms(reps, || global.forward(&v, batch).map(drop))
                .map_err(BenchError::stage("global branch"))?,
            None => 0.0,
        };
        let h = fast
            .multires
            .forward(&v, batch)
            .map_err(BenchError::stage("branches"))?;
        let output_mlp_ms = try_median_ms(reps, || match &fast.hidden {
            Some(hidden) => hidden
                .forward(&h)
                .and_then(|h| fast.head.forward(&h))
                .map(drop),
            None => fast.head.forward(&h).map(drop),
        })
        .map_err(BenchError::stage("output transform"))?;
        let network_ms = try_median_ms(reps, || fast.forward_features(x, batch).map(drop))
            .map_err(BenchError::stage("network"))?;
        let (reference_ms, frame_ms) = setup.whole_ms(reps, &net, &fast, &device)?;
        Ok(MultiResGnetFigures {
            bench: "multiresgnet",
            preset: self.preset.clone(),
            vertices: setup.character.vertex_count(),
            threads: rayon::current_num_threads(),
            parameters: burn::module::Module::num_params(&net),
            inputs_ms: setup.inputs_ms,
            input_mlp_ms,
            local_ms,
            global_ms,
            output_mlp_ms,
            network_ms,
            reference_ms,
            frame_ms,
        })
    }
}
