//! Training HOOD (seed 004) from the physics alone: no simulated data, only bodies,
//! procedural garments and motions, and the incremental potential of every predicted
//! step (eq. 5, weft-sim's energies through [`crate::loss::physics_loss`]).
//!
//! - Before the first step: a pool of garments (each kind × style built on each of
//!   `shapes` bodies of random β, in that body's rest pose, weft-garment) and of motions
//!   (procedural kinds, motion files). The normalisers are fitted on the start states of
//!   the first samples (HOOD's warm-up gathers them the same way), the output's on
//!   weft-sim's implicit step from there, and saved as `hood.json`.
//! - An item is a sample drawn from its index and the run's seed: a garment of the pool, a
//!   motion and a start frame, a material (`[model.materials]`, HOOD's ranges by default; a
//!   share of samples gets two materials split by a plane), 3 mm of noise on the start
//!   positions, and with some probability a start at rest (with the settling step first,
//!   body still, when `[model] settle_dt` > 0). The rollout of the current length runs from
//!   the skinned garment; every step's state is the previous prediction, detached (no
//!   backpropagation through time; projected first when the model's step ends in a
//!   projection, `[model] project_*`, as a rollout projects it), and the item's loss is the
//!   mean over its steps of each term of the potential, and of the distance to the implicit
//!   step when `solver_weight` > 0. HOOD steps the optimiser after every rollout step; here
//!   the steps of one item share one optimiser step, so an item is a pure function of its
//!   index and the model, and a resumed run repeats it exactly.
//! - Replay (`[train] replay`, not in HOOD): an item may instead go on with the rollout
//!   an earlier item left in its slot, from the model's own state at the frame it
//!   reached, so the network learns to correct the states its errors lead to. The kept
//!   rollouts are saved in every checkpoint ([`TrainTask::memory`]), and a resumed run
//!   still repeats the uninterrupted one.
//! - Stages: the rollout length (1 → `max_rollout`, one more every `rollout_every`
//!   steps) and the collision weight's level (HOOD's ramp of the collision stiffness,
//!   taken in [`COLLISION_LEVELS`] geometric steps).
//! - Validation: held-out scenes (new shapes, motions, materials) rolled out over
//!   `validation_frames` frames; metrics: the mean potential per frame at full collision
//!   stiffness (primary), the norm of its gradient at the predictions, the share of
//!   garment vertices inside the body, the mean edge strain, and the frames reached
//!   before any divergence.

pub mod config;

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use burn::tensor::{Device, Int, Tensor};
use weft_body::{BodyModel, Pose};
use weft_garment::{FitBody, Garment, GarmentKind, Style};
use weft_mesh::eccentricity::component_center_sets;
use weft_mesh::rng::SplitMix64;
use weft_mesh::TriMesh;
use weft_models::hood::rollout::{host_positions, next_positions};
use weft_models::hood::{
    roll_out, Advance, Corrector, Hood, HoodConfig, HoodInput, HoodStats, HoodStatsFit, InferHood,
    Materials, RolloutOptions, Scene, State, StateRef, StepAt, STATS_FILE,
};
use weft_models::Clip;
use weft_motion::{MotionKind, ProceduralParams};
use weft_nn::adjacency::index_tensor;
use weft_sim::{Attachment, BodyProximity, Energy, Material, StepInputs};

pub use config::{HoodRun, HoodTraining, COLLISION_LEVELS, OPEN_FRONT_BUTTONS};

use crate::error::{Result, TrainError};
use crate::loss::{physics_loss, FrameEnergies, PhysicsImpl, PotentialTerm};
use crate::task::{LossTerm, Metrics, StepEnd, TrainTask};

/// The validation metric the schedule watches: the mean incremental potential per frame
/// of the validation rollouts (J), at full collision stiffness.
pub const POTENTIAL: &str = "potential";
/// Share of garment vertices inside the body over the validation rollouts (%).
pub const INSIDE_PERCENT: &str = "inside_percent";
/// Mean relative edge-length change against the rest shape over the rollouts (%).
pub const EDGE_STRAIN_PERCENT: &str = "edge_strain_percent";
/// Share of the validation frames reached before a rollout diverged (%).
pub const FRAMES_REACHED_PERCENT: &str = "frames_reached_percent";
/// Mean over the validation frames of `‖∂E/∂x̂‖₂`, the norm of the potential's gradient
/// at the predicted positions of the free vertices (N): seed 004 Table 1's last column,
/// zero where a prediction is the step's minimiser.
pub const GRADIENT_NORM: &str = "gradient_norm";

/// Samples the normalisers are fitted on (HOOD's warm-up: 100 iterations).
const STATS_SAMPLES: usize = 64;

/// Rollouts kept going across items (`[train] replay`): items take the slots in turn.
const REPLAY_SLOTS: usize = 8;

/// A kept rollout further from its skinned garment than this (m) has diverged; its slot
/// starts afresh rather than teach from an exploded state.
const REPLAY_DRIFT: f64 = 0.5;

/// Training items per epoch: samples are drawn from their index, so this only sets how
/// often the order is reshuffled.
const ITEMS: usize = 100_000;

/// The terms of seed 004 eq. 5, in the order weft-sim's `ClothModel::step_potential`
/// builds them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Term {
    /// StVK stretching.
    Stretching,
    /// Dihedral bending.
    Bending,
    /// Gravity.
    Gravity,
    /// Inertia.
    Inertia,
    /// Cubic body collision.
    Collision,
    /// Friction against the body.
    Friction,
    /// Button pairs held together (weft-sim `Buttons`; zero for a sample without
    /// buttons or once unbuttoned).
    Buttons,
    /// The distance to weft-sim's implicit step from the same state (cm², mean over the
    /// vertices): the potential's minimiser as a target, see [`HoodTraining::solver_weight`].
    Solver,
    /// The distance to the implicit step's edge vectors (cm², mean over the mesh edges),
    /// see [`HoodTraining::solver_edge_weight`].
    SolverEdges,
    /// What [`Term::Solver`] would be if the network added nothing to inertia (`x_t +
    /// v_t`, pins at their targets): logged beside it with weight 0 (it does not depend
    /// on the network), so `solver / solver_coast` is the share of the implicit step's
    /// correction the network misses (docs/hood.md item 14).
    SolverCoast,
}

impl Term {
    /// The terms of the potential, in its order.
    pub const POTENTIAL: [Term; 7] = [
        Term::Stretching,
        Term::Bending,
        Term::Gravity,
        Term::Inertia,
        Term::Collision,
        Term::Friction,
        Term::Buttons,
    ];
}

impl LossTerm for Term {
    fn name(self) -> &'static str {
        match self {
            Term::Stretching => "stretching",
            Term::Bending => "bending",
            Term::Gravity => "gravity",
            Term::Inertia => "inertia",
            Term::Collision => "collision",
            Term::Friction => "friction",
            Term::Buttons => "buttons",
            Term::Solver => "solver",
            Term::SolverEdges => "solver_edges",
            Term::SolverCoast => "solver_coast",
        }
    }
}

/// Where the curriculum is.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Stage {
    /// Rollout steps per item.
    pub rollout: usize,
    /// The collision weight's level (0 ..= [`COLLISION_LEVELS`]).
    pub collision: usize,
}

impl Default for Stage {
    fn default() -> Self {
        Stage {
            rollout: 1,
            collision: 0,
        }
    }
}

