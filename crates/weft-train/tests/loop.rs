//! The training loop on a small stand-in model: bit-for-bit resume (also after a "kill"
//! between checkpoints), mismatching checkpoints, the non-finite guard, the step-2
//! freeze, and that the loss goes down.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use burn::module::{Module, ParamGroup};
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{DType, Device, Tensor, TensorData};
use serde::Serialize;
use weft_mesh::primitives::grid;
use weft_mesh::TriMesh;
use weft_models::ModelKind;
use weft_nn::backend::{cpu_autodiff, seeded};
use weft_sim::Sphere;
use weft_train::loss::{
    collision_energies, edge_loss, gravity_energy, membrane_energies, normal_loss, physics_loss,
    rest_frames, vertex_loss, GarmentTopology, PhysicsImpl, Targets,
};
use weft_train::tasks::multilevel::{Phase, ScheduleConfig, ScheduleState, Term, TermWeights};
use weft_train::{
    train, Metrics, RunDir, RunOptions, StepEnd, TrainConfig, TrainError, TrainTable, TrainTask,
};

const FRAMES: usize = 3;
const ITEMS: usize = 5;

#[derive(Module, Debug)]
struct Toy {
    first: Linear,
    second: Linear,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
struct ToyConfig {
    hidden: usize,
}

impl Toy {
    fn new(cfg: &ToyConfig, n: usize, device: &Device) -> Self {
        Toy {
            first: LinearConfig::new(3, cfg.hidden).init(device),
            second: LinearConfig::new(cfg.hidden, 3 * n).init(device),
        }
    }

    fn forward(&self, features: Tensor<2>, rest: Tensor<3>) -> Tensor<3> {
        let [t, n, _] = rest.dims();
        let h = self.first.forward(features).tanh();
        let offsets: Tensor<3> = self.second.forward(h).reshape([t, n, 3]).mul_scalar(0.01);
        rest + offsets
    }
}

struct ToyTask {
    mesh: TriMesh,
    topology: GarmentTopology,
    device: Device,
    weights: TermWeights,
    /// The two-step schedule, Multilevel's, as a staged task.
    schedule: ScheduleConfig,
    /// Items whose losses are made NaN (to test the guard).
    poisoned: Vec<usize>,
}

fn phase_of(item: usize, t: usize) -> f64 {
    0.37 * (item * FRAMES + t) as f64
}

impl ToyTask {
    fn new(cfg: &Cfg) -> Self {
        let mesh = grid(3, 3, 0.1);
        ToyTask {
            topology: GarmentTopology::new(&mesh).unwrap(),
            mesh,
            device: cpu_autodiff(),
            weights: TermWeights::default(),
            schedule: cfg.task.schedule.clone(),
            poisoned: Vec::new(),
        }
    }

    fn features(&self, item: usize) -> Tensor<2> {
        let v: Vec<f32> = (0..FRAMES)
            .flat_map(|t| {
                let p = phase_of(item, t);
                [p.sin() as f32, p.cos() as f32, 1.0]
            })
            .collect();
        Tensor::from_data(TensorData::new(v, [FRAMES, 3]), &self.device)
    }

    fn rest(&self) -> Tensor<3> {
        let v: Vec<f32> = (0..FRAMES)
            .flat_map(|_| self.mesh.positions.iter().flatten().map(|&c| c as f32))
            .collect();
        Tensor::from_data(
            TensorData::new(v, [FRAMES, self.mesh.vertex_count(), 3]),
            &self.device,
        )
    }

    fn truth(&self, item: usize) -> Vec<Vec<[f32; 3]>> {
        (0..FRAMES)
            .map(|t| {
                let p = phase_of(item, t);
                self.mesh
                    .positions
                    .iter()
                    .map(|q| {
                        let lift = 0.02 * p.sin() * (q[0] + 0.5 * q[2]);
                        [q[0] as f32, (q[1] + lift) as f32, q[2] as f32]
                    })
                    .collect()
            })
            .collect()
    }
}

impl TrainTask for ToyTask {
    type Model = Toy;
    type Term = Term;
    type Stage = ScheduleState;

    fn item_count(&self) -> usize {
        ITEMS
    }

    fn terms(&self, stage: &ScheduleState) -> Vec<(Term, f64)> {
        stage.phase.weighted_terms(&self.weights, &self.schedule)
    }

