//! The Multilevel model trained through the whole schedule on a small in-memory
//! sequence: every phase runs (physics terms against the posed default body included),
//! a resumed run ends with the same parameters bit for bit, and weft-models' Predictor
//! loads the run directory the trainer wrote.

use std::path::PathBuf;

use burn::module::{Module, ModuleVisitor, Param};
use burn::tensor::Tensor;
use weft_garment::{FitBody, GarmentKind, Style};
use weft_models::multilevel::{Multilevel, MultilevelConfig, Predictor};
use weft_models::ModelKind;
use weft_motion::{generate, MotionKind, ProceduralParams};
use weft_nn::backend::{cpu_autodiff, seeded};
use weft_train::tasks::multilevel::{carried_sequence, Phase, E_VERTS_MM};
use weft_train::{
    train, MultilevelTask, MultilevelTraining, RunDir, RunOptions, TrainConfig, TrainTable,
};

const FRAMES: usize = 8;

/// A skirt on the default body following a procedural walk; the "simulated" frames are
/// the rest garment carried by the root translation.
fn sequence(id: &str, seed: u64) -> (weft_body::BodyModel, weft_data::Sequence) {
    let body = weft_body::default_body().expect("default body");
    let fit = FitBody::new(&body, &[]).expect("fit");
    let garment = fit
        .generate(
            GarmentKind::Skirt,
            &Style::from_seed(GarmentKind::Skirt, seed),
            300,
        )
        .expect("skirt")
        .mesh;
    let mut params = ProceduralParams::new(MotionKind::parse("walk").expect("walk"));
    params.frames = FRAMES;
    let motion = generate(&params).expect("walk");
    let poses = motion.poses().to_vec();
    let seq = carried_sequence(id, garment, poses, motion.trans().to_vec(), motion.fps());
    (body, seq)
}

fn config() -> TrainTable<MultilevelTraining> {
    let mut cfg = TrainTable {
        trainer: TrainConfig {
            steps: 6,
            checkpoint_every: 3,
            validate_every: 3,
            learning_rate: 1e-3,
            ..TrainConfig::default()
        },
        task: MultilevelTraining {
            window: 4,
            ..MultilevelTraining::default()
        },
    };
    cfg.task.schedule.supervised_max_fraction = Some(0.3);
    cfg.task.schedule.physics_max_fraction = Some(0.6);
    cfg
}

fn task(model_cfg: &MultilevelConfig, cfg: &TrainTable<MultilevelTraining>) -> MultilevelTask {
    let (body, train) = sequence("train", 1);
    let (_, validation) = sequence("validation", 2);
    MultilevelTask::new(
        model_cfg,
        &cfg.task,
        body,
        vec![train],
        vec![validation],
        &cpu_autodiff(),
    )
    .unwrap()
}

fn fresh(cfg: &MultilevelConfig, seed: u64) -> Multilevel {
    Multilevel::new(cfg, &seeded(&cpu_autodiff(), seed)).unwrap()
}

/// Every parameter's bits in traversal order.
#[derive(Default)]
struct Bits(Vec<u32>);

impl ModuleVisitor for Bits {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        let v = param
            .val()
            .into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .unwrap();
        self.0.extend(v.into_iter().map(f32::to_bits));
    }
}

fn bits(m: &Multilevel) -> Vec<u32> {
    let mut b = Bits::default();
    m.visit(&mut b);
    b.0
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("weft-train-ml-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn multilevel_trains_through_every_phase_and_resumes_bit_for_bit() {
    let model_cfg = MultilevelConfig::new();
    let cfg = config();
    let mut t = task(&model_cfg, &cfg);
    assert_eq!(t.validation_window_count(), 2);

    let straight_dir = temp_dir("straight");
    let run = RunDir::new(
        &straight_dir,
        ModelKind::Multilevel,
        "cpu",
        &model_cfg,
        &cfg,
    )
    .unwrap();
    let (straight, outcome) = train(
        &mut t,
        fresh(&model_cfg, cfg.trainer.seed),
        &run,
        &RunOptions::default(),
    )
    .unwrap();
    assert_eq!(outcome.steps, 6);
    assert_eq!(outcome.skipped, 0);
    assert_eq!(outcome.stage, Phase::FullPhysics.name());
    let v = outcome.validation[E_VERTS_MM];
    assert!(v.is_finite() && v > 0.0, "{v}");
    let log = std::fs::read_to_string(straight_dir.join("metrics.jsonl")).unwrap();
    for term in [
        "\"vertex\"",
        "\"normal\"",
        "\"collision\"",
        "\"gravity\"",
        "\"stretch\"",
        "\"shear\"",
    ] {
        assert!(log.contains(term), "{term} never evaluated:\n{log}");
    }

    let split_dir = temp_dir("split");
    let run = RunDir::new(&split_dir, ModelKind::Multilevel, "cpu", &model_cfg, &cfg).unwrap();
    let mut t = task(&model_cfg, &cfg);
    let half = RunOptions {
        session_steps: Some(3),
        ..RunOptions::default()
    };
    train(&mut t, fresh(&model_cfg, cfg.trainer.seed), &run, &half).unwrap();
    let mut t = task(&model_cfg, &cfg);
    let resume = RunOptions {
        resume: true,
        ..RunOptions::default()
    };
    let (resumed, _) = train(&mut t, fresh(&model_cfg, cfg.trainer.seed), &run, &resume).unwrap();
    assert_eq!(
        bits(&resumed),
        bits(&straight),
        "parameters differ after resume"
    );

    // weft-models reads the run directory for inference.
    let predictor = Predictor::load(&split_dir).unwrap();
    assert_eq!(bits(predictor.model()), bits(&straight));
    let _ = std::fs::remove_dir_all(&straight_dir);
    let _ = std::fs::remove_dir_all(&split_dir);
}