/// A garment of the pool: the mesh on its body, and that body's shape.
#[derive(Clone, Debug)]
struct PoolGarment {
    mesh: TriMesh,
    betas: Vec<f32>,
    /// Each component's minimum-eccentricity vertices (the centres a sample draws from).
    centres: Vec<Vec<u32>>,
    /// The same garment opened down the front, when `[train] open_front` > 0.
    open: Option<OpenGarment>,
}

/// A pool garment cut down the front, with its button pairs.
#[derive(Clone, Debug)]
struct OpenGarment {
    mesh: TriMesh,
    buttons: Vec<[u32; 2]>,
    centres: Vec<Vec<u32>>,
}

impl PoolGarment {
    /// The mesh a sample uses and its centre sets: the open variant for an open sample.
    fn variant(&self, open: bool) -> (&TriMesh, &[Vec<u32>]) {
        match (&self.open, open) {
            (Some(o), true) => (&o.mesh, &o.centres),
            _ => (&self.mesh, &self.centres),
        }
    }
}

/// A motion of the pool.
#[derive(Clone, Debug)]
struct PoolMotion {
    poses: Vec<Pose>,
    trans: Vec<[f32; 3]>,
    fps: f64,
}

/// One drawn sample.
#[derive(Clone, Debug)]
struct Sample {
    garment: usize,
    motion: usize,
    /// First frame of the window (the frame before the rollout starts).
    first: usize,
    materials: Materials,
    /// The rollout starts from the skinned garment at rest, as inference does (with the
    /// settling step first when `[model] settle_dt` > 0).
    at_rest: bool,
    noise_seed: u64,
    /// The hierarchy's centre in each garment component (`[train] random_centres`);
    /// none: the first minimum-eccentricity vertex, as inference takes it.
    centres: Option<Vec<u32>>,
    /// The garment opened down the front (`[train] open_front`), and whether it is
    /// buttoned; `None`: the closed garment.
    open: Option<bool>,
}

/// A rollout kept for a later item (`[train] replay`): the sample it belongs to, the
/// motion frame its state has reached, and that state (the model's own predictions).
#[derive(Clone, Debug)]
struct Live {
    /// The item and rollout length whose fresh sample started it (what a checkpoint
    /// saves of `sample`).
    origin: (usize, usize),
    sample: Sample,
    /// The motion frame of `state.cur`.
    frame: usize,
    /// Frames run since its skinned start.
    age: usize,
    state: State,
}

impl Sample {
    /// Whether the rollout's step `k` is the settling step.
    fn settles(&self, k: usize, config: &HoodConfig) -> bool {
        k == 0 && self.at_rest && config.settle_dt > 0.0
    }
}

/// HOOD's training task; see the module documentation.
pub struct HoodTask {
    training: HoodTraining,
    config: HoodConfig,
    stats: HoodStats,
    body: BodyModel,
    garments: Vec<PoolGarment>,
    motions: Vec<PoolMotion>,
    validation: Vec<Scene>,
    seed: u64,
    stage: Stage,
    device: Device,
    /// Kept rollouts, [`REPLAY_SLOTS`] of them once `[train] replay` > 0.
    live: Vec<Option<Live>>,
    /// Items evaluated so far: the next one's replay slot.
    evaluated: usize,
}

/// The two-material split of a garment: vertices on the positive side of a random plane
/// through its centroid take `b`.
fn two_materials(mesh: &TriMesh, a: Material, b: Material, rng: &mut SplitMix64) -> Materials {
    let n = mesh.vertex_count().max(1) as f64;
    let c = mesh.positions.iter().fold([0.0; 3], |s, p| {
        [s[0] + p[0] / n, s[1] + p[1] / n, s[2] + p[2] / n]
    });
    let d = weft_mesh::vec3::normalize_or_zero([
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
    ]);
    Materials::PerVertex(
        mesh.positions
            .iter()
            .map(|p| {
                if weft_mesh::vec3::dot(weft_mesh::vec3::sub(*p, c), d) > 0.0 {
                    b
                } else {
                    a
                }
            })
            .collect(),
    )
}

