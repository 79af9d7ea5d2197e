//! Edge-contraction pooling: a hand-checked matching, the unpooling identity, gradients
//! against central differences, determinism and the pooling ratio on meshes.

use burn::module::Param;
use burn::tensor::{DType, Device, Tensor};
use weft_mesh::primitives::{cylinder, grid};

use super::*;
use crate::backend::{cpu, cpu_autodiff, seeded};
use crate::testutil::{host, max_diff, random_graph, tensor, Rng};

/// A layer with the given parameters (`W` `[d, F]`, `a_src`, `a_dst` `[1, F]`).
fn layer(
    d: usize,
    weight: Vec<f64>,
    att_src: Vec<f64>,
    att_dst: Vec<f64>,
    score_offset: f64,
    device: &Device,
    dtype: DType,
) -> EdgePool {
    let f = att_src.len();
    let param = |v: Vec<f64>, shape| Param::from_tensor(tensor(v, shape, device, dtype));
    EdgePool {
        weight: param(weight, [d, f]),
        att_src: param(att_src, [1, f]),
        att_dst: param(att_dst, [1, f]),
        negative_slope: DEFAULT_NEGATIVE_SLOPE,
        score_offset,
    }
}

fn path(n: u32) -> Graph {
    Graph::from_edges(
        n as usize,
        &(0..n - 1).map(|i| [i, i + 1]).collect::<Vec<_>>(),
    )
}

/// A path 0–1–2–3–4 and a triangle 5, 6, 7. With `W = [1, 0]ᵀ`, `a_src = 1`, `a_dst = 0`
/// the logit of `j → i` is `LeakyReLU(x_j0)`: the path's ends have one neighbour (α = 1),
/// and in the triangle (x_0 = 0, 1, 2) the best edge is 7 → 6 with
/// α = e² / (e⁰ + e²).
fn hand_made() -> (GraphBatch, Vec<f64>) {
    let batch =
        GraphBatch::new(&[&path(5), &Graph::from_edges(3, &[[0, 1], [1, 2], [2, 0]])]).unwrap();
    let x = vec![
        0.3, 1.0, //
        -0.5, 2.0, //
        0.8, -1.0, //
        0.1, 0.5, //
        -0.2, 3.0, //
        0.0, 0.25, //
        1.0, -0.75, //
        2.0, 1.5,
    ];
    (batch, x)
}

fn hand_layer(offset: f64, device: &Device) -> EdgePool {
    layer(
        2,
        vec![1.0, 0.0],
        vec![1.0],
        vec![0.0],
        offset,
        device,
        DType::F64,
    )
}

#[test]
fn hand_made_graph_contracts_the_best_edges_within_each_graph() {
    let device = cpu();
    let (batch, xv) = hand_made();
    let x = tensor(xv.clone(), [8, 2], &device, DType::F64);
    let s = 2f64.exp() / (1.0 + 2f64.exp());
    for offset in [0.0, 0.5] {
        let pooled = hand_layer(offset, &device)
            .forward(x.clone(), &batch)
            .unwrap();
        let c = &pooled.clusters;
        assert_eq!(
            c.members,
            vec![
                (0, Some(1)),
                (2, None),
                (3, Some(4)),
                (5, None),
                (6, Some(7))
            ]
        );
        assert_eq!(c.assignment, vec![0, 0, 1, 2, 2, 3, 4, 4]);
        // Path: the ends merge first (α = 1), the middle node is left alone.
        let scores = host(&c.scores);
        let expected = [1.0 + offset, 1.0, 1.0 + offset, 1.0, s + offset];
        assert!(max_diff(&scores, &expected) < 1e-12, "{scores:?}");
        // Coarse graph: member edges between clusters, once each, per graph.
        let coarse = &c.coarse;
        assert_eq!(coarse.offsets(), &[0, 3, 5]);
        assert_eq!(coarse.graph().edges(), vec![[0, 1], [1, 2], [3, 4]]);
        // Features: s (v_i + v_j), singletons unchanged.
        let v = |r: usize| [xv[2 * r], xv[2 * r + 1]];
        let mut want = Vec::new();
        for (k, &(a, b)) in c.members.iter().enumerate() {
            let (va, vb) = (v(a as usize), b.map_or([0.0; 2], |b| v(b as usize)));
            want.extend([expected[k] * (va[0] + vb[0]), expected[k] * (va[1] + vb[1])]);
        }
        assert!(max_diff(&host(&pooled.features), &want) < 1e-12);
    }
}

