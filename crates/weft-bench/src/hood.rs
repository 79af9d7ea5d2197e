//! `weft bench hood`: one rollout step of HOOD (seed 004) on the benchmark skirt of about
//! `vertices` vertices over the walking body, per stage, as `weft animate` runs it: the
//! step graph (body edges by nearest body vertex, features of nodes and of every level's
//! edges), the inputs (normalised), the network, the integration to `x_{t+1}`, and the
//! whole step; with `batch` garments advanced in one forward pass, the rollout steps per
//! second of the batch. The scene (posing the body, the garment's hierarchy, skinning) is
//! timed apart: a clip pays it once.
//!
//! The network runs in its inference form (`InferHood`, weft-nn's `infer`), as rollouts
//! run it; the same network's forward as burn layers on the flex CPU backend, the form
//! training differentiates, is timed beside it. Reference (issue 12): the public HOOD
//! network at 4 000 vertices takes 710 ms per step with PyTorch at 2 threads.

use std::hint::black_box;

use serde::Serialize;
use weft_body::BodyModel;
use weft_models::hood::features::StepGraph;
use weft_models::hood::rollout::{step_batch, Advance};
use weft_models::hood::{HoodBatch, InferHood};
use weft_models::hood::{HoodConfig, HoodInput, HoodStats, Materials, Scene, StepAt};
use weft_models::Clip;
use weft_motion::{generate, MotionKind, ProceduralParams};
use weft_nn::backend::cpu;
use weft_sim::{Attachment, Material};

use crate::timing::try_median_ms;
use crate::{skirt, BenchError, Row};

/// What to measure.
#[derive(Clone, Debug)]
pub struct HoodBench {
    /// Model preset: cpu or paper.
    pub preset: String,
    /// A message-passing schedule in place of the preset's (`"0 x15"`: Fine15; the
    /// format of [`HoodConfig::schedule`]).
    pub schedule: Option<String>,
    /// Vertices of the garment.
    pub vertices: usize,
    /// Garments advanced in one forward pass.
    pub batch: usize,
    /// Timed runs per figure.
    pub reps: usize,
}

/// One rollout step, per stage, ms.
#[derive(Clone, Debug, Serialize)]
pub struct HoodFigures {
    /// `"hood"`.
    pub bench: &'static str,
    /// The preset.
    pub preset: String,
    /// The message-passing schedule.
    pub schedule: String,
    /// How many mesh hops a vertex's information travels in one step through the
    /// schedule (seed 004 Table 1).
    pub propagation_radius: usize,
    /// Vertices of one garment.
    pub vertices: usize,
    /// Garments per forward pass.
    pub batch: usize,
    /// Threads of the pool.
    pub threads: usize,
    /// Parameters of the network.
    pub parameters: usize,
    /// Directed mesh edges of each level of one garment.
    pub level_edges: Vec<usize>,
    /// Body edges (both directions) of one garment at the timed frame.
    pub body_edges: usize,
    /// Once per garment and clip: posed body, hierarchy, skinning, physics.
    pub scene_ms: f64,
    /// The step graph of every garment of the batch.
    pub graph_ms: f64,
    /// The batch's inputs, normalised.
    pub inputs_ms: f64,
    /// The network (encoders, message passing, decoder), inputs included, in its
    /// inference form.
    pub network_ms: f64,
    /// The same as burn layers (the forward that training differentiates, here without
    /// autodiff), inputs as tensors included.
    pub burn_network_ms: f64,
    /// Graphs, network and integration: one rollout step of the batch.
    pub step_ms: f64,
    /// Garment rollout steps per second (`batch` per step).
    pub steps_per_s: f64,
}

impl Row for HoodFigures {
    fn cells(&self) -> Vec<(&'static str, String)> {
        vec![
            ("preset", self.preset.clone()),
            // The schedule's `|` would split a Markdown cell.
            ("schedule", self.schedule.replace('|', "\\|")),
            ("radius", self.propagation_radius.to_string()),
            ("N", self.vertices.to_string()),
            ("batch", self.batch.to_string()),
            ("params", self.parameters.to_string()),
            ("scene (once)", format!("{:.0}", self.scene_ms)),
            ("graph", format!("{:.1}", self.graph_ms)),
            ("inputs", format!("{:.1}", self.inputs_ms)),
            ("network", format!("{:.1}", self.network_ms)),
            ("network (burn)", format!("{:.1}", self.burn_network_ms)),
            ("step ms", format!("{:.1}", self.step_ms)),
            ("steps/s", format!("{:.2}", self.steps_per_s)),
        ]
    }
}