/// A standard normal draw (Box–Muller).
fn normal(rng: &mut SplitMix64) -> f64 {
    let u = rng.unit().max(1e-300);
    let v = rng.unit();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// The garment pool: every kind × style on every body shape.
fn garment_pool(
    training: &HoodTraining,
    body: &BodyModel,
    shapes: &[Vec<f32>],
    seed: u64,
) -> Result<Vec<PoolGarment>> {
    let mut out = Vec::new();
    for betas in shapes {
        for name in &training.garments {
            for s in 0..training.styles {
                let garment = garment_on(training, body, betas, name, seed.wrapping_add(s as u64))?;
                let open = if training.open_front > 0.0 {
                    let open = garment.open_front(OPEN_FRONT_BUTTONS).map_err(|e| {
                        TrainError::config("train.open_front", training.open_front, &e.to_string())
                    })?;
                    Some(OpenGarment {
                        centres: component_center_sets(&open.garment.mesh.graph()),
                        mesh: open.garment.mesh,
                        buttons: open.buttons,
                    })
                } else {
                    None
                };
                let mesh = garment.mesh;
                out.push(PoolGarment {
                    centres: component_center_sets(&mesh.graph()),
                    mesh,
                    betas: betas.clone(),
                    open,
                });
            }
        }
    }
    Ok(out)
}

/// The garment `kind` of style `style_seed` built on the body of shape `betas` in its rest
/// pose, with the training's vertex count; errors name the config field.
fn garment_on(
    training: &HoodTraining,
    body: &BodyModel,
    betas: &[f32],
    kind: &str,
    style_seed: u64,
) -> Result<Garment> {
    let b64: Vec<f64> = betas.iter().map(|&b| f64::from(b)).collect();
    let fit = FitBody::new(body, &b64).map_err(|e| {
        TrainError::config("train.shape_range", training.shape_range, &e.to_string())
    })?;
    let parsed = GarmentKind::parse(kind)
        .map_err(|e| TrainError::config("train.garments", kind, &e.to_string()))?;
    fit.generate(
        parsed,
        &Style::from_seed(parsed, style_seed),
        training.garment_vertices,
    )
    .map_err(|e| TrainError::config("train.garments", kind, &e.to_string()))
}

/// The motion pool: each procedural kind (seeded) and each motion file, at `step_fps`
/// frames per second (`[model] step_fps`: one network step a pool frame).
fn motion_pool(
    training: &HoodTraining,
    body: &BodyModel,
    seed: u64,
    step_fps: f64,
) -> Result<Vec<PoolMotion>> {
    let mut out = Vec::new();
    for (k, name) in training.motions.iter().enumerate() {
        let kind = MotionKind::parse(name).ok_or_else(|| {
            TrainError::config(
                "train.motions",
                name,
                "a procedural motion name (walk, run, jump, dance, kick, raise-arms, twist, bow)",
            )
        })?;
        let mut p = ProceduralParams::new(kind);
        p.frames = training.motion_frames;
        p.seed = seed.wrapping_add(k as u64);
        let m = weft_motion::generate(&p)
            .and_then(|m| weft_motion::resample(&m, step_fps))
            .map_err(|e| TrainError::config("train.motions", name, &e.to_string()))?;
        out.push(PoolMotion {
            poses: m.poses().to_vec(),
            trans: m.trans().to_vec(),
            fps: m.fps(),
        });
    }
    for path in &training.motion_files {
        let joints = weft_motion::body_rest_joints(body, &[]).map_err(|e| {
            TrainError::config("train.motion_files", path.display(), &e.to_string())
        })?;
        let options = weft_motion::MotionFileOptions::for_body(joints, None);
        let m = weft_motion::load_motion(path, &options, Some(step_fps))
            .map_err(|e| TrainError::config("train.motion_files", path.display(), &e.to_string()))?
            .motion;
        if m.poses().len() < training.max_rollout + 3 {
            return Err(TrainError::config(
                "train.motion_files",
                path.display(),
                &format!("a motion of at least {} frames", training.max_rollout + 3),
            ));
        }
        out.push(PoolMotion {
            poses: m.poses().to_vec(),
            trans: m.trans().to_vec(),
            fps: m.fps(),
        });
    }
    Ok(out)
}

/// `count` shapes drawn in the training range.
fn shapes(training: &HoodTraining, count: usize, rng: &mut SplitMix64) -> Vec<Vec<f32>> {
    (0..count)
        .map(|_| {
            (0..training.shape_components)
                .map(|_| rng.uniform(-training.shape_range, training.shape_range) as f32)
                .collect()
        })
        .collect()
}

impl HoodTask {
    /// The task for `config` and `training` on `body`; fits the normalisers unless
    /// `stats` is given (a resumed run's own).
    pub fn new(
        config: &HoodConfig,
        training: &HoodTraining,
        body: BodyModel,
        stats: Option<HoodStats>,
        seed: u64,
        device: &Device,
    ) -> Result<Self> {
        training.validate_values()?;
        // A term left out needs the projection that does its work at every step.
        for (field, weight, bound, needs) in [
            (
                "train.collision_weight",
                training.collision_weight,
                config.project_margin,
                "above 0 unless [model] project_margin is set (nothing else keeps the cloth out of the body)",
            ),
            (
                "train.stretching_weight",
                training.stretching_weight,
                config.project_stretch,
                "above 0 unless [model] project_stretch is set (nothing else bounds the stretch)",
            ),
        ] {
            if weight == 0.0 && bound.is_none() {
                return Err(TrainError::config(field, weight, needs));
            }
        }
        let mut rng = SplitMix64::new(seed ^ 0x4F0D_5EED);
        let train_shapes = shapes(training, training.shapes.max(1), &mut rng);
        let garments = garment_pool(training, &body, &train_shapes, seed)?;
        let motions = motion_pool(training, &body, seed, config.step_fps)?;
        let mut task = HoodTask {
            training: training.clone(),
            config: config.clone(),
            stats: HoodStats {
                node: weft_nn::FeatureNormalizer {
                    mean: vec![],
                    std: vec![],
                },
                mesh: weft_nn::FeatureNormalizer {
                    mean: vec![],
                    std: vec![],
                },
                body: weft_nn::FeatureNormalizer {
                    mean: vec![],
                    std: vec![],
                },
                output: weft_nn::FeatureNormalizer {
                    mean: vec![],
                    std: vec![],
                },
            },
            body,
            garments,
            motions,
            validation: Vec::new(),
            seed,
            stage: Stage::default(),
            device: device.clone(),
            live: vec![None; REPLAY_SLOTS],
            evaluated: 0,
        };
        task.validation = task.validation_scenes(&mut rng)?;
        task.stats = match stats {
            Some(s) => s,
            None => task.fit_stats()?,
        };
        Ok(task)
    }

    /// The normalisers, as saved beside the checkpoints.
    pub fn stats(&self) -> &HoodStats {
        &self.stats
    }

    /// (garments in the pool, motions, validation scenes).
    pub fn describe(&self) -> (usize, usize, usize) {
        (
            self.garments.len(),
            self.motions.len(),
            self.validation.len(),
        )
    }

    /// Sample `item`, drawn from the run's seed.
    fn sample(&self, item: usize, rollout: usize) -> Sample {
        let mut rng = SplitMix64::new(
            self.seed
                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                .wrapping_add(item as u64),
        );
        let garment = rng.below(self.garments.len());
        let motion = rng.below(self.motions.len());
        let frames = self.motions[motion].poses.len();
        // The window: frame `first` (t − 1), the start `first + 1`, and `rollout` more.
        let first = rng.below(frames - rollout - 1);
        // No draw without open garments, so runs without them keep their samples.
        let open = (self.training.open_front > 0.0 && rng.unit() < self.training.open_front)
            .then(|| rng.unit() < 0.5);
        let (mesh, centre_sets) = self.garments[garment].variant(open.is_some());
        let a = self.config.materials.sample(&mut rng);
        let materials = if rng.unit() < self.training.two_materials {
            let b = self.config.materials.sample(&mut rng);
            two_materials(mesh, a, b, &mut rng)
        } else {
            Materials::Uniform(a)
        };
        let at_rest = rollout > 1 || rng.unit() < self.training.settle_probability;
        let noise_seed = rng.next_u64();
        let centres = self.training.random_centres.then(|| {
            centre_sets
                .iter()
                .map(|set| set[rng.below(set.len())])
                .collect()
        });
        Sample {
            garment,
            motion,
            first,
            materials,
            at_rest,
            noise_seed,
            centres,
            open,
        }
    }

    /// The scene of sample `s`: a window of `frames` frames of its pool motion from its
    /// first frame, the garment's hierarchy around the sample's centres.
    fn scene(&self, s: &Sample, frames: usize) -> Result<Scene> {
        let g = &self.garments[s.garment];
        let m = &self.motions[s.motion];
        let end = (s.first + frames).min(m.poses.len());
        let clip = Clip {
            betas: &g.betas,
            poses: &m.poses[s.first..end],
            trans: &m.trans[s.first..end],
            fps: m.fps,
        };
        let (mesh, _) = g.variant(s.open.is_some());
        let mut scene = Scene::new(
            mesh,
            &self.body,
            &clip,
            &s.materials,
            Attachment::TopOpening,
            &self.config,
        )?;
        if let Some(centres) = &s.centres {
            scene.garment = scene.garment.recentred(centres)?;
        }
        if let (Some(true), Some(open)) = (s.open, &g.open) {
            scene = scene.with_buttons(&open.buttons)?;
        }
        Ok(scene)
    }

    /// Held-out scenes: new shapes (drawn after the training ones), every motion in turn
    /// from its start, HOOD's default material and a garment split between the two
    /// corners of the run's material space (`[model.materials]`) in turn.
    fn validation_scenes(&self, rng: &mut SplitMix64) -> Result<Vec<Scene>> {
        let shapes = shapes(&self.training, self.training.validation_scenes, rng);
        let mut out = Vec::new();
        for (k, betas) in shapes.iter().enumerate() {
            let kind = &self.training.garments[k % self.training.garments.len()];
            let style = self.seed.wrapping_add(1000 + k as u64);
            let mesh = garment_on(&self.training, &self.body, betas, kind, style)?.mesh;
            let m = &self.motions[k % self.motions.len()];
            let end = self.training.validation_frames.min(m.poses.len());
            let clip = Clip {
                betas,
                poses: &m.poses[..end],
                trans: &m.trans[..end],
                fps: m.fps,
            };
            let materials = if k % 2 == 0 {
                Materials::Uniform(Material::hood())
            } else {
                let mut split = SplitMix64::new(k as u64);
                let corners = [0, 1].map(|end| self.config.materials.corner(end));
                two_materials(&mesh, corners[0], corners[1], &mut split)
            };
            out.push(Scene::new(
                &mesh,
                &self.body,
                &clip,
                &materials,
                Attachment::TopOpening,
                &self.config,
            )?);
        }
        Ok(out)
    }

    /// The normalisers from the skinned states of the first samples, as drawn (the
    /// settling steps included, so the time step is a feature the network can read):
    /// inputs of the step from the skinned garment; outputs the acceleration of
    /// weft-sim's implicit step from there, the step the loss's minimum is. HOOD takes
    /// the skinned garment's own acceleration instead, but a skinned start is far from
    /// equilibrium: the implicit step moves vertices 1–2 cm (up to 6) where skinning
    /// accelerates them by 3–4 mm, so outputs scaled by skinning need 5–17 standard
    /// deviations (docs/hood.md).
    fn fit_stats(&self) -> Result<HoodStats> {
        let mut fit = HoodStatsFit::new(self.config.levels)?;
        for item in 0..STATS_SAMPLES {
            let s = self.sample(item, 1);
            let scene = self.scene(&s, 3)?;
            let start = scene.start(1, s.at_rest)?;
            let settle = s.settles(0, &self.config);
            let at = StepAt {
                t: 1,
                settle,
                dt: if settle {
                    self.config.settle_dt
                } else {
                    scene.dt
                },
                buttoned: true,
            };
            let (graph, _) = scene.step(start.as_ref(), at, &self.config)?;
            let (prev, cur) = (&start.prev, &start.cur);
            let body = scene.contact_body(at)?;
            let next = scene.implicit_step(start.as_ref(), at, body.as_ref())?;
            let mut accel = Vec::with_capacity(3 * cur.len());
            for i in (0..cur.len()).filter(|&i| !scene.garment.pinned[i]) {
                accel.extend((0..3).map(|k| (next[i][k] - 2.0 * cur[i][k] + prev[i][k]) as f32));
            }
            fit.observe(&graph, &accel)?;
        }
        Ok(fit.finish()?)
    }

    /// The potential of step `at` of `scene` from `cur` (inertial target from
    /// `advance`) against the step's contact `body`, each term with its weight.
    fn potential_terms(
        &self,
        scene: &Scene,
        cur: &[[f64; 3]],
        advance: &Advance,
        at: StepAt,
        body: &(dyn BodyProximity + Sync),
        collision_weight: f64,
    ) -> Result<Vec<Arc<dyn Energy + Send + Sync>>> {
        let dt = at.dt;
        let target = advance.inertial_target();
        let cloth = scene.cloth_at(at);
        let stiffness = cloth.options().collision_stiffness * collision_weight;
        let potential = cloth.step_potential(&StepInputs {
            start: cur,
            target: &target,
            dt,
            pinned: &scene.garment.pinned,
            body: Some(body),
            collision_stiffness: Some(stiffness),
        })?;
        Ok(PotentialTerm::all(potential))
    }
}

/// [`HoodTask`]'s memory in a checkpoint: its kept rollouts, positions as their `f64`
/// bits so that a resumed run starts from the very same states.
#[derive(serde::Serialize, serde::Deserialize)]
struct Memory {
    evaluated: usize,
    live: Vec<Option<SavedLive>>,
}

/// A [`Live`] rollout as saved: its sample is redrawn from its origin.
#[derive(serde::Serialize, serde::Deserialize)]
struct SavedLive {
    item: usize,
    rollout: usize,
    frame: usize,
    age: usize,
    prev: Vec<u64>,
    cur: Vec<u64>,
}

impl HoodTask {
    /// The rollout in `slot` for item `item`, moved on so that its window of `rollout`
    /// steps starts at the frame it reached, when the item draws a replay
    /// (`[train] replay`) and the rollout has frames and age left.
    fn replayed(&mut self, item: usize, slot: usize, rollout: usize) -> Option<Live> {
        if self.training.replay <= 0.0 {
            return None;
        }
        let mut rng = SplitMix64::new(
            (self.seed ^ 0x5EED_4E91_A7ED_0000)
                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                .wrapping_add(item as u64),
        );
        if rng.unit() >= self.training.replay {
            return None;
        }
        let live = self.live[slot].take()?;
        let frames = self.motions[live.sample.motion].poses.len();
        let fits = live.frame + rollout < frames;
        let young = live.age + rollout <= self.training.replay_frames;
        (fits && young).then(|| {
            let mut live = live;
            // The window's frame before the start is `first`, its start `first + 1`.
            live.sample.first = live.frame - 1;
            live.sample.at_rest = false;
            live.sample.noise_seed = rng.next_u64();
            live
        })
    }

    /// What an item's rollout leaves for a later one: its state at window frame `t`,
    /// unless it has drifted [`REPLAY_DRIFT`] from the skinned garment (diverged).
    fn kept(
        &self,
        scene: &Scene,
        origin: (usize, usize),
        sample: Sample,
        t: usize,
        age: usize,
        state: State,
    ) -> Option<Live> {
        let skinned = scene.pin_targets(t);
        let drift = state
            .cur
            .iter()
            .zip(&skinned)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>())
            .fold(
                0.0,
                |m: f64, d| if d.is_nan() { f64::INFINITY } else { m.max(d) },
            )
            .sqrt();
        (drift < REPLAY_DRIFT).then(|| Live {
            origin,
            frame: sample.first + t,
            sample,
            age,
            state,
        })
    }

    /// A saved rollout back as it was, checked against this run's pool.
    fn restored(&self, saved: SavedLive) -> std::result::Result<Live, String> {
        if !(1..=self.training.max_rollout).contains(&saved.rollout) {
            return Err(format!(
                "a kept rollout started with {} steps (max_rollout is {})",
                saved.rollout, self.training.max_rollout
            ));
        }
        let sample = self.sample(saved.item, saved.rollout);
        let (mesh, _) = self.garments[sample.garment].variant(sample.open.is_some());
        let n = mesh.vertex_count();
        let frames = self.motions[sample.motion].poses.len();
        if saved.frame == 0 || saved.frame >= frames {
            return Err(format!(
                "a kept rollout at frame {} of a {frames}-frame motion",
                saved.frame
            ));
        }
        let positions = |bits: &[u64]| -> std::result::Result<Vec<[f64; 3]>, String> {
            if bits.len() != 3 * n {
                return Err(format!(
                    "a kept rollout of {} coordinates for a garment of {n} vertices",
                    bits.len()
                ));
            }
            Ok(bits
                .chunks_exact(3)
                .map(|c| std::array::from_fn(|k| f64::from_bits(c[k])))
                .collect())
        };
        Ok(Live {
            origin: (saved.item, saved.rollout),
            frame: saved.frame,
            age: saved.age,
            state: State {
                prev: positions(&saved.prev)?,
                cur: positions(&saved.cur)?,
            },
            sample,
        })
    }
}

