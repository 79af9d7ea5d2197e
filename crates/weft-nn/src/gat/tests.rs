//! The fused GAT operation against the generic reference path and against central finite
//! differences.

use std::sync::Arc;

use burn::tensor::{DType, Tensor};

use super::*;
use crate::backend::{cpu, cpu_autodiff};
use crate::testutil::{host, max_diff, random_directed, random_graph, tensor, Rng};

struct Case {
    adjacency: Arc<Adjacency>,
    heads: usize,
    channels: usize,
    z: Vec<f64>,
    a_src: Vec<f64>,
    a_dst: Vec<f64>,
    /// Weights of the scalar loss `L = Σ out ⊙ R`.
    r: Vec<f64>,
}

fn case(rng: &mut Rng, adjacency: Adjacency, heads: usize, channels: usize) -> Case {
    let n = adjacency.node_count();
    let w = heads * channels;
    Case {
        heads,
        channels,
        z: rng.values(n * w).into_iter().map(|v| 2.0 * v).collect(),
        a_src: rng.values(w),
        a_dst: rng.values(w),
        r: rng.values(n * w),
        adjacency: Arc::new(adjacency),
    }
}

/// Output and the gradients of `Σ out ⊙ R` w.r.t. `z`, `a_src`, `a_dst`.
fn run(c: &Case, implementation: AttentionImpl, dtype: DType) -> [Vec<f64>; 4] {
    let device = cpu_autodiff();
    let n = c.adjacency.node_count();
    let (h, f) = (c.heads, c.channels);
    let z = tensor(c.z.clone(), [n, h * f], &device, dtype).require_grad();
    let a_src = tensor(c.a_src.clone(), [h, f], &device, dtype).require_grad();
    let a_dst = tensor(c.a_dst.clone(), [h, f], &device, dtype).require_grad();
    let out = attention(
        z.clone(),
        a_src.clone(),
        a_dst.clone(),
        &c.adjacency,
        DEFAULT_NEGATIVE_SLOPE,
        implementation,
    )
    .unwrap();
    let r = tensor(c.r.clone(), [n, h * f], &device, dtype);
    let grads = (out.clone() * r).sum().backward();
    let g = |t: &Tensor<2>| host(&t.grad(&grads).expect("tracked input has a gradient"));
    [host(&out), g(&z), g(&a_src), g(&a_dst)]
}

#[test]
fn fused_matches_reference_forward_and_backward_on_random_graphs() {
    let mut rng = Rng::new(7);
    let cases = [
        (
            Adjacency::from_graph(&random_graph(&mut rng, 150, 300)),
            4,
            8,
        ),
        (Adjacency::from_graph(&random_graph(&mut rng, 97, 40)), 3, 5),
        // Directed, asymmetric: the transpose pass must not assume symmetry.
        (random_directed(&mut rng, 80, 400), 2, 7),
        // One node, self-loop only.
        (Adjacency::from_csr(1, &[0, 0], &[], true).unwrap(), 1, 3),
    ];
    for (adjacency, heads, channels) in cases {
        let c = case(&mut rng, adjacency, heads, channels);
        let fused = run(&c, AttentionImpl::Auto, DType::F32);
        let reference = run(&c, AttentionImpl::Reference, DType::F32);
        assert!(max_diff(&fused[0], &reference[0]) < 1e-5, "forward");
        for (k, name) in [(1, "z"), (2, "a_src"), (3, "a_dst")] {
            let scale = reference[k].iter().fold(1.0f64, |m, v| m.max(v.abs()));
            let d = max_diff(&fused[k], &reference[k]) / scale;
            assert!(d < 1e-4, "gradient of {name}: relative difference {d}");
        }
    }
}

