//! The configuration of a HOOD run: what it trains on (bodies × procedural garments ×
//! motions, no simulated data), its curriculum and its loss settings (`[train]` beside
//! the loop's), and the run type.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use weft_models::hood::HoodConfig;
use weft_models::ModelKind;

use crate::config::TrainConfig;
use crate::error::{Result, TrainError};
use crate::optim::{AdamParams, LrScheduleConfig, OptimizerConfig};
use crate::run_config::{ModelSettings, RunConfig, TaskSettings};

/// HOOD's task settings, in the `[train]` table beside the loop's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HoodTraining {
    /// The body model (an SMPL-format `.npz`); none: weft's built-in body.
    pub body: Option<PathBuf>,
    /// Garment kinds drawn (weft-garment's names: skirt, dress, tshirt, tank,
    /// longsleeve, shorts, pants, jumpsuit).
    pub garments: Vec<String>,
    /// Garment styles per kind (each a seed of weft-garment's style draw).
    pub styles: usize,
    /// Vertices of each training garment (about).
    pub garment_vertices: usize,
    /// Body shapes of the garment pool (each garment kind and style is built on each).
    pub shapes: usize,
    /// Body shapes: the first `shape_components` β are drawn uniformly in
    /// `[−shape_range, shape_range]` per sample (HOOD's code: ±3 on 10; the paper: ±2).
    pub shape_range: f64,
    /// How many β components are drawn (the rest are 0).
    pub shape_components: usize,
    /// Procedural motions drawn (weft-motion's names: walk, run, jump, dance, kick,
    /// raise-arms, twist, bow).
    pub motions: Vec<String>,
    /// Motion files (AMASS `.npz`, BVH) drawn beside the procedural ones.
    pub motion_files: Vec<PathBuf>,
    /// Frames of each procedural motion at 30 fps (the pool's motions are resampled to
    /// `[model] step_fps`, so the rollout lengths below count network steps).
    pub motion_frames: usize,
    /// The longest rollout of the curriculum (HOOD: 5).
    pub max_rollout: usize,
    /// Steps between rollout-length increases (HOOD: 5 000); the rollout starts at 1.
    pub rollout_every: usize,
    /// Probability that a sample starts from the skinned garment at rest, as a rollout
    /// does, while the rollout is one step long; afterwards every sample does (HOOD).
    /// With `[model] settle_dt` > 0 such a start takes the settling step first (body
    /// still, that time step); otherwise the skinned garment moves with the body.
    pub settle_probability: f64,
    /// Gaussian noise on the start positions (m; HOOD: 3 mm).
    pub noise: f64,
    /// The collision term's weight ramps from this (a factor of HOOD's stiffness
    /// 5·10⁵ J/m³) …
    pub collision_start: f64,
    /// … to 1 between these two shares of the run.
    pub collision_ramp: [f64; 2],
    /// The collision term's weight once ramped (HOOD: 1), a factor on the whole ramp.
    /// 0 leaves the term out of the loss: a model whose step ends in a contact
    /// projection (`[model] project_margin`) has its cloth kept out of the body by the
    /// projection, as position-based cloth is, and the term's gradient, the largest of
    /// the potential's, then only teaches the network what the projection already does
    /// (docs/hood.md item 16). Validation keeps it at full stiffness.
    pub collision_weight: f64,
    /// The stretching term's weight (HOOD: 1). 0 leaves stretching to the step
    /// projection's strain bounds (`[model] project_stretch`, `project_compression`)
    /// and to the implicit step's positions (`solver_weight`), which hold it too: the
    /// term is hundreds of times stiffer than inertia, and its gradient drowns the
    /// garment-wide motion the network is to learn (docs/hood.md items 14 and 16).
    pub stretching_weight: f64,
    /// Share of samples whose garment is made of two materials, split by a random plane
    /// (HOOD's training never sees heterogeneous materials; run-time maps need it).
    pub two_materials: f64,
    /// Share of samples whose garment is opened down the front (weft-garment's
    /// `Garment::open_front`, with [`OPEN_FRONT_BUTTONS`] button pairs) and buttoned or
    /// not with even odds, so that button edges and the buttons term are not first seen
    /// at run time (HOOD never trains on them). 0: every garment closed, as HOOD.
    pub open_front: f64,
    /// Pool each sample's hierarchy around a centre drawn among each garment component's
    /// minimum-eccentricity vertices (HOOD's code; its augmentation of the levels), not
    /// always the first of them as inference does.
    pub random_centres: bool,
    /// Weight of the distance to weft-sim's implicit step from the same state (cm²). 0
    /// is HOOD: the potential alone. The potential is badly conditioned (stretching is
    /// hundreds of times stiffer than inertia), so its gradient teaches the network the
    /// implicit step slowly; the step itself, solved by Newton on the same potential, is
    /// a well-conditioned target (docs/hood.md).
    pub solver_weight: f64,
    /// Weight of the distance between the predicted and the implicit step's edge vectors
    /// (cm², mean over the mesh edges). The position distance above is dominated by
    /// smooth, garment-wide errors; a vertex-to-vertex jitter of a few millimetres, which
    /// is what a rollout's edge strain is made of, hardly shows in it. Edge vectors see
    /// only the relative error (docs/hood.md item 10). 0: no such term (HOOD).
    pub solver_edge_weight: f64,
    /// Probability that an item goes on with a rollout an earlier item left (the
    /// model's own predicted state, its garment, motion and material, from the frame it
    /// reached) instead of starting from the skinned garment. 0 is HOOD: every item
    /// starts skinned, so the network never trains on the states its own errors lead to
    /// in a long rollout, and a rollout that drifts keeps drifting (docs/hood.md).
    pub replay: f64,
    /// The most steps a kept rollout runs before its slot starts afresh.
    pub replay_frames: usize,
    /// Validation scenes (held-out shapes, motions and materials) and their frames.
    pub validation_scenes: usize,
    /// Steps of each validation rollout.
    pub validation_frames: usize,
}