/// `‖x − target‖²` in cm², the mean over the vertices (pinned ones are exact in both).
fn solver_loss(x: Tensor<2>, target: Tensor<2>) -> Tensor<1> {
    squared_cm(x - target)
}

/// `‖(x_b − x_a) − (t_b − t_a)‖²` in cm², the mean over the directed edges `(a, b)`.
fn solver_edge_loss(x: Tensor<2>, target: Tensor<2>, edges: &EdgeIndex) -> Tensor<1> {
    let d = x - target;
    squared_cm(d.clone().select(0, edges.b.clone()) - d.select(0, edges.a.clone()))
}

/// The mean over rows of the squared norm of `d` (m), in cm².
fn squared_cm(d: Tensor<2>) -> Tensor<1> {
    let rows = d.dims()[0].max(1) as f64;
    let d = d.mul_scalar(100.0);
    (d.clone() * d).sum().div_scalar(rows).reshape([1])
}

/// Host positions as a `[N, 3]` tensor.
fn positions_tensor(x: &[[f64; 3]], device: &Device) -> Tensor<2> {
    let flat: Vec<f32> = x.iter().flatten().map(|&v| v as f32).collect();
    Tensor::<2>::from_data(burn::tensor::TensorData::new(flat, [x.len(), 3]), device)
}

