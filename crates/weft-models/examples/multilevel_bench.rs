//! Inference and training-step timings of the Multilevel model, per stage, and the GEMM
//! FLOP floor of a frame (issue 6 item 8; figures in docs/benchmarks.md).
//!
//! `cargo run --release -p weft-models --example multilevel_bench -- [--presets cpu,paper]
//! [--sizes 1000,4000,12000] [--batches 1,16] [--reps 5] [--train]`
//!
//! Garments are skirts generated on weft's default body at the requested vertex counts,
//! the motion a procedural walk. Every figure is the median over `reps` runs after one
//! warm-up, divided by the frames of the window (per frame).

use std::time::Instant;

use burn::tensor::{Distribution, Tensor};
use weft_garment::{FitBody, GarmentKind, Style};
use weft_models::multilevel::{FrameInputs, GarmentInput, Multilevel, MultilevelConfig};
use weft_models::Clip;
use weft_motion::{generate, MotionKind, ProceduralParams};
use weft_nn::backend::{cpu, cpu_autodiff, retain_freed_memory, seeded};

struct Args {
    presets: Vec<String>,
    sizes: Vec<usize>,
    batches: Vec<usize>,
    reps: usize,
    train: bool,
}

fn list<T: std::str::FromStr>(v: &str) -> Vec<T> {
    v.split(',').filter_map(|x| x.trim().parse().ok()).collect()
}

fn args() -> Args {
    let mut a = Args {
        presets: vec!["cpu".into(), "paper".into()],
        sizes: vec![1000, 4000, 12000],
        batches: vec![1, 16],
        reps: 5,
        train: false,
    };
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < argv.len() {
        let value = argv.get(i + 1).cloned().unwrap_or_default();
        match argv[i].as_str() {
            "--presets" => a.presets = list(&value),
            "--sizes" => a.sizes = list(&value),
            "--batches" => a.batches = list(&value),
            "--reps" => a.reps = value.parse().unwrap_or(5),
            "--train" => {
                a.train = true;
                i += 1;
                continue;
            }
            other => {
                eprintln!("unknown argument {other}");
                std::process::exit(2);
            }
        }
        i += 2;
    }
    a
}

/// Median of `reps` timings (ms) of `f`, after one warm-up run.
fn time_ms(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(|a, b| a.total_cmp(b));
    t[t.len() / 2]
}

fn sync<const D: usize>(t: Tensor<D>) {
    let _ = t.into_data();
}