impl HoodTraining {
    /// Seed 004's training as the reference reads it (garments of about 4 000
    /// vertices, rollouts up to 5 steps growing every 5 000 steps, the collision ramp
    /// from a hundredth to full strength over the middle of the run).
    pub fn paper() -> Self {
        HoodTraining {
            body: None,
            garments: [
                "tshirt",
                "tank",
                "longsleeve",
                "shorts",
                "pants",
                "dress",
                "skirt",
            ]
            .map(String::from)
            .to_vec(),
            styles: 4,
            garment_vertices: 4000,
            shapes: 16,
            shape_range: 2.0,
            shape_components: 2,
            motions: [
                "walk",
                "run",
                "jump",
                "dance",
                "kick",
                "raise-arms",
                "twist",
                "bow",
            ]
            .map(String::from)
            .to_vec(),
            motion_files: Vec::new(),
            motion_frames: 150,
            max_rollout: 5,
            rollout_every: 5000,
            settle_probability: 0.5,
            noise: 0.003,
            collision_start: 0.01,
            collision_ramp: [0.33, 0.66],
            collision_weight: 1.0,
            stretching_weight: 1.0,
            two_materials: 0.25,
            open_front: 0.0,
            random_centres: true,
            solver_weight: 0.0,
            solver_edge_weight: 0.0,
            replay: 0.0,
            replay_frames: 60,
            validation_scenes: 4,
            validation_frames: 60,
        }
    }

    /// The CPU preset: garments of about 1 000 vertices (skirt, dress, t-shirt), the
    /// rollout growing every 300 steps, the solver's step as a target, half the items
    /// going on from earlier rollouts (docs/hood.md items 6, 7 and 9). No edge-vector
    /// target: item 10 gave it against jitter strain, which the `cpu` model's step
    /// projection now bounds, and without it the hem moves 12–18 % faster against the
    /// hips (item 15). No collision or stretching term either: the projection keeps
    /// the cloth out of the body and within its length, and without their gradients
    /// the network learns more of its implicit-step target and the hem swings as its
    /// objective's does (item 16).
    pub fn cpu() -> Self {
        HoodTraining {
            garments: ["skirt", "dress", "tshirt"].map(String::from).to_vec(),
            styles: 3,
            garment_vertices: 1000,
            shapes: 6,
            rollout_every: 300,
            motion_frames: 90,
            solver_weight: 1.0,
            collision_ramp: [0.2, 0.4],
            collision_weight: 0.0,
            stretching_weight: 0.0,
            replay: 0.5,
            validation_scenes: 2,
            validation_frames: 45,
            ..HoodTraining::paper()
        }
    }

