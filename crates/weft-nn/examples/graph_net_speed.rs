//! Times HOOD's processor (seed 004) at the size of its speed target: 15 message-passing
//! steps at latent 128 (MLPs Linear(·→L)–ReLU–Linear(L→L)–ReLU–Linear(L→L)–LayerNorm) over
//! 4 000 garment vertices and 2 000 body vertices, with random edges of HOOD's counts:
//! fine 23 600 directed mesh edges, coarse levels of 1 992 and 985 nodes with 11 750 and
//! 5 810, and 4 000 body edges (2 000 each way), read as `[0, 1, b] ×3, [1, 2, b] ×3,
//! [2, b] ×3, [1, 2, b] ×3, [0, 1, b] ×3`.
//!
//! `cargo run --release -p weft-nn --example graph_net_speed [-- REPEATS [fwd|bwd]]`
//! (`fwd` / `bwd`: only the forward / only the forward + backward, for profiling).
//!
//! Prints, per repeat, the wall time of one forward (flex, no autodiff) and of one forward +
//! backward (flex with autodiff, gradients of every parameter and of the inputs), and the
//! GFLOP/s those times give for the products of the straightforward form (`2·m·k·n` per
//! linear layer with the edge MLP's first layer on the gathered `[E, 3L]` rows; backward
//! twice the forward).

use std::time::Instant;

use weft_nn::backend::{cpu, cpu_autodiff};
use weft_nn::burn::tensor::{Device, Distribution, Tensor};
use weft_nn::{EdgeSet, Processor, ProcessorConfig};

const LATENT: usize = 128;
const GARMENT: usize = 4_000;
const BODY: usize = 2_000;
/// (nodes of the level, directed edges), fine first.
const LEVELS: [(usize, usize); 3] = [(4_000, 23_600), (1_992, 11_750), (985, 5_810)];
const BODY_EDGES_EACH_WAY: usize = 2_000;

/// A small deterministic generator (xorshift64*), so every run times the same graph.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> u32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 32) % n as u64) as u32
    }
}

fn graph(device: &Device) -> Vec<EdgeSet> {
    let nodes = GARMENT + BODY;
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut sets: Vec<EdgeSet> = LEVELS
        .iter()
        .map(|&(level_nodes, edges)| {
            let list: Vec<[u32; 2]> = (0..edges)
                .map(|_| [rng.below(level_nodes), rng.below(level_nodes)])
                .collect();
            EdgeSet::new(nodes, &list, device).expect("endpoints in range")
        })
        .collect();
    let mut body = Vec::with_capacity(2 * BODY_EDGES_EACH_WAY);
    for _ in 0..BODY_EDGES_EACH_WAY {
        let (g, b) = (rng.below(GARMENT), GARMENT as u32 + rng.below(BODY));
        body.push([b, g]);
        body.push([g, b]);
    }
    sets.push(EdgeSet::new(nodes, &body, device).expect("endpoints in range"));
    sets
}

fn schedule() -> Vec<Vec<usize>> {
    let b = LEVELS.len();
    [
        vec![0, 1, b],
        vec![1, 2, b],
        vec![2, b],
        vec![1, 2, b],
        vec![0, 1, b],
    ]
    .into_iter()
    .flat_map(|step| std::iter::repeat_n(step, 3))
    .collect()
}

/// Forward FLOPs of the straightforward form (2 hidden layers).
fn forward_flops(sets: &[EdgeSet], nodes: usize) -> f64 {
    let l2 = (LATENT * LATENT) as f64;
    schedule()
        .iter()
        .map(|step| {
            let edges: usize = step.iter().map(|&k| sets[k].edge_count()).sum();
            2.0 * l2 * (5.0 * edges as f64 + (3.0 + step.len() as f64) * nodes as f64)
        })
        .sum()
}

fn processor(device: &Device) -> Processor {
    device.seed(1);
    ProcessorConfig::new(LATENT, LEVELS.len() + 1, schedule())
        .init(device)
        .expect("valid schedule")
}

fn inputs(device: &Device, sets: &[EdgeSet], grad: bool) -> (Tensor<2>, Vec<Tensor<2>>) {
    let normal = Distribution::Normal(0.0, 1.0);
    let track = |t: Tensor<2>| if grad { t.require_grad() } else { t };
    let x = track(Tensor::random([GARMENT + BODY, LATENT], normal, device));
    let e = sets
        .iter()
        .map(|s| track(Tensor::random([s.edge_count(), LATENT], normal, device)))
        .collect();
    (x, e)
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let only = std::env::args().nth(2).unwrap_or_default();
    let (run_fwd, run_bwd) = (only != "bwd", only != "fwd");
    weft_nn::backend::retain_freed_memory();

    let device = cpu();
    let sets = graph(&device);
    let flops = forward_flops(&sets, GARMENT + BODY);
    let p = processor(&device);
    let (x, e) = inputs(&device, &sets, false);

    let train = cpu_autodiff();
    let train_sets = graph(&train);
    let tp = processor(&train);
    let (tx, te) = inputs(&train, &train_sets, true);
    let r = Tensor::<2>::random(
        [GARMENT + BODY, LATENT],
        Distribution::Normal(0.0, 1.0),
        &train,
    );

    println!(
        "15 steps, N = {}, edges {:?}, {:.1} GFLOP forward (straightforward form)",
        GARMENT + BODY,
        sets.iter().map(EdgeSet::edge_count).collect::<Vec<_>>(),
        flops * 1e-9
    );
    let mut fwd = Vec::new();
    let mut both = Vec::new();
    // One untimed round first (allocator, thread pool).
    for round in 0..=repeats {
        let start = Instant::now();
        if run_fwd {
            let (y, _) = p.forward(x.clone(), &sets, e.clone()).expect("shapes");
            let _ = y.into_data();
        }
        let f = start.elapsed().as_secs_f64();

        let start = Instant::now();
        if run_bwd {
            let (y, _) = tp
                .forward(tx.clone(), &train_sets, te.clone())
                .expect("shapes");
            let grads = (y * r.clone()).sum().backward();
            drop(grads);
        }
        let b = start.elapsed().as_secs_f64();
        if round > 0 {
            println!(
                "forward {:7.1} ms ({:5.1} GFLOP/s)   forward+backward {:7.1} ms ({:5.1} GFLOP/s)",
                f * 1e3,
                flops / f * 1e-9,
                b * 1e3,
                3.0 * flops / b * 1e-9
            );
            fwd.push(f);
            both.push(b);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (f, b) = (median(&mut fwd), median(&mut both));
    // Sorted by `median`: the first is the fastest (least disturbed on a shared machine).
    let (f_min, b_min) = (fwd[0], both[0]);
    println!(
        "median: forward {:.1} ms ({:.1} GFLOP/s), forward+backward {:.1} ms ({:.1} GFLOP/s)",
        f * 1e3,
        flops / f * 1e-9,
        b * 1e3,
        3.0 * flops / b * 1e-9
    );
    println!(
        "min:    forward {:.1} ms ({:.1} GFLOP/s), forward+backward {:.1} ms ({:.1} GFLOP/s)",
        f_min * 1e3,
        flops / f_min * 1e-9,
        b_min * 1e3,
        3.0 * flops / b_min * 1e-9
    );
}