/// The mesh edges' end points as index tensors.
struct EdgeIndex {
    a: Tensor<1, Int>,
    b: Tensor<1, Int>,
}

impl EdgeIndex {
    fn new(edges: &[[u32; 2]], device: &Device) -> Self {
        let pick = |k: usize| index_tensor(&edges.iter().map(|e| e[k]).collect::<Vec<_>>(), device);
        EdgeIndex {
            a: pick(0),
            b: pick(1),
        }
    }
}

impl TrainTask for HoodTask {
    type Model = Hood;
    type Term = Term;
    type Stage = Stage;

    fn item_count(&self) -> usize {
        ITEMS
    }

    fn terms(&self, _stage: &Stage) -> Vec<(Term, f64)> {
        let mut terms: Vec<(Term, f64)> = Term::POTENTIAL
            .iter()
            .map(|&t| match t {
                Term::Stretching => (t, self.training.stretching_weight),
                _ => (t, 1.0),
            })
            .collect();
        if self.training.solver_weight > 0.0 {
            terms.push((Term::Solver, self.training.solver_weight));
        }
        if self.training.solver_edge_weight > 0.0 {
            terms.push((Term::SolverEdges, self.training.solver_edge_weight));
        }
        if self.training.solver_weight > 0.0 || self.training.solver_edge_weight > 0.0 {
            terms.push((Term::SolverCoast, 0.0));
        }
        terms
    }

    fn losses(&mut self, model: &Hood, item: usize, terms: &[Term]) -> Result<Vec<Tensor<1>>> {
        let rollout = self.stage.rollout;
        let slot = self.evaluated % REPLAY_SLOTS;
        self.evaluated += 1;
        let (origin, s, age, start) = match self.replayed(item, slot, rollout) {
            Some(live) => (live.origin, live.sample, live.age, Some(live.state)),
            None => ((item, rollout), self.sample(item, rollout), 0, None),
        };
        let scene = self.scene(&s, rollout + 2)?;
        let start = match start {
            Some(state) => state,
            None => scene.start(1, s.at_rest)?,
        };
        let (mut prev, mut cur) = (start.prev, start.cur);
        // Position noise on the free vertices, the same offset at t − 1 and t.
        let mut rng = SplitMix64::new(s.noise_seed);
        for i in 0..cur.len() {
            if scene.garment.pinned[i] {
                continue;
            }
            let d: [f64; 3] = std::array::from_fn(|_| self.training.noise * normal(&mut rng));
            for k in 0..3 {
                prev[i][k] += d[k];
                cur[i][k] += d[k];
            }
        }
        let weight = self.training.collision_weight_at(self.stage.collision);
        let edges = terms
            .contains(&Term::SolverEdges)
            .then(|| EdgeIndex::new(&scene.garment.levels[0], &self.device));
        // The model's step projection (`[model] project_*`), as a rollout applies it.
        let corrector = match self.config.projects() {
            true => Some(Corrector::new(
                &scene,
                &RolloutOptions::default().over(&self.config),
            )?),
            false => None,
        };
        let mut sums: Vec<Option<Tensor<1>>> = vec![None; terms.len()];
        let mut t = 1;
        for k in 0..rollout {
            let settle = s.settles(k, &self.config);
            let dt = if settle {
                self.config.settle_dt
            } else {
                scene.dt
            };
            let at = StepAt {
                t,
                settle,
                dt,
                buttoned: true,
            };
            let state = StateRef {
                prev: &prev,
                cur: &cur,
            };
            let (graph, advance) = scene.step(state, at, &self.config)?;
            // The step's potential and the implicit step from the same state (once for
            // both solver terms), on one contact body, do not depend on the network, so
            // they run beside the forward pass: each uses the other's idle thread, and no
            // result depends on the threads.
            let wants_target = terms
                .iter()
                .any(|t| matches!(t, Term::Solver | Term::SolverCoast))
                || edges.is_some();
            let (physics, out) = rayon::join(
                || -> Result<_> {
                    let body = scene.contact_body(at)?;
                    let potential =
                        self.potential_terms(&scene, &cur, &advance, at, body.as_ref(), weight)?;
                    let target = if wants_target {
                        Some(scene.implicit_step(state, at, body.as_ref())?)
                    } else {
                        None
                    };
                    Ok((potential, target))
                },
                || model.forward(HoodInput::new(&[&graph], &self.stats, &self.device)?),
            );
            let x = next_positions(out?, &[&advance], &self.stats, &self.device)?;
            let mut next = host_positions(&x)?;
            // The projected step: the loss is the network's own step's, the rollout goes
            // on from the projected garment, as a rollout does. (The potential of the
            // projected garment with the gradient passed straight through the projection
            // taught the network to lift the cloth and let the compression bound crumple
            // it at the waist: docs/hood.md item 15.) The settling step stays
            // unprojected, as in a rollout.
            if let (Some(corrector), false) = (&corrector, settle) {
                corrector.correct(&cur, at, &mut next)?;
            }
            let n = graph.garment_nodes;
            let (potential, target) = physics?;
            let x3 = x.clone().reshape([1, n, 3]);
            let target = target.map(|target| positions_tensor(&target, &self.device));
            for (slot, term) in sums.iter_mut().zip(terms) {
                let loss = match (term, &target, &edges) {
                    (Term::Solver, Some(target), _) => solver_loss(x.clone(), target.clone()),
                    (Term::SolverEdges, Some(target), Some(edges)) => {
                        solver_edge_loss(x.clone(), target.clone(), edges)
                    }
                    (Term::SolverCoast, Some(target), _) => solver_loss(
                        positions_tensor(&advance.inertial_target(), &self.device),
                        target.clone(),
                    ),
                    _ => {
                        let index = Term::POTENTIAL.iter().position(|a| a == term).unwrap_or(0);
                        let energy = match potential.get(index) {
                            Some(energy) => energy.clone(),
                            // The potential holds the buttons only while there are some.
                            None if *term == Term::Buttons => {
                                *slot = Some(
                                    slot.take()
                                        .unwrap_or_else(|| Tensor::<1>::zeros([1], &self.device)),
                                );
                                continue;
                            }
                            None => {
                                return Err(TrainError::config(
                                    "train",
                                    term.name(),
                                    "a term of the potential",
                                ))
                            }
                        };
                        physics_loss(
                            x3.clone(),
                            &Arc::new(FrameEnergies::per_frame(vec![energy])?),
                            PhysicsImpl::Auto,
                        )?
                    }
                };
                *slot = Some(match slot.take() {
                    Some(s) => s + loss,
                    None => loss,
                });
            }
            if settle {
                prev = next.clone();
            } else {
                prev = cur;
                t += 1;
            }
            cur = next;
        }
        if self.training.replay > 0.0 {
            let state = State { prev, cur };
            self.live[slot] = self.kept(&scene, origin, s, t, age + rollout, state);
        }
        Ok(sums
            .into_iter()
            .map(|s| s.map(|s| s.div_scalar(rollout as f64)))
            .collect::<Option<Vec<_>>>()
            .unwrap_or_default())
    }