    /// The rollout length after `step` steps.
    pub fn rollout_at(&self, step: usize) -> usize {
        (1 + step / self.rollout_every.max(1)).min(self.max_rollout)
    }

    /// The collision weight's level (0 ..= [`COLLISION_LEVELS`]) after `step` of `total`
    /// steps: the ramp is taken in steps so that a change is a stage the log names.
    pub fn collision_level(&self, step: usize, total: usize) -> usize {
        let s = step as f64 / total.max(1) as f64;
        let [a, b] = self.collision_ramp;
        let f = if b > a {
            ((s - a) / (b - a)).clamp(0.0, 1.0)
        } else if s >= a {
            1.0
        } else {
            0.0
        };
        (f * COLLISION_LEVELS as f64).floor() as usize
    }

    /// The collision weight of a level: geometric from `collision_start` to 1, times
    /// `collision_weight`.
    pub fn collision_weight_at(&self, level: usize) -> f64 {
        let f = level.min(COLLISION_LEVELS) as f64 / COLLISION_LEVELS as f64;
        self.collision_weight * self.collision_start.powf(1.0 - f)
    }

    /// Checks every range; errors name the field as in config.toml.
    pub fn validate_values(&self) -> Result<()> {
        for (field, v) in [
            ("train.styles", self.styles),
            ("train.shapes", self.shapes),
            ("train.garment_vertices", self.garment_vertices),
            ("train.motion_frames", self.motion_frames),
            ("train.max_rollout", self.max_rollout),
            ("train.rollout_every", self.rollout_every),
            ("train.validation_frames", self.validation_frames),
            ("train.replay_frames", self.replay_frames),
        ] {
            if v == 0 {
                return Err(TrainError::config(field, v, "at least 1"));
            }
        }
        if self.garments.is_empty() {
            return Err(TrainError::config(
                "train.garments",
                "[]",
                "at least one garment kind",
            ));
        }
        if self.motions.is_empty() && self.motion_files.is_empty() {
            return Err(TrainError::config(
                "train.motions",
                "[]",
                "at least one procedural motion or motion file",
            ));
        }
        if self.motion_frames < self.max_rollout + 3 {
            return Err(TrainError::config(
                "train.motion_frames",
                self.motion_frames,
                &format!("at least max_rollout + 3 = {}", self.max_rollout + 3),
            ));
        }
        for (field, v) in [
            ("train.settle_probability", self.settle_probability),
            ("train.two_materials", self.two_materials),
            ("train.open_front", self.open_front),
            ("train.replay", self.replay),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(TrainError::config(field, v, "between 0 and 1"));
            }
        }
        for (field, v) in [("train.collision_start", self.collision_start)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(TrainError::config(field, v, "a positive number"));
            }
        }
        for (field, v) in [
            ("train.collision_weight", self.collision_weight),
            ("train.stretching_weight", self.stretching_weight),
            ("train.solver_weight", self.solver_weight),
            ("train.solver_edge_weight", self.solver_edge_weight),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(TrainError::config(field, v, "a weight >= 0"));
            }
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return Err(TrainError::config(
                "train.noise",
                self.noise,
                "metres, at least 0",
            ));
        }
        if !(self.shape_range.is_finite() && self.shape_range >= 0.0) {
            return Err(TrainError::config(
                "train.shape_range",
                self.shape_range,
                "at least 0",
            ));
        }
        let [a, b] = self.collision_ramp;
        if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) || a > b {
            return Err(TrainError::config(
                "train.collision_ramp",
                format!("[{a}, {b}]"),
                "two shares of the run, 0 <= start <= end <= 1",
            ));
        }
        Ok(())
    }
}

/// The collision ramp is taken in this many steps.
pub const COLLISION_LEVELS: usize = 8;

/// Button pairs down the front of an open-front training garment
/// ([`HoodTraining::open_front`]): a shirt's worth.
pub const OPEN_FRONT_BUTTONS: usize = 6;

impl Default for HoodTraining {
    fn default() -> Self {
        HoodTraining::paper()
    }
}

impl TaskSettings for HoodTraining {
    fn preset(name: &str) -> Result<Self> {
        match name {
            "paper" => Ok(HoodTraining::paper()),
            "cpu" => Ok(HoodTraining::cpu()),
            other => Err(TrainError::config("preset", other, "one of cpu, paper")),
        }
    }

    fn validate(&self) -> Result<()> {
        self.validate_values()
    }
}