    fn losses(
        &mut self,
        model: &Toy,
        item: usize,
        terms: &[Term],
    ) -> weft_train::Result<Vec<Tensor<1>>> {
        let x = model.forward(self.features(item), self.rest());
        let truth = self.truth(item);
        let targets = Targets::new(&self.topology, &self.mesh.faces, &truth, &self.device)?;
        let window = self.topology.window(FRAMES, &self.device)?;
        let n = self.mesh.vertex_count();
        let host: Vec<[f64; 3]> = x
            .to_data()
            .convert::<f64>()
            .try_into_vec::<f64>()
            .unwrap()
            .chunks(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let mut out = Vec::new();
        for &term in terms {
            let l = match term {
                Term::Vertex => vertex_loss(x.clone(), targets.positions.clone())?,
                Term::Edge => edge_loss(
                    x.clone(),
                    &self.topology,
                    &window,
                    targets.edge_lengths.clone(),
                )?,
                Term::Normal => {
                    normal_loss(x.clone(), &self.topology, &window, targets.normals.clone())?
                }
                Term::Collision => {
                    let body = Sphere {
                        center: [0.1, -0.25, 0.1],
                        radius: 0.26,
                    };
                    let w = &self.weights;
                    let e = collision_energies(
                        &[body; FRAMES],
                        &host,
                        n,
                        w.collision_eps,
                        w.collision_radius,
                    )?;
                    physics_loss(x.clone(), &Arc::new(e), PhysicsImpl::Auto)?
                }
                Term::Gravity => {
                    let e = gravity_energy(&self.mesh, FRAMES, self.weights.density)?;
                    physics_loss(x.clone(), &Arc::new(e), PhysicsImpl::Auto)?
                }
                Term::Stretch | Term::Shear => {
                    let (s, h) =
                        membrane_energies(&rest_frames(&self.mesh, None).unwrap(), FRAMES)?;
                    let e = if term == Term::Stretch { s } else { h };
                    physics_loss(x.clone(), &Arc::new(e), PhysicsImpl::Auto)?
                }
            };
            let l = if self.poisoned.contains(&item) {
                l.mul_scalar(f64::NAN)
            } else {
                l
            };
            out.push(l);
        }
        Ok(out)
    }

    fn validate(&mut self, model: &Toy) -> weft_train::Result<Metrics> {
        let device = model.first.weight.val().device();
        let features = self.features(0).to_device(&device);
        let x = model.forward(features, self.rest().to_device(&device));
        let pred: Vec<Vec<[f32; 3]>> = x
            .to_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .unwrap()
            .chunks(3 * self.mesh.vertex_count())
            .map(|f| f.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
            .collect();
        let mm = weft_train::loss::mean_vertex_error_mm(&pred, &self.truth(0))?;
        Ok(Metrics::from([("mm".to_string(), mm)]))
    }

    fn primary_metric(&self) -> &'static str {
        "mm"
    }

    fn stage_name(&self, stage: &ScheduleState) -> String {
        stage.phase.name().into()
    }

    fn advance(&self, stage: &mut ScheduleState, end: &StepEnd<'_, Term>) -> bool {
        stage.advance(&self.schedule, end)
    }

    fn enter_stage(&mut self, model: Toy, stage: &ScheduleState) -> Toy {
        if stage.phase.is_frozen() {
            let group = ParamGroup::ids_from_module(model.second.clone());
            model.no_grad().set_require_grad_group(group, true)
        } else {
            model
        }
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("weft-train-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The toy's own training settings, in `[train]` beside the loop's.
#[derive(Clone, Debug, PartialEq, Serialize)]
struct ToyTraining {
    schedule: ScheduleConfig,
}

type Cfg = TrainTable<ToyTraining>;

fn config(steps: usize) -> Cfg {
    let mut cfg = TrainTable {
        trainer: TrainConfig {
            steps,
            seed: 5,
            batch: 2,
            checkpoint_every: 3,
            validate_every: 4,
            learning_rate: 1e-2,
            ..TrainConfig::default()
        },
        task: ToyTraining {
            schedule: ScheduleConfig::cpu(),
        },
    };
    // Short caps so both phases of step 2 (and the freeze) happen within the run.
    cfg.task.schedule.supervised_max_fraction = Some(0.3);
    cfg.task.schedule.physics_max_fraction = Some(0.6);
    cfg
}

/// burn's device seed is process-wide state: tests that build models in parallel would
/// draw from each other's generator, so model construction takes this lock.
static SEED_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn fresh(cfg: &Cfg, toy: &ToyConfig) -> Toy {
    let _guard = SEED_LOCK
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let device = seeded(&cpu_autodiff(), cfg.trainer.seed);
    let model = Toy::new(toy, ToyTask::new(cfg).mesh.vertex_count(), &device);
    // Parameters are initialised lazily: materialise them under the lock.
    let _ = params(&model);
    model
}

fn params(model: &Toy) -> Vec<u32> {
    [
        model.first.weight.val().flatten::<1>(0, 1),
        model.first.bias.as_ref().unwrap().val(),
        model.second.weight.val().flatten::<1>(0, 1),
        model.second.bias.as_ref().unwrap().val(),
    ]
    .into_iter()
    .flat_map(|t| {
        t.into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .unwrap()
            .into_iter()
            .map(f32::to_bits)
    })
    .collect()
}

fn run_in(dir: &Path, cfg: &Cfg, toy: &ToyConfig, preset: &str) -> RunDir {
    RunDir::new(dir, ModelKind::Multilevel, preset, toy, cfg).unwrap()
}

#[test]
fn a_resumed_run_continues_bit_for_bit() {
    let toy = ToyConfig { hidden: 6 };
    let cfg = config(10);
    let mut task = ToyTask::new(&cfg);

    let straight_dir = temp_dir("straight");
    let run = run_in(&straight_dir, &cfg, &toy, "toy");
    let (straight, outcome) =
        train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap();
    assert_eq!(outcome.steps, 10);
    assert_eq!(outcome.stage, Phase::FullPhysics.name());
    let straight_log = std::fs::read_to_string(straight_dir.join("metrics.jsonl")).unwrap();
    // Checkpoints at steps 3, 6, 9 and 10; the default keeps the newest 3.
    let mut kept: Vec<String> = std::fs::read_dir(straight_dir.join("checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".state.json"))
        .collect();
    kept.sort();
    assert_eq!(
        kept,
        [
            "step-000006.state.json",
            "step-000009.state.json",
            "step-000010.state.json"
        ]
    );

    // Half, stop, resume. Every checkpoint kept: the kill below goes back to step 3.
    let split_dir = temp_dir("split");
    let mut keep_all = cfg.clone();
    keep_all.trainer.keep_checkpoints = 0;
    let run = run_in(&split_dir, &keep_all, &toy, "toy");
    let half = RunOptions {
        session_steps: Some(5),
        ..RunOptions::default()
    };
    let (_, o) = train(&mut task, fresh(&cfg, &toy), &run, &half).unwrap();
    assert_eq!(o.steps, 5);
    let resume = RunOptions {
        resume: true,
        ..RunOptions::default()
    };
    let (resumed, o) = train(&mut task, fresh(&cfg, &toy), &run, &resume).unwrap();
    assert_eq!(o.steps, 10);
    assert_eq!(
        params(&resumed),
        params(&straight),
        "parameters differ after resume"
    );

    // Killed after step 5 but before its checkpoint: `latest` still names step 3.
    std::fs::write(split_dir.join("checkpoints/latest"), "step-000003.bpk\n").unwrap();
    let (resumed, _) = train(&mut task, fresh(&cfg, &toy), &run, &resume).unwrap();
    assert_eq!(
        params(&resumed),
        params(&straight),
        "parameters differ after a kill"
    );
    // The log reads as if the run had never stopped (step times aside).
    let strip = |text: &str| -> Vec<serde_json::Value> {
        text.lines()
            .map(|l| {
                let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                v.as_object_mut().unwrap().remove("step_ms");
                v
            })
            .collect()
    };
    let split_log = std::fs::read_to_string(split_dir.join("metrics.jsonl")).unwrap();
    assert_eq!(strip(&split_log), strip(&straight_log));
    assert!(split_dir.join("curves.png").exists());
    // weft-models reads the model record that `latest` names with Module::load_file.
    let latest = std::fs::read_to_string(split_dir.join("checkpoints/latest")).unwrap();
    let loaded = Toy::new(&toy, task.mesh.vertex_count(), &weft_nn::backend::cpu())
        .try_load_file(split_dir.join("checkpoints").join(latest.trim()))
        .unwrap();
    assert_eq!(params(&loaded), params(&straight));
    let _ = std::fs::remove_dir_all(&straight_dir);
    let _ = std::fs::remove_dir_all(&split_dir);
}

#[test]
fn checkpoints_of_another_run_are_refused_by_name() {
    let toy = ToyConfig { hidden: 4 };
    let cfg = config(3);
    let mut task = ToyTask::new(&cfg);
    let dir = temp_dir("mismatch");
    let run = run_in(&dir, &cfg, &toy, "toy");
    train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap();
    let resume = RunOptions {
        resume: true,
        ..RunOptions::default()
    };

    // A fresh start over a finished run.
    let err = train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap_err();
    assert!(matches!(err, TrainError::RunDir { .. }), "{err}");
    // Another preset.
    let other = run_in(&dir, &cfg, &toy, "paper");
    let err = train(&mut task, fresh(&cfg, &toy), &other, &resume).unwrap_err();
    assert!(
        matches!(&err, TrainError::Mismatch { field, .. } if field == "preset"),
        "{err}"
    );
    // Another model configuration.
    let wide = ToyConfig { hidden: 5 };
    let other = run_in(&dir, &cfg, &wide, "toy");
    let err = train(&mut task, fresh(&cfg, &wide), &other, &resume).unwrap_err();
    assert!(
        matches!(&err, TrainError::Mismatch { field, .. } if field == "model.hidden"),
        "{err}"
    );
    assert!(err.to_string().contains("model.hidden"));
    // Another training configuration.
    let mut longer = cfg.clone();
    longer.trainer.learning_rate = 0.5;
    let other = run_in(&dir, &longer, &toy, "toy");
    let err = train(&mut task, fresh(&longer, &toy), &other, &resume).unwrap_err();
    assert!(
        matches!(&err, TrainError::Mismatch { field, .. } if field == "train.learning_rate"),
        "{err}"
    );
    // A checkpoint copied from another format version.
    let state = dir.join("checkpoints/step-000003.state.json");
    let text = std::fs::read_to_string(&state).unwrap();
    std::fs::write(
        &state,
        text.replace("\"format_version\": 1", "\"format_version\": 0"),
    )
    .unwrap();
    let err = train(&mut task, fresh(&cfg, &toy), &run, &resume).unwrap_err();
    assert!(
        matches!(&err, TrainError::Mismatch { field, .. } if field == "format_version"),
        "{err}"
    );
    // Resume without a checkpoint.
    let empty = temp_dir("empty");
    let run = run_in(&empty, &cfg, &toy, "toy");
    std::fs::write(empty.join("config.toml"), run.config_text().unwrap()).unwrap();
    let err = train(&mut task, fresh(&cfg, &toy), &run, &resume).unwrap_err();
    assert!(matches!(err, TrainError::RunDir { .. }), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&empty);
}

#[test]
fn a_second_writer_and_a_lost_latest_never_overwrite_checkpoints() {
    let toy = ToyConfig { hidden: 4 };
    let cfg = config(6);
    let mut task = ToyTask::new(&cfg);
    let dir = temp_dir("lock");
    let run = run_in(&dir, &cfg, &toy, "toy");
    // Another process holds the directory: refused, naming it, nothing written.
    let held = run.lock().unwrap();
    let err = train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap_err();
    assert!(matches!(err, TrainError::Lock(_)), "{err}");
    assert!(err.to_string().contains("weft train, pid"), "{err}");
    assert!(!dir.join("config.toml").exists());
    drop(held);
    // A stale temporary file of a killed checkpoint write is removed by the next run.
    std::fs::create_dir_all(dir.join("checkpoints")).unwrap();
    let stale = dir.join("checkpoints/.step-000003.bpk.999999.0.tmp");
    std::fs::write(&stale, [0u8; 64]).unwrap();
    let (straight, _) = train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap();
    assert!(!stale.exists());

    // `latest` lost: a fresh start is refused and leaves every checkpoint as it was…
    let latest = dir.join("checkpoints/latest");
    std::fs::remove_file(&latest).unwrap();
    let six = std::fs::read(dir.join("checkpoints/step-000006.bpk")).unwrap();
    let err = train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap_err();
    assert!(matches!(err, TrainError::RunDir { .. }), "{err}");
    assert!(err.to_string().contains("--resume"), "{err}");
    assert_eq!(
        std::fs::read(dir.join("checkpoints/step-000006.bpk")).unwrap(),
        six
    );
    // …and --resume goes on from the newest complete checkpoint.
    std::fs::remove_file(dir.join("checkpoints/step-000006.state.json")).unwrap();
    assert_eq!(run.resume_point().unwrap().as_deref(), Some("step-000003"));
    let resume = RunOptions {
        resume: true,
        ..RunOptions::default()
    };
    let (resumed, o) = train(&mut task, fresh(&cfg, &toy), &run, &resume).unwrap();
    assert_eq!(o.steps, 6);
    assert_eq!(params(&resumed), params(&straight));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn non_finite_losses_skip_the_step_and_stop_when_persistent() {
    let toy = ToyConfig { hidden: 4 };
    let mut cfg = config(12);
    cfg.trainer.batch = 1;
    cfg.task.schedule.two_step = false;
    let mut task = ToyTask::new(&cfg);
    task.poisoned = vec![2];
    let dir = temp_dir("nan");
    let run = run_in(&dir, &cfg, &toy, "toy");
    let (model, outcome) =
        train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap();
    // Item 2 comes once per epoch: 12 steps over 5 items is 2 or 3 poisoned steps.
    assert!((2..=3).contains(&outcome.skipped), "{outcome:?}");
    assert!(params(&model)
        .iter()
        .all(|&b| f32::from_bits(b).is_finite()));
    let log = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
    let events: Vec<serde_json::Value> = log
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|v| v["event"] == "non_finite")
        .collect();
    assert_eq!(events.len(), outcome.skipped);
    assert_eq!(events[0]["term"], "vertex");

    // Every item poisoned: stops after max_non_finite steps, naming the term.
    cfg.trainer.max_non_finite = 3;
    task.poisoned = (0..ITEMS).collect();
    let dir2 = temp_dir("nan2");
    let run = run_in(&dir2, &cfg, &toy, "toy");
    let err = train(&mut task, fresh(&cfg, &toy), &run, &RunOptions::default()).unwrap_err();
    assert!(
        matches!(
            &err,
            TrainError::NonFinite {
                step: 3,
                consecutive: 3,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("`vertex`"));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&dir2);
}

#[test]
fn step_two_trains_only_the_second_submodule_and_the_loss_falls() {
    let toy = ToyConfig { hidden: 8 };
    let mut cfg = config(40);
    cfg.trainer.checkpoint_every = 40;
    cfg.task.schedule.supervised_max_fraction = Some(0.75);
    cfg.task.schedule.physics_max_fraction = None;
    let mut task = ToyTask::new(&cfg);
    let dir = temp_dir("freeze");
    let run = run_in(&dir, &cfg, &toy, "toy");
    let first = RunOptions {
        session_steps: Some(30),
        ..RunOptions::default()
    };
    let (before, o) = train(&mut task, fresh(&cfg, &toy), &run, &first).unwrap();
    assert_eq!(o.stage, Phase::Physics.name());
    let resume = RunOptions {
        resume: true,
        ..RunOptions::default()
    };
    let (after, o) = train(&mut task, fresh(&cfg, &toy), &run, &resume).unwrap();
    assert_eq!(o.steps, 40);
    let bits = |m: &Toy| -> (Vec<u32>, Vec<u32>) {
        let p = params(m);
        let split = 3 * toy.hidden + toy.hidden;
        (p[..split].to_vec(), p[split..].to_vec())
    };
    let (b1, b2) = bits(&before);
    let (a1, a2) = bits(&after);
    assert_eq!(a1, b1, "the first submodule moved in step 2");
    assert_ne!(a2, b2, "the second submodule did not train in step 2");

    let log = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
    let vertex: Vec<f64> = log
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter_map(|v| v["terms"]["vertex"].as_f64())
        .collect();
    let early: f64 = vertex[..5].iter().sum::<f64>() / 5.0;
    let late: f64 = vertex[20..25].iter().sum::<f64>() / 5.0;
    assert!(late < 0.7 * early, "vertex loss {early} -> {late}");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = DType::F32;
}