    fn validate(&mut self, model: &Hood) -> Result<Metrics> {
        let scenes: Vec<&Scene> = self.validation.iter().collect();
        let options = RolloutOptions::default();
        let rollouts = roll_out(
            &InferHood::from(model),
            &self.stats,
            &self.config,
            &scenes,
            &options,
            &self.device,
        )?;
        let (mut potential, mut gradient, mut steps) = (0.0, 0.0, 0usize);
        let (mut inside, mut vertices) = (0usize, 0usize);
        let (mut strain, mut edges) = (0.0, 0usize);
        let (mut reached, mut wanted) = (0usize, 0usize);
        for (scene, r) in scenes.iter().zip(&rollouts) {
            wanted += scene.frames();
            reached += r.frames.len();
            let rest_edges = scene.garment.rest.edges();
            let rest = &scene.garment.rest.positions;
            for (t, x) in r.frames.iter().enumerate() {
                let body = scene.posed_body(StepAt {
                    t,
                    settle: true,
                    dt: scene.dt,
                    buttoned: true,
                })?;
                inside += body.penetration(x, 0.0)?.count;
                vertices += x.len();
                for &[a, b] in &rest_edges {
                    let l0 = weft_mesh::vec3::dist(rest[a as usize], rest[b as usize]);
                    let l = weft_mesh::vec3::dist(x[a as usize], x[b as usize]);
                    if l0 > 0.0 {
                        strain += (l / l0 - 1.0).abs();
                        edges += 1;
                    }
                }
                if t >= 1 {
                    let prev = if t >= 2 {
                        &r.frames[t - 2]
                    } else {
                        &r.frames[t - 1]
                    };
                    let cur = &r.frames[t - 1];
                    let at = StepAt {
                        t: t - 1,
                        settle: false,
                        dt: scene.dt,
                        buttoned: true,
                    };
                    let (_, advance) = scene.step(StateRef { prev, cur }, at, &self.config)?;
                    let body = scene.contact_body(at)?;
                    let terms =
                        self.potential_terms(scene, cur, &advance, at, body.as_ref(), 1.0)?;
                    let mut g = vec![[0.0; 3]; x.len()];
                    for e in &terms {
                        potential += e.add_gradient(x, 1.0, &mut g)?;
                    }
                    gradient += g
                        .iter()
                        .zip(&scene.garment.pinned)
                        .filter(|(_, &pinned)| !pinned)
                        .map(|(gi, _)| gi.iter().map(|c| c * c).sum::<f64>())
                        .sum::<f64>()
                        .sqrt();
                    steps += 1;
                }
            }
        }
        let pct = |a: f64, b: usize| 100.0 * a / b.max(1) as f64;
        Ok(BTreeMap::from([
            (POTENTIAL.to_string(), potential / steps.max(1) as f64),
            (GRADIENT_NORM.to_string(), gradient / steps.max(1) as f64),
            (INSIDE_PERCENT.to_string(), pct(inside as f64, vertices)),
            (EDGE_STRAIN_PERCENT.to_string(), pct(strain, edges)),
            (
                FRAMES_REACHED_PERCENT.to_string(),
                pct(reached as f64, wanted),
            ),
        ]))
    }

    fn primary_metric(&self) -> &'static str {
        POTENTIAL
    }

    fn stage_name(&self, stage: &Stage) -> String {
        format!(
            "rollout {}, collision weight {:.3}",
            stage.rollout,
            self.training.collision_weight_at(stage.collision)
        )
    }

    fn advance(&self, stage: &mut Stage, end: &StepEnd<'_, Term>) -> bool {
        let next = Stage {
            rollout: self.training.rollout_at(end.step),
            collision: self.training.collision_level(end.step, end.total),
        };
        let changed = next != *stage;
        *stage = next;
        changed
    }

    fn enter_stage(&mut self, model: Hood, stage: &Stage) -> Hood {
        self.stage = stage.clone();
        model
    }
    fn memory(&self) -> Option<serde_json::Value> {
        if self.training.replay <= 0.0 {
            return None;
        }
        let bits = |x: &[[f64; 3]]| x.iter().flatten().map(|v| v.to_bits()).collect();
        let memory = Memory {
            evaluated: self.evaluated,
            live: self
                .live
                .iter()
                .map(|l| {
                    l.as_ref().map(|l| SavedLive {
                        item: l.origin.0,
                        rollout: l.origin.1,
                        frame: l.frame,
                        age: l.age,
                        prev: bits(&l.state.prev),
                        cur: bits(&l.state.cur),
                    })
                })
                .collect(),
        };
        serde_json::to_value(memory).ok()
    }

    fn restore_memory(&mut self, memory: serde_json::Value) -> std::result::Result<(), String> {
        let memory: Memory = serde_json::from_value(memory).map_err(|e| e.to_string())?;
        if memory.live.len() != REPLAY_SLOTS {
            return Err(format!(
                "{} kept rollouts (weft keeps {REPLAY_SLOTS})",
                memory.live.len()
            ));
        }
        let mut live = Vec::with_capacity(REPLAY_SLOTS);
        for saved in memory.live {
            live.push(match saved {
                Some(saved) => Some(self.restored(saved)?),
                None => None,
            });
        }
        self.evaluated = memory.evaluated;
        self.live = live;
        Ok(())
    }
}