#[test]
fn fused_gradients_match_central_differences_in_f64() {
    let mut rng = Rng::new(11);
    let adjacency = random_directed(&mut rng, 9, 20);
    let c = case(&mut rng, adjacency, 2, 3);
    let [_, gz, gs, gd] = run(&c, AttentionImpl::Auto, DType::F64);
    let device = cpu();
    let n = c.adjacency.node_count();
    let loss = |z: &[f64], s: &[f64], d: &[f64]| -> f64 {
        let out = attention(
            tensor(z.to_vec(), [n, 6], &device, DType::F64),
            tensor(s.to_vec(), [2, 3], &device, DType::F64),
            tensor(d.to_vec(), [2, 3], &device, DType::F64),
            &c.adjacency,
            DEFAULT_NEGATIVE_SLOPE,
            AttentionImpl::Auto,
        )
        .unwrap();
        host(&out).iter().zip(&c.r).map(|(o, r)| o * r).sum()
    };
    let eps = 1e-6;
    let numeric = |which: usize, len: usize| -> Vec<f64> {
        (0..len)
            .map(|k| {
                let mut p = [c.z.clone(), c.a_src.clone(), c.a_dst.clone()];
                let mut m = p.clone();
                p[which][k] += eps;
                m[which][k] -= eps;
                (loss(&p[0], &p[1], &p[2]) - loss(&m[0], &m[1], &m[2])) / (2.0 * eps)
            })
            .collect()
    };
    assert!(max_diff(&gz, &numeric(0, c.z.len())) < 1e-7);
    assert!(max_diff(&gs, &numeric(1, 6)) < 1e-7);
    assert!(max_diff(&gd, &numeric(2, 6)) < 1e-7);
}

#[test]
fn fused_forward_is_deterministic_and_rejects_bad_shapes() {
    let mut rng = Rng::new(3);
    let adjacency = Adjacency::from_graph(&random_graph(&mut rng, 300, 600));
    let c = case(&mut rng, adjacency, 4, 8);
    let a = run(&c, AttentionImpl::Auto, DType::F32);
    let b = run(&c, AttentionImpl::Auto, DType::F32);
    assert_eq!(a, b);
    let device = cpu();
    let z = Tensor::<2>::zeros([299, 32], &device);
    let att = Tensor::<2>::zeros([4, 8], &device);
    let err = attention(
        z,
        att.clone(),
        att.clone(),
        &c.adjacency,
        0.2,
        AttentionImpl::Auto,
    )
    .unwrap_err();
    assert!(matches!(
        err,
        NnError::NodeCount {
            graph: 300,
            features: 299,
            ..
        }
    ));
    let z = Tensor::<2>::zeros([300, 31], &device);
    assert!(attention(z, att.clone(), att, &c.adjacency, 0.2, AttentionImpl::Auto).is_err());
}

#[test]
fn gat_block_heads_streams_and_paths_agree() {
    let device = cpu_autodiff();
    let mut rng = Rng::new(5);
    let batch = crate::batch::GraphBatch::single(&random_graph(&mut rng, 60, 80));
    let x = tensor(rng.values(60 * 7), [60, 7], &device, DType::F32);
    for (merge, beta, width) in [
        (HeadMerge::Concat, None, 12),
        (HeadMerge::Mean, None, 3),
        (HeadMerge::Concat, Some(0.125), 12 + 2),
    ] {
        let config = GatBlockConfig::new(7, 3)
            .with_heads(4)
            .with_merge(merge)
            .with_self_reinforced(beta)
            .with_activation(crate::Activation::Tanhshrink);
        assert_eq!(config.output_width(), width);
        let block = config.init(&device).unwrap();
        assert_eq!(block.output_width(), width);
        let fused = block.forward(x.clone(), batch.adjacency()).unwrap();
        assert_eq!(fused.dims(), [60, width]);
        let reference = block
            .clone()
            .with_implementation(AttentionImpl::Reference)
            .forward(x.clone(), batch.adjacency())
            .unwrap();
        assert!(max_diff(&host(&fused), &host(&reference)) < 1e-5);
    }
    let block = GatBlockConfig::new(7, 3).init(&device).unwrap();
    let wrong = tensor(rng.values(60 * 6), [60, 6], &device, DType::F32);
    assert!(block.forward(wrong, batch.adjacency()).is_err());
    assert!(GatBlockConfig::new(7, 0).init(&device).is_err());
    assert!(GatBlockConfig::new(7, 3)
        .with_self_reinforced(Some(-1.0))
        .init(&device)
        .is_err());
}

