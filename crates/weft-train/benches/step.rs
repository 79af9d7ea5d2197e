//! One training step of the Multilevel model (issue 6 item 8): forward, the step-1 loss
//! terms (vertex, edge, normal), backward and the Adamax update, at batch 1 (one frame)
//! and for a window of 8 frames, on a 4 000-vertex skirt on weft's default body, for the
//! `cpu` and `paper` presets. Also the step-2 terms (collision against the posed body,
//! gravity) on the `cpu` preset, and the `paper` step of schedule step 2 (only the second
//! M^mp submodule trains). Figures in docs/benchmarks.md ("Training").
//!
//! `cargo bench -p weft-train --bench step`

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use std::time::Duration;

use burn::optim::GradientsParams;
use criterion::{criterion_group, criterion_main, Criterion};
use weft_garment::{FitBody, GarmentKind, Style};
use weft_models::multilevel::{Multilevel, MultilevelConfig};
use weft_motion::{generate, MotionKind, ProceduralParams};
use weft_nn::backend::{cpu_autodiff, retain_freed_memory, seeded};
use weft_nn::AdamaxConfig;
use weft_train::tasks::multilevel::{carried_sequence, Phase, ScheduleState, Term};
use weft_train::{MultilevelTask, MultilevelTraining, TrainTask};

const VERTICES: usize = 4000;

fn task(model: &MultilevelConfig, window: usize) -> MultilevelTask {
    let body = weft_body::default_body().expect("default body");
    let fit = FitBody::new(&body, &[]).expect("fit");
    let garment = fit
        .generate(
            GarmentKind::Skirt,
            &Style::from_seed(GarmentKind::Skirt, 1),
            VERTICES,
        )
        .expect("skirt")
        .mesh;
    let mut params = ProceduralParams::new(MotionKind::parse("walk").expect("walk"));
    params.frames = 16;
    let motion = generate(&params).expect("walk");
    let poses = motion.poses().to_vec();
    let seq = carried_sequence(
        "bench",
        garment,
        poses,
        motion.trans().to_vec(),
        motion.fps(),
    );
    let cfg = MultilevelTraining {
        window,
        ..MultilevelTraining::default()
    };
    MultilevelTask::new(model, &cfg, body, vec![seq], Vec::new(), &cpu_autodiff()).expect("task")
}

fn bench(c: &mut Criterion) {
    retain_freed_memory();
    let mut group = c.benchmark_group("train_step_4k_skirt");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    let supervised = [Term::Vertex, Term::Edge, Term::Normal];
    let physics = [Term::Vertex, Term::Edge, Term::Collision, Term::Gravity];
    let cases: [(&str, usize, &[Term]); 5] = [
        ("cpu", 1, &supervised),
        ("cpu", 8, &supervised),
        ("paper", 1, &supervised),
        ("paper", 8, &supervised),
        ("cpu", 1, &physics),
    ];
    for (preset, window, terms) in cases {
        let cfg = MultilevelConfig::preset(preset).expect("preset");
        let mut t = task(&cfg, window);
        let mut model = Multilevel::new(&cfg, &seeded(&cpu_autodiff(), 0)).expect("model");
        let mut optim = AdamaxConfig::new().init();
        let name = format!(
            "{preset}/frames={window}/{}",
            if terms.len() == 3 {
                "supervised"
            } else {
                "physics"
            }
        );
        group.bench_function(name, |b| {
            b.iter(|| {
                let losses = t.losses(&model, 0, terms).expect("losses");
                let total = losses.into_iter().reduce(|a, b| a + b).expect("terms");
                let grads = GradientsParams::from_grads(total.backward(), &model);
                model = optim.step(1e-4, model.clone(), grads);
            })
        });
    }
    // Step 2 of the schedule: only the second M^mp submodule trains (the rest is
    // frozen and the pair encoding cached), the comparable case to a step of M^mp alone.
    let cfg = MultilevelConfig::paper();
    let mut t = task(&cfg, 1);
    let model = Multilevel::new(&cfg, &seeded(&cpu_autodiff(), 0)).expect("model");
    let stage = ScheduleState {
        phase: Phase::Physics,
        ..ScheduleState::default()
    };
    let mut model = t.enter_stage(model, &stage);
    let mut optim = AdamaxConfig::new().init();
    group.bench_function("paper/frames=1/supervised/second-submodule-only", |b| {
        b.iter(|| {
            let losses = t.losses(&model, 0, &supervised).expect("losses");
            let total = losses.into_iter().reduce(|a, b| a + b).expect("terms");
            let grads = GradientsParams::from_grads(total.backward(), &model);
            model = optim.step(1e-4, model.clone(), grads);
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