/// Saves the normalisers as `dir/hood.json` (atomically).
pub fn save_stats(dir: &Path, stats: &HoodStats) -> Result<()> {
    crate::run::save_json(dir, STATS_FILE, stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One 300-vertex skirt on one body, a short walk.
    fn task(random_centres: bool) -> HoodTask {
        task_with(HoodTraining {
            random_centres,
            ..small()
        })
    }

    fn small() -> HoodTraining {
        HoodTraining {
            garments: vec!["skirt".into()],
            styles: 1,
            shapes: 1,
            garment_vertices: 300,
            motions: vec!["walk".into()],
            motion_frames: 12,
            max_rollout: 2,
            validation_scenes: 1,
            validation_frames: 5,
            replay: 0.0,
            // HOOD's terms, so that a test may take the projection away.
            collision_weight: 1.0,
            stretching_weight: 1.0,
            ..HoodTraining::cpu()
        }
    }

    /// A term left out of the loss needs the projection that does its work: the
    /// `cpu` preset trains, and without `[model] project_margin` / `project_stretch`
    /// its training settings are refused by name.
    #[test]
    fn terms_left_out_need_the_projection() {
        let device = weft_nn::backend::cpu();
        let body = || weft_body::default_body().unwrap();
        let stats = || Some(HoodStats::identity(3));
        let cpu = HoodConfig::preset("cpu").unwrap();
        let training = HoodTraining {
            collision_weight: 0.0,
            stretching_weight: 0.0,
            ..small()
        };
        assert!(HoodTask::new(&cpu, &training, body(), stats(), 7, &device).is_ok());
        for (config, field) in [
            (
                HoodConfig {
                    project_margin: None,
                    ..cpu.clone()
                },
                "train.collision_weight",
            ),
            (
                HoodConfig {
                    project_stretch: None,
                    ..cpu.clone()
                },
                "train.stretching_weight",
            ),
        ] {
            let e = HoodTask::new(&config, &training, body(), stats(), 7, &device)
                .err()
                .unwrap()
                .to_string();
            assert!(e.contains(field), "{e}");
        }
    }

    fn task_with(training: HoodTraining) -> HoodTask {
        task_on(
            HoodConfig::preset("cpu").unwrap(),
            training,
            weft_nn::backend::cpu(),
        )
    }

    fn task_on(config: HoodConfig, training: HoodTraining, device: Device) -> HoodTask {
        // Pass-through normalisers: fitting them takes implicit steps this test does not
        // need.
        let stats = HoodStats::identity(config.levels);
        let body = weft_body::default_body().unwrap();
        HoodTask::new(&config, &training, body, Some(stats), 7, &device).unwrap()
    }

    /// Samples and the validation's corners are drawn from the run's material space
    /// (`[model.materials]`): with `μ` pinned to one value every material has it,
    /// and the other fields keep HOOD's ranges.
    #[test]
    fn materials_are_drawn_from_the_runs_space() {
        let mut config = HoodConfig::preset("cpu").unwrap();
        config.materials.mu = [20_000.0; 2];
        let t = task_on(config, small(), weft_nn::backend::cpu());
        let hood = weft_sim::MaterialRanges::hood();
        let mut seen = 0;
        for item in 0..8 {
            let list = match t.sample(item, 1).materials {
                Materials::Uniform(m) => vec![m],
                Materials::PerVertex(m) => m,
            };
            for m in list {
                assert!((m.lame().0 - 20_000.0).abs() < 1e-6, "{m:?}");
                assert!(hood.outside(&m).is_empty(), "{m:?}");
                seen += 1;
            }
        }
        assert!(seen >= 8);
        let corners = [0, 1].map(|end| t.config.materials.corner(end));
        assert!(corners.iter().all(|m| (m.lame().0 - 20_000.0).abs() < 1e-6));
        assert!(corners[0].density < corners[1].density);
    }

    #[test]
    fn samples_draw_their_hierarchy_centres_among_the_tied_ones() {
        let t = task(true);
        let sets = &t.garments[0].centres;
        assert_eq!(sets.len(), 1, "the skirt is one piece");
        assert!(sets[0].len() > 1, "a tube has tied centres: {:?}", sets[0]);
        let mut seen = std::collections::BTreeSet::new();
        let mut level_sets = std::collections::BTreeSet::new();
        for item in 0..12 {
            let s = t.sample(item, 1);
            let c = s.centres.clone().unwrap();
            assert_eq!(c.len(), 1);
            assert!(sets[0].contains(&c[0]));
            // The sample's scene pools around it: it is a node of every level.
            let scene = t.scene(&s, 3).unwrap();
            assert_eq!(scene.garment.level_of[c[0] as usize], 2);
            seen.insert(c[0]);
            level_sets.insert(scene.garment.levels[1].clone());
        }
        assert!(seen.len() > 1 && level_sets.len() > 1, "{seen:?}");
        // Off, every sample keeps inference's hierarchy.
        let t = task(false);
        let s = t.sample(0, 1);
        assert!(s.centres.is_none());
        let default = t.scene(&s, 3).unwrap().garment;
        let c = component_center_sets(&t.garments[0].mesh.graph());
        let first = default.clone().recentred(&[c[0][0]]).unwrap();
        assert_eq!(default.levels[..2], first.levels[..2]);
    }

    /// `[train] open_front`: samples draw the skirt opened down the front, buttoned with
    /// even odds; a buttoned sample's scene has the button edges and a buttons term of
    /// positive energy once the pairs are pulled apart, an unbuttoned one neither. Off
    /// (the default), no garment is opened.
    #[test]
    fn open_front_samples_train_buttoned_and_unbuttoned() {
        let t = task_with(HoodTraining {
            open_front: 1.0,
            ..small()
        });
        let open = t.garments[0].open.as_ref().unwrap();
        assert_eq!(open.buttons.len(), OPEN_FRONT_BUTTONS);
        assert!(open.mesh.vertex_count() > t.garments[0].mesh.vertex_count());
        let (mut buttoned, mut unbuttoned) = (0, 0);
        for item in 0..16 {
            let s = t.sample(item, 1);
            let scene = t.scene(&s, 3).unwrap();
            assert_eq!(scene.garment.rest.vertex_count(), open.mesh.vertex_count());
            if s.open == Some(true) {
                buttoned += 1;
                assert_eq!(scene.garment.buttons.len(), 2 * OPEN_FRONT_BUTTONS);
                let springs = scene.cloth.buttons().unwrap();
                let mut x = open.mesh.positions.clone();
                let [a, _] = springs.pairs()[0];
                x[a as usize][0] += 0.01;
                assert!(springs.value(&x).unwrap() > 0.0);
            } else {
                unbuttoned += 1;
                assert!(scene.garment.buttons.is_empty() && scene.cloth.buttons().is_none());
            }
        }
        assert!(buttoned > 0 && unbuttoned > 0, "{buttoned} / {unbuttoned}");
        let closed = task(true);
        assert!(closed.garments[0].open.is_none());
        assert_eq!(closed.sample(3, 1).open, None);
    }

    fn scalar(t: Tensor<1>) -> f64 {
        t.into_data()
            .convert::<f64>()
            .try_into_vec::<f64>()
            .unwrap()[0]
    }

    /// The edge term sees only relative error: a prediction shifted as a whole from the
    /// implicit step costs nothing in it (and 1 cm² in the position term), one vertex
    /// off by 1 cm costs 1 cm² on each directed edge it ends, averaged over the edges.
    #[test]
    fn solver_edge_loss_measures_relative_error_only() {
        let device = weft_nn::backend::cpu();
        // A triangle and a pendant vertex: edges 0–1, 1–2, 2–0, 2–3, both directions.
        let edges: Vec<[u32; 2]> = [[0, 1], [1, 2], [2, 0], [2, 3]]
            .iter()
            .flat_map(|&[a, b]| [[a, b], [b, a]])
            .collect();
        let index = EdgeIndex::new(&edges, &device);
        let target = [
            [0.0, 0.0, 0.0],
            [0.1, 0.0, 0.0],
            [0.0, 0.1, 0.0],
            [0.0, 0.2, 0.0],
        ];
        let value = scalar;
        let shifted: Vec<[f64; 3]> = target.iter().map(|p| [p[0], p[1], p[2] + 0.01]).collect();
        let (x, t) = (
            positions_tensor(&shifted, &device),
            positions_tensor(&target, &device),
        );
        assert!(value(solver_edge_loss(x.clone(), t.clone(), &index)).abs() < 1e-9);
        assert!((value(solver_loss(x, t.clone())) - 1.0).abs() < 1e-4);
        let mut moved = target.to_vec();
        moved[2][0] += 0.01;
        let x = positions_tensor(&moved, &device);
        // Vertex 2 ends 3 of the 4 undirected edges: 6 of the 8 directed ones.
        let expected = 6.0 / 8.0;
        assert!((value(solver_edge_loss(x.clone(), t.clone(), &index)) - expected).abs() < 1e-4);
        assert!((value(solver_loss(x, t)) - 0.25).abs() < 1e-4);
    }

    /// `[train] solver_edge_weight` adds the edge term (0 leaves it out); an item's
    /// losses include it, finite and above zero for an untrained network.
    #[test]
    fn the_solver_edge_term_enters_the_loss_when_weighted() {
        let mut t = task_with(HoodTraining {
            solver_edge_weight: 2.0,
            ..small()
        });
        let terms = t.terms(&Stage::default());
        assert!(terms.contains(&(Term::SolverEdges, 2.0)), "{terms:?}");
        let without = task_with(HoodTraining {
            solver_edge_weight: 0.0,
            ..small()
        });
        assert!(!without
            .terms(&Stage::default())
            .iter()
            .any(|(t, _)| *t == Term::SolverEdges));
        let model = t.config.init(&t.device).unwrap();
        let names: Vec<Term> = terms.iter().map(|(t, _)| *t).collect();
        let losses = t.losses(&model, 0, &names).unwrap();
        let at = names.iter().position(|t| *t == Term::SolverEdges).unwrap();
        let edge = scalar(losses[at].clone());
        assert!(edge.is_finite() && edge > 0.0, "{edge}");
    }

    /// `[train] stretching_weight` weights the stretching term and `collision_weight`
    /// the collision term's stiffness: with both 0 every item's collision loss is
    /// exactly 0, where HOOD's weights give some a positive one, and the other terms
    /// (each logged unweighted) are unchanged to the bit.
    #[test]
    fn stretching_and_collision_weights_reach_the_loss() {
        let mut hood = task_with(small());
        let mut off = task_with(HoodTraining {
            stretching_weight: 0.0,
            collision_weight: 0.0,
            ..small()
        });
        let terms = off.terms(&Stage::default());
        assert!(terms.contains(&(Term::Stretching, 0.0)), "{terms:?}");
        assert!(hood
            .terms(&Stage::default())
            .contains(&(Term::Stretching, 1.0)));
        let model = hood.config.init(&hood.device).unwrap();
        let names: Vec<Term> = terms.iter().map(|(t, _)| *t).collect();
        let at = |term| names.iter().position(|t| *t == term).unwrap();
        let mut touched = 0;
        for item in 0..8 {
            let a = hood.losses(&model, item, &names).unwrap();
            let b = off.losses(&model, item, &names).unwrap();
            let value = |l: &[Tensor<1>], term| scalar(l[at(term)].clone());
            assert_eq!(value(&b, Term::Collision), 0.0, "item {item}");
            touched += usize::from(value(&a, Term::Collision) > 0.0);
            for term in [Term::Stretching, Term::Inertia, Term::Solver] {
                assert_eq!(value(&a, term), value(&b, term), "item {item}, {term:?}");
            }
        }
        assert!(touched > 0, "no item touched the body");
    }

    /// `solver_coast` is logged with weight 0 beside the solver terms, and an untrained
    /// network (its decoder's last layer zero) coasts: its `solver` term is exactly
    /// that, and both are above zero. Without solver terms it is not logged.
    #[test]
    fn the_coasting_distance_is_logged_beside_the_solver_term() {
        let mut t = task_with(small());
        let terms = t.terms(&Stage::default());
        assert!(terms.contains(&(Term::SolverCoast, 0.0)), "{terms:?}");
        let potential_only = task_with(HoodTraining {
            solver_weight: 0.0,
            solver_edge_weight: 0.0,
            ..small()
        });
        assert!(!potential_only
            .terms(&Stage::default())
            .iter()
            .any(|(t, _)| *t == Term::SolverCoast));
        let model = t.config.init(&t.device).unwrap();
        let names: Vec<Term> = terms.iter().map(|(t, _)| *t).collect();
        let losses = t.losses(&model, 0, &names).unwrap();
        let value = |term| scalar(losses[names.iter().position(|t| *t == term).unwrap()].clone());
        let (solver, coast) = (value(Term::Solver), value(Term::SolverCoast));
        assert!(coast > 0.0, "{coast}");
        assert!(
            (solver - coast).abs() <= 1e-4 * coast,
            "{solver} against {coast}"
        );
    }

    /// A model whose step ends in a projection (`[model] project_*`) takes the loss of
    /// the network's own step and goes on from the projected garment: the untrained
    /// network coasts from the 3 mm position noise, which leaves edges more than 5 %
    /// over their rest length; with a 1 % stretch bound the kept state is near it, and
    /// the loss is the unprojected model's to the bit.
    #[test]
    fn a_projected_step_goes_on_from_the_projected_garment() {
        let training = HoodTraining {
            replay: 1.0,
            ..small()
        };
        let plain = HoodConfig {
            project_stretch: None,
            project_compression: None,
            project_margin: None,
            ..HoodConfig::preset("cpu").unwrap()
        };
        let projected = HoodConfig {
            project_stretch: Some(0.01),
            project_margin: Some(0.002),
            ..plain.clone()
        };
        let terms = [Term::Stretching, Term::Inertia];
        let mut outcome = Vec::new();
        for config in [plain, projected] {
            let mut t = task_on(config, training.clone(), weft_nn::backend::cpu());
            let model = t.config.init(&t.device).unwrap();
            let losses: Vec<_> = t
                .losses(&model, 0, &terms)
                .unwrap()
                .into_iter()
                .map(|l| l.into_data())
                .collect();
            let live = t.live.iter().flatten().next().expect("a kept rollout");
            let rest = t.scene(&live.sample, 2).unwrap().garment.rest;
            let x = &live.state.cur;
            let strain = rest
                .edges()
                .iter()
                .map(|&[a, b]| {
                    let (a, b) = (a as usize, b as usize);
                    weft_mesh::vec3::dist(x[a], x[b])
                        / weft_mesh::vec3::dist(rest.positions[a], rest.positions[b])
                        - 1.0
                })
                .fold(f64::NEG_INFINITY, f64::max);
            outcome.push((losses, strain));
        }
        let [(plain_losses, plain_strain), (losses, strain)] = &outcome[..] else {
            unreachable!()
        };
        assert!(*plain_strain > 0.05, "{plain_strain}");
        assert!(*strain < 0.03, "{strain}");
        assert_eq!(losses, plain_losses);
    }

    /// `[train] replay`: once every slot holds a rollout, an item that draws a replay
    /// goes on from its slot's state at the next frame, and a task restored from the
    /// saved memory evaluates that item to the same bits (a resumed run repeats the
    /// uninterrupted one). A saved state of the wrong size is refused; without replay
    /// nothing is kept.
    #[test]
    fn replayed_items_go_on_from_kept_rollouts_and_survive_a_checkpoint() {
        let training = HoodTraining {
            replay: 1.0,
            motion_frames: 30,
            ..small()
        };
        let mut t = task_with(training.clone());
        let model = t.config.init(&t.device).unwrap();
        let terms = [Term::Stretching, Term::Inertia];
        for item in 0..REPLAY_SLOTS {
            t.losses(&model, item, &terms).unwrap();
        }
        let kept: Vec<Live> = t.live.iter().map(|l| l.clone().unwrap()).collect();
        assert!(kept.iter().all(|l| l.age == 1 && l.origin.1 == 1));
        let memory = t.memory().unwrap();
        let mut resumed = task_with(training);
        resumed.restore_memory(memory.clone()).unwrap();
        assert_eq!(resumed.memory(), Some(memory.clone()));

        let item = 1000;
        let a = t.losses(&model, item, &terms).unwrap();
        let b = resumed.losses(&model, item, &terms).unwrap();
        for (a, b) in a.into_iter().zip(b) {
            assert_eq!(a.into_data(), b.into_data());
        }
        let next = t.live[0].as_ref().unwrap();
        assert_eq!(
            next.origin, kept[0].origin,
            "slot 0 went on with its rollout"
        );
        assert_eq!((next.age, next.frame), (2, kept[0].frame + 1));
        assert_ne!(next.state.cur, kept[0].state.cur);

        let mut bad = memory;
        bad["live"][0]["cur"].as_array_mut().unwrap().pop();
        let e = resumed.restore_memory(bad).unwrap_err();
        assert!(e.contains("coordinates"), "{e}");
        let mut bad = resumed.memory().unwrap();
        bad["live"][0]["rollout"] = serde_json::json!(1_000_000);
        let e = resumed.restore_memory(bad).unwrap_err();
        assert!(e.contains("max_rollout"), "{e}");
        assert!(task(false).memory().is_none());
    }
}