impl ModelSettings for HoodConfig {
    const KIND: ModelKind = ModelKind::Hood;

    fn preset(name: &str) -> Result<Self> {
        Ok(HoodConfig::preset(name)?)
    }

    fn check(&self) -> std::result::Result<(), String> {
        self.validate().map_err(|e| e.to_string())
    }

    /// HOOD: Adam 5e-5 halving every 50 000 steps, gradient clipping at norm 1, 150 000
    /// iterations (`paper`); `cpu`: Adam 1e-3 with cosine decay over 1 500 steps.
    fn trainer(name: &str) -> Result<TrainConfig> {
        let base = TrainConfig::preset(name)?;
        let paper = name == "paper";
        Ok(TrainConfig {
            steps: if paper { 150_000 } else { 1500 },
            learning_rate: if paper { 5e-5 } else { 1e-3 },
            min_learning_rate: if paper { 5e-7 } else { 1e-5 },
            optimizer: OptimizerConfig::Adam(AdamParams::default()),
            lr_schedule: if paper {
                LrScheduleConfig::Step {
                    every: 50_000,
                    factor: 0.5,
                }
            } else {
                LrScheduleConfig::Cosine
            },
            batch: 1,
            grad_clip_norm: Some(1.0),
            checkpoint_every: if paper { 5000 } else { 250 },
            validate_every: if paper { 5000 } else { 250 },
            ..base
        })
    }
}

/// A HOOD run's configuration.
pub type HoodRun = RunConfig<HoodConfig, HoodTraining>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_ranges_and_schedules() {
        let cpu = HoodRun::preset("cpu").unwrap();
        cpu.train.task.validate_values().unwrap();
        HoodRun::preset("paper")
            .unwrap()
            .train
            .task
            .validate_values()
            .unwrap();
        let t = &cpu.train.task;
        assert_eq!(t.rollout_at(0), 1);
        assert_eq!(t.rollout_at(300), 2);
        assert_eq!(t.rollout_at(100_000), 5);
        assert_eq!(t.collision_level(0, 3000), 0);
        assert_eq!(t.collision_level(3000, 3000), COLLISION_LEVELS);
        // The `cpu` preset leaves the term out; HOOD's weight ramps it up.
        assert!((0..=COLLISION_LEVELS).all(|l| t.collision_weight_at(l) == 0.0));
        let hood = HoodTraining {
            collision_weight: 1.0,
            ..t.clone()
        };
        assert!((hood.collision_weight_at(0) - 0.01).abs() < 1e-12);
        assert!((hood.collision_weight_at(COLLISION_LEVELS) - 1.0).abs() < 1e-12);
        assert!(hood.collision_weight_at(3) < hood.collision_weight_at(4));
        for (bad, field) in [
            (
                HoodTraining {
                    garments: vec![],
                    ..HoodTraining::cpu()
                },
                "train.garments",
            ),
            (
                HoodTraining {
                    motion_frames: 5,
                    ..HoodTraining::cpu()
                },
                "train.motion_frames",
            ),
            (
                HoodTraining {
                    collision_ramp: [0.7, 0.2],
                    ..HoodTraining::cpu()
                },
                "train.collision_ramp",
            ),
            (
                HoodTraining {
                    collision_weight: -1.0,
                    ..HoodTraining::cpu()
                },
                "train.collision_weight",
            ),
            (
                HoodTraining {
                    stretching_weight: f64::INFINITY,
                    ..HoodTraining::cpu()
                },
                "train.stretching_weight",
            ),
            (
                HoodTraining {
                    noise: -1.0,
                    ..HoodTraining::cpu()
                },
                "train.noise",
            ),
            (
                HoodTraining {
                    solver_edge_weight: f64::NAN,
                    ..HoodTraining::cpu()
                },
                "train.solver_edge_weight",
            ),
        ] {
            let e = bad.validate_values().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
        assert!(cpu.to_toml().unwrap().contains("rollout_every"));
        // Every name in both presets is one the garment and motion libraries know.
        for preset in [HoodTraining::cpu(), HoodTraining::paper()] {
            for g in &preset.garments {
                assert!(weft_garment::GarmentKind::parse(g).is_ok(), "garment {g}");
            }
            for m in &preset.motions {
                assert!(weft_motion::MotionKind::parse(m).is_some(), "motion {m}");
            }
        }
    }
}
