//! Pooling layers on batches of different graphs.

use burn::tensor::{DType, Tensor};
use weft_hierarchy::Hierarchy;

use super::*;
use crate::backend::cpu_autodiff;
use crate::batch::HierarchyBatch;
use crate::sparse::SparseImpl;
use crate::testutil::{host, max_diff, random_graph, tensor, Rng};

fn two_graphs(rng: &mut Rng) -> GraphBatch {
    let a = random_graph(rng, 30, 20);
    let b = random_graph(rng, 45, 10);
    GraphBatch::new(&[&a, &b]).unwrap()
}

#[test]
fn structure_pool_and_unpool_follow_the_hierarchy() {
    let mut rng = Rng::new(1);
    let (a, b) = (
        random_graph(&mut rng, 40, 15),
        random_graph(&mut rng, 64, 30),
    );
    let (ha, hb) = (
        Hierarchy::build(a, 3).unwrap(),
        Hierarchy::build(b, 3).unwrap(),
    );
    let hbatch = HierarchyBatch::new(&[&ha, &hb]).unwrap();
    assert_eq!(hbatch.len(), 3);
    let device = cpu_autodiff();
    let x = tensor(rng.values(104 * 4), [104, 4], &device, DType::F32).require_grad();
    let level = hbatch.level(1).unwrap();
    let coarse = StructurePool.forward(x.clone(), level).unwrap();
    assert_eq!(coarse.dims(), [level.batch.node_count(), 4]);
    // Kept rows are copied unchanged.
    let (xh, ch) = (host(&x), host(&coarse));
    for (r, &k) in level.kept.iter().enumerate() {
        assert_eq!(
            &ch[r * 4..r * 4 + 4],
            &xh[k as usize * 4..k as usize * 4 + 4]
        );
    }
    // Unpooling: fused and generic agree, forward and backward.
    let run = |implementation| {
        let c = StructurePool.forward(x.clone(), level).unwrap();
        let fine = StructureUnpool { implementation }
            .forward(c, level)
            .unwrap();
        let grads = (fine.clone() * fine.clone()).sum().backward();
        (host(&fine), host(&x.grad(&grads).unwrap()))
    };
    let (f1, g1) = run(SparseImpl::Auto);
    let (f2, g2) = run(SparseImpl::Reference);
    assert_eq!(f1.len(), 104 * 4);
    assert!(max_diff(&f1, &f2) < 1e-5 && max_diff(&g1, &g2) < 1e-4);
    // A kept vertex gets its own value back.
    for &k in &level.kept {
        let k = k as usize;
        assert!(max_diff(&f1[k * 4..k * 4 + 4], &xh[k * 4..k * 4 + 4]) < 1e-6);
    }
    let wrong = Tensor::<2>::zeros([10, 4], &device);
    assert!(StructurePool.forward(wrong, level).is_err());
}