#[test]
fn seeded_initialisation_is_deterministic() {
    let weights = |seed| {
        let device = crate::backend::seeded(&cpu(), seed);
        let block = GatBlockConfig::new(5, 4)
            .with_heads(2)
            .init(&device)
            .unwrap();
        (host(&block.weight.val()), host(&block.att_src.val()))
    };
    assert_eq!(weights(42), weights(42));
    assert_ne!(weights(42), weights(43));
}

#[test]
fn attention_coefficients_are_softmax_rows_that_reproduce_attention() {
    let mut rng = Rng::new(13);
    let graph = random_graph(&mut rng, 40, 30);
    let (heads, channels) = (2, 3);
    let with_self = Adjacency::from_graph(&graph);
    let without_self = Adjacency::from_csr(40, graph.offsets(), graph.adjacency(), false).unwrap();
    for adjacency in [with_self, without_self] {
        let c = case(&mut rng, adjacency, heads, channels);
        let device = cpu_autodiff();
        let (n, w) = (c.adjacency.node_count(), heads * channels);
        let z = tensor(c.z.clone(), [n, w], &device, DType::F64).require_grad();
        let a_src = tensor(c.a_src.clone(), [heads, channels], &device, DType::F64);
        let a_dst = tensor(c.a_dst.clone(), [heads, channels], &device, DType::F64);
        let alpha = attention_coefficients(
            z.clone(),
            a_src,
            a_dst,
            &c.adjacency,
            DEFAULT_NEGATIVE_SLOPE,
        )
        .unwrap();
        assert_eq!(alpha.dims(), [c.adjacency.entry_count(), heads]);
        let al = host(&alpha);
        // Rows offsets[i]..offsets[i + 1] are node i's softmax.
        for i in 0..n {
            for k in 0..heads {
                let range = c.adjacency.offsets()[i]..c.adjacency.offsets()[i + 1];
                let total: f64 = range.map(|e| al[e * heads + k]).sum();
                assert!((total - 1.0).abs() < 1e-12, "node {i} head {k}: {total}");
            }
        }
        // Σ_j α_ij z_j per head is what `attention` computes, and so is its gradient.
        let (sources, targets) = (c.adjacency.sources(), c.adjacency.targets());
        let mut aggregated = vec![0.0; n * w];
        for e in 0..sources.len() {
            let (j, i) = (sources[e] as usize, targets[e] as usize);
            for k in 0..heads {
                for f in 0..channels {
                    let col = k * channels + f;
                    aggregated[i * w + col] += al[e * heads + k] * c.z[j * w + col];
                }
            }
        }
        let [out, gz, _, _] = run(&c, AttentionImpl::Auto, DType::F64);
        assert!(max_diff(&aggregated, &out) < 1e-12);
        let r = tensor(c.r.clone(), [n, w], &device, DType::F64);
        let entries = sources.len();
        let messages = (z
            .clone()
            .select(0, c.adjacency.index_tensors(&device).0)
            .reshape([entries * heads, channels])
            * alpha.reshape([entries * heads, 1]))
        .reshape([entries, w]);
        let out = Tensor::<2>::zeros([n, w], (&device, DType::F64)).select_assign(
            0,
            c.adjacency.index_tensors(&device).1,
            messages,
            burn::tensor::IndexingUpdateOp::Add,
        );
        let grads = (out * r).sum().backward();
        assert!(max_diff(&host(&z.grad(&grads).unwrap()), &gz) < 1e-12);
    }
    let z = Tensor::<2>::zeros([39, 6], &cpu());
    let att = Tensor::<2>::zeros([2, 3], &cpu());
    let adjacency = Adjacency::from_graph(&graph);
    assert!(matches!(
        attention_coefficients(z, att.clone(), att, &adjacency, 0.2),
        Err(NnError::NodeCount { .. })
    ));
}