/// The benchmark garment: a skirt of about `size` vertices (style seed 1) on `fit`.
fn skirt(fit: &FitBody, size: usize) -> Result<weft_mesh::TriMesh, weft_garment::GarmentError> {
    let style = Style::from_seed(GarmentKind::Skirt, 1);
    Ok(fit.generate(GarmentKind::Skirt, &style, size)?.mesh)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    retain_freed_memory();
    let a = args();
    let body = weft_body::default_body()?;
    let fit = FitBody::new(&body, &[])?;
    let mut params = ProceduralParams::new(MotionKind::Walk);
    params.frames = 64;
    let motion = generate(&params)?;
    let poses = motion.poses().to_vec();
    let trans = motion.trans().to_vec();
    println!(
        "threads {}, body {} vertices",
        rayon::current_num_threads(),
        body.vertex_count()
    );
    println!("| preset | N | T | inputs | t1+W | t2 | embed GEMM floor (GFLOP) | embed | rest of M^mp | LBS | total / frame | embed GFLOP/s |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for preset in &a.presets {
        let cfg = MultilevelConfig::preset(preset)?;
        let model = Multilevel::new(&cfg, &seeded(&cpu(), 1))?;
        for &size in &a.sizes {
            let garment = skirt(&fit, size)?;
            let n = garment.vertex_count();
            let start = Instant::now();
            let g = GarmentInput::new(&garment, &body, &[], &cfg)?;
            let prep_pair = start.elapsed().as_secs_f64() * 1e3;
            let encode = time_ms(a.reps.min(3), || {
                sync(model.encode_pair(&g).expect("encode").fused)
            });
            let pair = model.encode_pair(&g)?;
            eprintln!(
                "{preset} N={n}: garment inputs {prep_pair:.0} ms, pair encoding {encode:.1} ms"
            );
            for &t in &a.batches {
                let range = 8..8 + t;
                let start = Instant::now();
                let f = FrameInputs::new(
                    &body,
                    &Clip {
                        betas: &[],
                        poses: &poses,
                        trans: &trans,
                        fps: motion.fps(),
                    },
                    range,
                    &cfg,
                )?;
                let inputs = start.elapsed().as_secs_f64() * 1e3;
                let _ = g.frame_batch(t)?;
                let w = time_ms(a.reps, || {
                    sync(model.skinning_weights(&pair, &g, &f).expect("W"))
                });
                let t2 = time_ms(a.reps, || sync(model.motion_features(&g, &f).expect("t2")));
                let motion2 = model.motion_features(&g, &f)?;
                let batch = g.frame_batch(t)?;
                let (mut embed, mut rest) = (0.0, 0.0);
                for sub in &model.mp {
                    embed += time_ms(a.reps, || {
                        sync(
                            sub.embed(pair.fused.clone(), motion2.clone(), batch.batch(0))
                                .expect("embed"),
                        )
                    });
                    let x = sub.embed(pair.fused.clone(), motion2.clone(), batch.batch(0))?;
                    rest += time_ms(a.reps, || sync(sub.process(x.clone(), &batch).expect("mp")));
                }
                let weights = model.skinning_weights(&pair, &g, &f)?;
                let blend = Tensor::<3>::zeros([t, n, 3], &model.device());
                let lbs = time_ms(a.reps, || {
                    sync(
                        model
                            .skin(&g, &f, weights.clone(), blend.clone())
                            .expect("skin"),
                    )
                });
                let total = time_ms(a.reps, || {
                    sync(model.forward(&pair, &g, &f).expect("forward").vertices)
                });
                let floor =
                    2.0 * (n * cfg.fused_width() * cfg.mp_width() * cfg.mp_submodules) as f64;
                let per = |ms: f64| ms / t as f64;
                println!(
                    "| {preset} | {n} | {t} | {:.2} | {:.2} | {:.2} | {:.3} | {:.2} | {:.2} | {:.2} | **{:.2}** | {:.1} |",
                    per(inputs),
                    per(w),
                    per(t2),
                    floor / 1e9,
                    per(embed),
                    per(rest),
                    per(lbs),
                    per(total),
                    floor / (per(embed) * 1e-3) / 1e9,
                );
                // The embedding GEMM alone, same shapes.
                let hc = cfg.mp_width();
                let wmat = Tensor::<2>::random(
                    [cfg.fused_width(), t * hc],
                    Distribution::Default,
                    &model.device(),
                );
                let gemm = time_ms(a.reps, || sync(pair.fused.clone().matmul(wmat.clone())));
                eprintln!(
                    "  T={t}: embedding GEMM alone {:.2} ms/frame/submodule ({:.1} GFLOP/s)",
                    per(gemm),
                    2.0 * (n * cfg.fused_width() * hc * t) as f64 / (gemm * 1e-3) / 1e9
                );
            }
        }
    }
    if a.train {
        println!();
        println!("| preset | N | T | forward + backward (ms) | per frame |");
        println!("|---|---|---|---|---|");
        for preset in &a.presets {
            let cfg = MultilevelConfig::preset(preset)?;
            let model = Multilevel::new(&cfg, &seeded(&cpu_autodiff(), 1))?;
            for &size in &a.sizes {
                let garment = skirt(&fit, size)?;
                let n = garment.vertex_count();
                let g = GarmentInput::new(&garment, &body, &[], &cfg)?;
                for &t in &a.batches {
                    let f = FrameInputs::new(
                        &body,
                        &Clip {
                            betas: &[],
                            poses: &poses,
                            trans: &trans,
                            fps: motion.fps(),
                        },
                        8..8 + t,
                        &cfg,
                    )?;
                    let ms = time_ms(a.reps, || {
                        let pair = model.encode_pair(&g).expect("encode");
                        let p = model.forward(&pair, &g, &f).expect("forward");
                        let target = p.vertices.clone().detach() + 0.01;
                        let loss = (p.vertices - target).powi_scalar(2).mean();
                        let _ = loss.backward();
                    });
                    println!("| {preset} | {n} | {t} | {ms:.1} | {:.1} |", ms / t as f64);
                }
            }
        }
    }
    Ok(())
}