#[test]
fn unpooling_gives_both_members_their_sum_and_singletons_themselves() {
    let device = cpu();
    let (batch, xv) = hand_made();
    let x = tensor(xv.clone(), [8, 2], &device, DType::F64);
    for offset in [0.0, 0.5] {
        let pooled = hand_layer(offset, &device)
            .forward(x.clone(), &batch)
            .unwrap();
        let back = host(&edge_unpool(pooled.features, &pooled.clusters).unwrap());
        let sum = |a: usize, b: usize| [xv[2 * a] + xv[2 * b], xv[2 * a + 1] + xv[2 * b + 1]];
        let (p01, p34, p67) = (sum(0, 1), sum(3, 4), sum(6, 7));
        let want: Vec<f64> = [
            p01,
            p01,
            [xv[4], xv[5]],
            p34,
            p34,
            [xv[10], xv[11]],
            p67,
            p67,
        ]
        .concat();
        assert!(max_diff(&back, &want) < 1e-12, "{back:?}");
    }
    // The same identity for a freshly initialised layer on a mesh.
    let mut rng = Rng::new(21);
    let batch = GraphBatch::single(&grid(7, 6, 1.0).graph());
    let xv = rng.values(42 * 3);
    let x = tensor(xv.clone(), [42, 3], &device, DType::F32);
    let pooled = EdgePoolConfig::new(3)
        .init(&seeded(&device, 2))
        .unwrap()
        .forward(x, &batch)
        .unwrap();
    let back = host(&edge_unpool(pooled.features, &pooled.clusters).unwrap());
    for &(a, b) in &pooled.clusters.members {
        let members = [Some(a), b];
        for m in members.iter().flatten() {
            for ch in 0..3 {
                let want: f64 = members
                    .iter()
                    .flatten()
                    .map(|&u| xv[u as usize * 3 + ch])
                    .sum();
                assert!((back[*m as usize * 3 + ch] - want).abs() < 1e-5);
            }
        }
    }
}

/// `L = Σ R_c ⊙ g² + Σ R_f ⊙ unpool(tanh g)`: the tanh keeps `s` from cancelling in the
/// unpooling, so the loss depends on the attention parameters through both paths.
struct GradCase {
    batch: GraphBatch,
    d: usize,
    /// x, W, a_src, a_dst.
    values: [Vec<f64>; 4],
    r_coarse: Vec<f64>,
    r_fine: Vec<f64>,
}

impl GradCase {
    fn loss(
        &self,
        values: &[Vec<f64>; 4],
        device: &Device,
    ) -> (Tensor<2>, EdgePool, Tensor<2>, Clusters) {
        let n = self.batch.node_count();
        let mut x = tensor(values[0].clone(), [n, self.d], device, DType::F64);
        if device.is_autodiff() {
            x = x.require_grad();
        }
        let pool = layer(
            self.d,
            values[1].clone(),
            values[2].clone(),
            values[3].clone(),
            0.0,
            device,
            DType::F64,
        );
        let pooled = pool.forward(x.clone(), &self.batch).unwrap();
        let c = pooled.clusters.members.len();
        let g = pooled.features;
        let r_c = tensor(
            self.r_coarse[..c * self.d].to_vec(),
            [c, self.d],
            device,
            DType::F64,
        );
        let r_f = tensor(self.r_fine.clone(), [n, self.d], device, DType::F64);
        let fine = edge_unpool(g.clone().tanh(), &pooled.clusters).unwrap();
        let loss = (g.clone() * g * r_c).sum().reshape([1, 1]) + (fine * r_f).sum().reshape([1, 1]);
        (loss, pool, x, pooled.clusters)
    }
}

#[test]
fn gradients_match_central_differences_with_the_matching_fixed() {
    let mut rng = Rng::new(17);
    let batch = GraphBatch::new(&[
        &random_graph(&mut rng, 10, 6),
        &random_graph(&mut rng, 8, 3),
    ])
    .unwrap();
    let (n, d, f) = (18, 3, 4);
    let scaled = |rng: &mut Rng, len, k: f64| -> Vec<f64> {
        rng.values(len).into_iter().map(|v| k * v).collect()
    };
    let case = GradCase {
        values: [
            scaled(&mut rng, n * d, 1.0),
            scaled(&mut rng, d * f, 1.5),
            scaled(&mut rng, f, 1.5),
            scaled(&mut rng, f, 1.5),
        ],
        r_coarse: rng.values(n * d),
        r_fine: rng.values(n * d),
        batch,
        d,
    };
    let (loss, pool, x, clusters) = case.loss(&case.values, &cpu_autodiff());
    let grads = loss.backward();
    let analytic = [
        host(&x.grad(&grads).unwrap()),
        host(&pool.weight.val().grad(&grads).unwrap()),
        host(&pool.att_src.val().grad(&grads).unwrap()),
        host(&pool.att_dst.val().grad(&grads).unwrap()),
    ];
    // Not a vacuous check: the scores do reach the loss.
    for a in &analytic[1..] {
        assert!(a.iter().any(|v| v.abs() > 1e-3), "{a:?}");
    }
    assert!(clusters.members.iter().any(|m| m.1.is_some()));
    let device = cpu();
    let eps = 1e-6;
    let eval = |values: &[Vec<f64>; 4]| -> f64 {
        let (loss, _, _, c) = case.loss(values, &device);
        assert_eq!(
            c.members, clusters.members,
            "the perturbation changed the matching"
        );
        host(&loss)[0]
    };
    for (which, a) in analytic.iter().enumerate() {
        let numeric: Vec<f64> = (0..case.values[which].len())
            .map(|k| {
                let (mut p, mut m) = (case.values.clone(), case.values.clone());
                p[which][k] += eps;
                m[which][k] -= eps;
                (eval(&p) - eval(&m)) / (2.0 * eps)
            })
            .collect();
        let scale = numeric.iter().fold(1.0f64, |s, v| s.max(v.abs()));
        let diff = max_diff(a, &numeric) / scale;
        assert!(diff < 1e-7, "parameter {which}: relative difference {diff}");
    }
}