impl HoodBench {
    /// Runs the bench on the skirt fitted to `body`, walking.
    pub fn run(
        &self,
        body: &BodyModel,
        progress: &mut dyn FnMut(&str),
    ) -> Result<HoodFigures, BenchError> {
        let mut cfg = HoodConfig::preset(&self.preset).map_err(|e| BenchError::Option {
            what: "--preset",
            message: e.to_string(),
        })?;
        if let Some(schedule) = &self.schedule {
            cfg.schedule = schedule.clone();
        }
        let propagation_radius = cfg.propagation_radius().map_err(|e| BenchError::Option {
            what: "--schedule",
            message: e.to_string(),
        })?;
        if self.batch == 0 {
            return Err(BenchError::Option {
                what: "--batch",
                message: "at least 1 garment per pass".into(),
            });
        }
        progress("scene");
        let mesh = skirt(body, self.vertices)?;
        let mut walk = ProceduralParams::new(MotionKind::Walk);
        walk.frames = 8;
        let motion = generate(&walk).map_err(BenchError::stage("the walk"))?;
        let clip = Clip {
            betas: &[],
            poses: motion.poses(),
            trans: motion.trans(),
            fps: motion.fps(),
        };
        let materials = Materials::Uniform(Material::hood());
        let new_scene = || Scene::new(&mesh, body, &clip, &materials, Attachment::TopOpening, &cfg);
        let scene_ms = try_median_ms(self.reps.min(3), || new_scene().map(drop))
            .map_err(BenchError::stage("the scene"))?;
        let scene = new_scene().map_err(BenchError::stage("the scene"))?;
        let start = scene
            .start(3, false)
            .map_err(BenchError::stage("the start state"))?;
        let at = StepAt {
            t: 3,
            settle: false,
            dt: scene.dt,
            buttoned: true,
        };
        let graphs = || -> Result<Vec<(StepGraph, Advance)>, weft_models::ModelError> {
            (0..self.batch)
                .map(|_| scene.step(start.as_ref(), at, &cfg))
                .collect()
        };
        progress("step graph");
        let graph_ms = try_median_ms(self.reps, || graphs().map(|g| drop(black_box(g))))
            .map_err(BenchError::stage("the step graph"))?;
        let built = graphs().map_err(BenchError::stage("the step graph"))?;
        let refs: Vec<&StepGraph> = built.iter().map(|(g, _)| g).collect();
        let device = cpu();
        let stats = HoodStats::identity(cfg.levels);
        let model = cfg
            .init(&device)
            .map_err(BenchError::stage("the network"))?;
        let infer = InferHood::from(&model);
        progress("inputs");
        let inputs_ms = try_median_ms(self.reps, || {
            HoodBatch::new(&refs, &stats).map(|x| drop(black_box(x)))
        })
        .map_err(BenchError::stage("the inputs"))?;
        progress("network");
        let network_ms = try_median_ms(self.reps, || {
            let out = infer.forward(&HoodBatch::new(&refs, &stats)?)?;
            drop(black_box(out));
            Ok::<(), weft_models::ModelError>(())
        })
        .map_err(BenchError::stage("the network"))?;
        progress("network (burn)");
        let burn_network_ms = try_median_ms(self.reps, || {
            let out = model.forward(HoodInput::new(&refs, &stats, &device)?)?;
            drop(black_box(out.into_data()));
            Ok::<(), weft_models::ModelError>(())
        })
        .map_err(BenchError::stage("the network"))?;
        progress("step");
        let step_ms = try_median_ms(self.reps, || {
            let built = graphs()?;
            let pairs: Vec<_> = built.iter().map(|(g, a)| (g, a)).collect();
            drop(black_box(step_batch(&infer, &stats, &pairs, &device)?));
            Ok::<(), weft_models::ModelError>(())
        })
        .map_err(BenchError::stage("one step"))?;
        let one = &built[0].0;
        Ok(HoodFigures {
            bench: "hood",
            preset: self.preset.clone(),
            schedule: cfg.schedule.clone(),
            propagation_radius,
            vertices: mesh.vertex_count(),
            batch: self.batch,
            threads: rayon::current_num_threads(),
            parameters: burn::module::Module::num_params(&model),
            level_edges: one.mesh.iter().map(|(e, _)| e.len()).collect(),
            body_edges: one.body.0.len(),
            scene_ms,
            graph_ms,
            inputs_ms,
            network_ms,
            burn_network_ms,
            step_ms,
            steps_per_s: 1e3 * self.batch as f64 / step_ms,
        })
    }
}
