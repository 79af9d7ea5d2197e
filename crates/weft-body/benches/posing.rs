//! Posing the default body (13 380 vertices, 24 joints) for 1 000 frames of a procedural
//! walk, with linear blend skinning and with dual quaternion skinning, through the
//! batched `f32` API (rayon over frames). Figures go to docs/benchmarks.md.
//!
//! `cargo bench -p weft-body --bench posing`

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use weft_body::{default_body, Skinning};
use weft_motion::{generate, MotionKind, ProceduralParams};

fn posing(c: &mut Criterion) {
    let model = default_body().expect("the default body loads");
    let shaped = model.shaped(&[0.5, -1.0]).expect("betas in range");
    let mut params = ProceduralParams::new(MotionKind::Walk);
    params.frames = 1000;
    let motion = generate(&params).expect("a walk");
    let mut g = c.benchmark_group("pose_1000_frames");
    g.sample_size(10);
    g.throughput(Throughput::Elements(1000));
    for method in [Skinning::Lbs, Skinning::Dqs] {
        g.bench_function(method.to_string(), |b| {
            b.iter(|| {
                let frames = model
                    .pose_frames(&shaped, motion.poses(), motion.trans(), method)
                    .expect("posing");
                std::hint::black_box(frames.len())
            })
        });
    }
    // One frame on one thread, for the per-frame cost without the thread pool.
    let mut out = vec![[0.0f32; 3]; model.vertex_count()];
    for method in [Skinning::Lbs, Skinning::Dqs] {
        g.bench_function(format!("{method}_single_frame_x1000_one_thread"), |b| {
            b.iter(|| {
                for (p, t) in motion.poses().iter().zip(motion.trans()) {
                    model
                        .pose_frame_f32(&shaped, p, *t, method, &mut out)
                        .expect("posing");
                }
                std::hint::black_box(out[0])
            })
        });
    }
    g.finish();
}

criterion_group!(benches, posing);
criterion_main!(benches);