#[test]
fn pooling_is_deterministic_maximal_and_halves_a_mesh() {
    let device = seeded(&cpu(), 5);
    let meshes = [
        grid(24, 18, 1.0).graph(),
        cylinder(20, 16, 1.0, 0.3).graph(),
    ];
    let batch = GraphBatch::new(&[&meshes[0], &meshes[1]]).unwrap();
    let n = batch.node_count();
    let mut rng = Rng::new(33);
    let x = tensor(rng.values(n * 6), [n, 6], &device, DType::F32);
    let pool = EdgePoolConfig::new(6).init(&device).unwrap();
    let a = pool.forward(x.clone(), &batch).unwrap();
    let b = pool.forward(x, &batch).unwrap();
    assert_eq!(a.clusters.members, b.clusters.members);
    assert_eq!(host(&a.features), host(&b.features));

    let c = &a.clusters;
    let fine = batch.graph();
    let membership = batch.membership();
    for g in 0..2 {
        let kept = c.coarse.nodes(g).len() as f64 / batch.nodes(g).len() as f64;
        assert!((0.5..=0.75).contains(&kept), "graph {g} keeps {kept}");
    }
    for (k, &(u, v)) in c.members.iter().enumerate() {
        assert_eq!(c.assignment[u as usize] as usize, k);
        match v {
            // A pair is a fine edge inside one graph.
            Some(v) => {
                assert!(u < v && fine.has_edge(u as usize, v as usize));
                assert_eq!(c.assignment[v as usize] as usize, k);
                assert_eq!(membership[u as usize], membership[v as usize]);
            }
            // A singleton has no free neighbour left (the greedy pass is maximal).
            None => {
                for &w in fine.neighbors(u as usize) {
                    assert!(c.members[c.assignment[w as usize] as usize].1.is_some());
                }
            }
        }
        assert!(c.coarse.nodes(membership[u as usize] as usize).contains(&k));
    }
    // Coarse edges are exactly the clusters with adjacent members.
    let mut joined = std::collections::BTreeSet::new();
    for [p, q] in fine.edges() {
        let (cp, cq) = (c.assignment[p as usize], c.assignment[q as usize]);
        if cp != cq {
            joined.insert([cp.min(cq), cp.max(cq)]);
        }
    }
    assert_eq!(
        c.coarse.graph().edges(),
        joined.into_iter().collect::<Vec<_>>()
    );
}

#[test]
fn bad_inputs_and_configurations_are_errors() {
    let device = cpu();
    let batch = GraphBatch::single(&path(6));
    let pool = EdgePoolConfig::new(4).init(&device).unwrap();
    let wrong_width = Tensor::<2>::zeros([6, 3], &device);
    assert!(matches!(
        pool.forward(wrong_width, &batch),
        Err(NnError::Shape { .. })
    ));
    let wrong_rows = Tensor::<2>::zeros([5, 4], &device);
    assert!(matches!(
        pool.forward(wrong_rows, &batch),
        Err(NnError::NodeCount {
            graph: 6,
            features: 5,
            ..
        })
    ));
    let pooled = pool
        .forward(Tensor::<2>::ones([6, 4], &device), &batch)
        .unwrap();
    assert_eq!(pooled.clusters.members.len(), 3);
    let wrong_coarse = Tensor::<2>::zeros([4, 4], &device);
    assert!(edge_unpool(wrong_coarse, &pooled.clusters).is_err());
    assert!(EdgePoolConfig::new(0).init(&device).is_err());
    assert!(EdgePoolConfig::new(4)
        .with_channels(0)
        .init(&device)
        .is_err());
    assert!(EdgePoolConfig::new(4)
        .with_score_offset(-0.5)
        .init(&device)
        .is_err());
}
