//! One GAT layer at the size issue 6 measures: N = 4 000 vertices (the built-in tube skirt,
//! 23 600 directed edges, ≈ E = 24 000), 32 → 4 heads × 32 channels, heads concatenated.
//! Forward (inference device) and forward + backward (autodiff device, gradients of the
//! input, W and both attention vectors), fused CPU kernel against the generic burn path.
//!
//! `cargo bench -p weft-nn --bench gat` — with `backend::retain_freed_memory()` as a
//! training binary would call it; set `WEFT_MALLOC_DEFAULTS=1` to measure with glibc's
//! default trimming instead.

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use weft_mesh::primitives::builtin_garment;
use weft_nn::backend::{cpu, cpu_autodiff};
use weft_nn::burn::tensor::{Device, Distribution, Tensor};
use weft_nn::{AttentionImpl, GatBlock, GatBlockConfig, GraphBatch};

fn layer(device: &Device, implementation: AttentionImpl) -> GatBlock {
    GatBlockConfig::new(32, 32)
        .with_heads(4)
        .init(device)
        .expect("valid config")
        .with_implementation(implementation)
}

fn bench(c: &mut Criterion) {
    if std::env::var_os("WEFT_MALLOC_DEFAULTS").is_none() {
        weft_nn::backend::retain_freed_memory();
    }
    let batch = GraphBatch::single(&builtin_garment().graph());
    let adjacency = batch.adjacency().clone();
    let n = batch.node_count();
    let mut group = c.benchmark_group("gat_layer_4000x32_to_4x32");
    group.sample_size(20);
    for (name, implementation) in [
        ("fused", AttentionImpl::Auto),
        ("reference", AttentionImpl::Reference),
    ] {
        let device = cpu();
        device.seed(1);
        let block = layer(&device, implementation);
        let x = Tensor::<2>::random([n, 32], Distribution::Normal(0.0, 1.0), &device);
        group.bench_function(format!("{name}/forward"), |b| {
            b.iter(|| block.forward(x.clone(), &adjacency).expect("shapes match"))
        });

        let device = cpu_autodiff();
        device.seed(1);
        let block = layer(&device, implementation);
        let x =
            Tensor::<2>::random([n, 32], Distribution::Normal(0.0, 1.0), &device).require_grad();
        group.bench_function(format!("{name}/forward_backward"), |b| {
            b.iter(|| {
                let out = block.forward(x.clone(), &adjacency).expect("shapes match");
                out.sum().backward()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
