//! Runs one GAT layer (issue 6 size: the 4 000-vertex tube, 32 → 4×32) a given number of
//! times, for CPU-time measurements with `perf stat` / `time` when the machine is shared and
//! criterion's wall-clock figures are noisy:
//!
//! `RAYON_NUM_THREADS=1 perf stat -e task-clock target/release/examples/gat_profile MODE N`
//!
//! MODE: `fused_fwd`, `fused_bwd`, `ref_fwd`, `ref_bwd` (the layer, forward or forward +
//! backward), `mm` (the dense transform alone), `att` (fused attention alone), `none`
//! (setup only, to subtract).

use std::time::Instant;

use weft_mesh::primitives::builtin_garment;
use weft_nn::backend::{cpu, cpu_autodiff};
use weft_nn::burn::tensor::{Distribution, Tensor};
use weft_nn::{AttentionImpl, GatBlockConfig, GraphBatch};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(mode), Some(iters)) = (args.get(1), args.get(2).and_then(|s| s.parse().ok())) else {
        eprintln!("usage: gat_profile MODE ITERATIONS");
        std::process::exit(2);
    };
    let iters: usize = iters;
    if std::env::var_os("WEFT_MALLOC_DEFAULTS").is_none() {
        weft_nn::backend::retain_freed_memory();
    }
    let batch = GraphBatch::single(&builtin_garment().graph());
    let adjacency = batch.adjacency().clone();
    let n = batch.node_count();
    let implementation = if mode.starts_with("ref") {
        AttentionImpl::Reference
    } else {
        AttentionImpl::Auto
    };
    let train = mode.ends_with("bwd");
    let device = if train { cpu_autodiff() } else { cpu() };
    device.seed(1);
    let block = GatBlockConfig::new(32, 32)
        .with_heads(4)
        .init(&device)
        .expect("valid config")
        .with_implementation(implementation);
    let normal = Distribution::Normal(0.0, 1.0);
    let mut x = Tensor::<2>::random([n, 32], normal, &device);
    if train {
        x = x.require_grad();
    }
    let w = Tensor::<2>::random([32, 128], normal, &device);
    let z = Tensor::<2>::random([n, 128], normal, &device);
    let a = Tensor::<2>::random([4, 32], normal, &device);
    let start = Instant::now();
    for _ in 0..iters {
        match mode.as_str() {
            "none" => {}
            "mm" => drop(x.clone().matmul(w.clone())),
            "att" => drop(
                weft_nn::gat::attention(
                    z.clone(),
                    a.clone(),
                    a.clone(),
                    &adjacency,
                    0.2,
                    AttentionImpl::Auto,
                )
                .expect("shapes match"),
            ),
            _ => {
                let out = block.forward(x.clone(), &adjacency).expect("shapes match");
                if train {
                    drop(out.sum().backward());
                }
            }
        }
    }
    println!(
        "{mode}: {:.3} ms wall per iteration",
        start.elapsed().as_secs_f64() * 1e3 / iters.max(1) as f64
    );
}