fn check_pooled(pooled: &Pooled, batch: &GraphBatch, ratio: f64) {
    let sel = &pooled.selection;
    assert_eq!(sel.fine_count, batch.node_count());
    assert_eq!(sel.coarse.graph_count(), batch.graph_count());
    for g in 0..batch.graph_count() {
        let n = batch.nodes(g).len();
        let k = (ratio * n as f64).ceil() as usize;
        assert_eq!(sel.coarse.nodes(g).len(), k);
        // Kept rows of graph g come from graph g.
        for r in sel.coarse.nodes(g) {
            assert!(batch.nodes(g).contains(&(sel.kept[r] as usize)));
        }
    }
    assert!(sel.kept.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(pooled.features.dims()[0], sel.kept.len());
}

#[test]
fn topk_keeps_the_best_scores_per_graph_and_trains_its_projection() {
    let mut rng = Rng::new(4);
    let batch = two_graphs(&mut rng);
    let device = cpu_autodiff();
    let layer = TopKPoolConfig::new(5)
        .with_ratio(0.4)
        .init(&device)
        .unwrap();
    let x = tensor(rng.values(75 * 5), [75, 5], &device, DType::F32).require_grad();
    let pooled = layer.forward(x.clone(), &batch).unwrap();
    check_pooled(&pooled, &batch, 0.4);
    // Every kept score beats every dropped one in the same graph.
    let p = host(&layer.projection.val());
    let norm = p.iter().map(|v| v * v).sum::<f64>().sqrt();
    let xs = host(&x);
    let score = |r: usize| (0..5).map(|c| xs[r * 5 + c] * p[c]).sum::<f64>() / norm;
    for g in 0..2 {
        let kept: Vec<usize> = pooled.selection.kept.iter().map(|&k| k as usize).collect();
        let worst_kept = batch
            .nodes(g)
            .filter(|r| kept.contains(r))
            .map(score)
            .fold(f64::INFINITY, f64::min);
        let best_dropped = batch
            .nodes(g)
            .filter(|r| !kept.contains(r))
            .map(score)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(worst_kept >= best_dropped);
    }
    let restored = unpool_by_index(pooled.features.clone(), &pooled.selection).unwrap();
    assert_eq!(restored.dims(), [75, 5]);
    let grads = restored.sum().backward();
    assert!(layer.projection.val().grad(&grads).is_some());
    assert!(x.grad(&grads).is_some());
    assert!(TopKPoolConfig::new(5)
        .with_ratio(0.0)
        .init(&device)
        .is_err());
    let two_hop = TopKPoolConfig::new(5)
        .with_ratio(0.4)
        .with_connectivity(Connectivity::TwoHop)
        .init(&device)
        .unwrap()
        .forward(x, &batch)
        .unwrap();
    assert!(two_hop.selection.coarse.graph().edge_count() >= 1);
}

#[test]
fn sag_pool_scores_with_a_graph_convolution() {
    let mut rng = Rng::new(8);
    let batch = two_graphs(&mut rng);
    let device = cpu_autodiff();
    let layer = SagPoolConfig::new(3).with_ratio(0.5).init(&device).unwrap();
    let x = tensor(rng.values(75 * 3), [75, 3], &device, DType::F32).require_grad();
    let pooled = layer.forward(x, &batch).unwrap();
    check_pooled(&pooled, &batch, 0.5);
    let grads = pooled.features.sum().backward();
    assert!(layer.score.weight.val().grad(&grads).is_some());
    // The normalised adjacency is symmetric with Â_ii = 1 / (deg + 1).
    let a = sag::gcn_normalized(&batch);
    assert_eq!(a.nnz(), batch.adjacency().entry_count());
}

#[test]
fn asap_pools_clusters_and_trains_every_map() {
    let mut rng = Rng::new(9);
    let batch = two_graphs(&mut rng);
    let device = cpu_autodiff();
    let layer = AsapPoolConfig::new(4)
        .with_ratio(0.5)
        .init(&device)
        .unwrap();
    let x = tensor(rng.values(75 * 4), [75, 4], &device, DType::F32).require_grad();
    let pooled = layer.forward(x.clone(), &batch).unwrap();
    check_pooled(&pooled, &batch, 0.5);
    let restored = unpool_by_index(pooled.features.clone(), &pooled.selection).unwrap();
    let grads = (restored.clone() * restored).sum().backward();
    for (name, w) in [
        ("query", layer.query.weight.val()),
        ("att_query", layer.att_query.weight.val()),
        ("att_member", layer.att_member.weight.val()),
        ("le_self", layer.le_self.weight.val()),
        ("le_center", layer.le_center.weight.val()),
        ("le_neighbour", layer.le_neighbour.weight.val()),
    ] {
        assert!(w.grad(&grads).is_some(), "{name} has no gradient");
    }
    // Clusters are joined exactly when their centers are within three hops.
    let sel = &pooled.selection;
    let fine = batch.graph();
    for (a, &ka) in sel.kept.iter().enumerate() {
        let dist = fine.bfs_distances(ka as usize);
        for (b, &kb) in sel.kept.iter().enumerate() {
            let d = dist[kb as usize];
            assert_eq!(
                sel.coarse.graph().has_edge(a, b),
                a != b && d <= 3,
                "{a} {b} {d}"
            );
        }
    }
}
