//! Each inference form equals its layer's forward on the inference device.

use burn::module::{Module, ModuleMapper, Param};
use burn::tensor::{DType, Distribution, Tensor};

use super::*;
use crate::backend::{cpu, seeded};
use crate::batch::GraphBatch;
use crate::testutil::{host, max_diff, random_graph, tensor, Rng};
use crate::{
    Activation, DenseGatModuleConfig, EdgeSet, GatBlockConfig, HeadMerge, MlpConfig,
    NormedGatConfig, ProcessorConfig,
};

/// Draws every vector parameter and running statistic (γ, β, μ, σ², biases) from
/// U(0.5, 1.5), away from their initial 0 and 1, so that the folding is exercised.
struct Statistics;

impl ModuleMapper for Statistics {
    fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
        if D > 1 {
            return param;
        }
        param.map(|t| Tensor::random(t.shape(), Distribution::Uniform(0.5, 1.5), &t.device()))
    }
}

fn device() -> burn::tensor::Device {
    seeded(&cpu(), 3)
}

fn input(rng: &mut Rng, n: usize, d: usize) -> (Features, Tensor<2>) {
    let values = rng.values(n * d);
    let f = Features::new(values.iter().map(|&v| v as f32).collect(), d).unwrap();
    (f, tensor(values, [n, d], &device(), DType::F32))
}

/// Within 1e-5 of the reference, relative to its largest value.
fn assert_close(got: &Features, want: Tensor<2>, what: &str) {
    let want = host(&want);
    let got: Vec<f64> = got.values().iter().map(|&v| f64::from(v)).collect();
    let scale = want.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    let diff = max_diff(&got, &want);
    assert!(diff <= 1e-5 * scale, "{what}: {diff} (scale {scale})");
}

#[test]
fn mlp_equals_the_layer() {
    let mut rng = Rng::new(1);
    let (f, x) = input(&mut rng, 70, 7);
    for (batch_norm, layer_norm) in [(true, false), (false, false), (false, true)] {
        for activation in [Activation::Tanh, Activation::Relu] {
            let mlp = MlpConfig::new(7, vec![16, 9, 4])
                .with_batch_norm(batch_norm)
                .with_layer_norm(layer_norm)
                .with_activation(activation)
                .with_output_activation(Activation::None)
                .init(&device())
                .unwrap()
                .map(&mut Statistics);
            let fast = InferMlp::from(&mlp);
            assert_eq!((fast.input_width(), fast.output_width()), (7, 4));
            let what =
                format!("MLP, batch norm {batch_norm}, layer norm {layer_norm}, {activation:?}");
            assert_close(
                &fast.forward(&f).unwrap(),
                mlp.forward(x.clone()).unwrap(),
                &what,
            );
        }
    }
}

#[test]
fn gat_block_equals_the_layer() {
    let mut rng = Rng::new(2);
    // More nodes than one row block, so that blocks meet.
    let n = 150;
    let batch = GraphBatch::single(&random_graph(&mut rng, n, 200));
    let (f, x) = input(&mut rng, n, 6);
    for (merge, beta, bias, batch_norm, activation) in [
        (
            HeadMerge::Concat,
            Some(0.5),
            true,
            true,
            Activation::Tanhshrink,
        ),
        (HeadMerge::Concat, None, true, false, Activation::Elu),
        (
            HeadMerge::Mean,
            Some(1.0),
            false,
            true,
            Activation::LeakyRelu(0.1),
        ),
        (HeadMerge::Mean, None, true, true, Activation::Sigmoid),
    ] {
        let block = NormedGatConfig::new(
            GatBlockConfig::new(6, 5)
                .with_heads(3)
                .with_merge(merge)
                .with_self_reinforced(beta)
                .with_bias(bias)
                .with_activation(activation),
        )
        .with_batch_norm(batch_norm)
        .init(&device())
        .unwrap()
        .map(&mut Statistics);
        let fast = InferGat::from(&block);
        assert_eq!(fast.output_width(), block.output_width());
        let want = block.forward(x.clone(), batch.adjacency()).unwrap();
        let got = fast.forward(&f, batch.adjacency()).unwrap();
        assert_close(
            &got,
            want,
            &format!("{merge:?} {beta:?} {bias} {batch_norm}"),
        );
    }
}

#[test]
fn dense_module_equals_the_layer_and_checks_inputs() {
    let mut rng = Rng::new(3);
    let n = 130;
    let batch = GraphBatch::single(&random_graph(&mut rng, n, 150));
    let (f, x) = input(&mut rng, n, 5);
    for dense in [true, false] {
        for batch_norm in [true, false] {
            let module = DenseGatModuleConfig::new(5, 3, 4)
                .with_heads(2)
                .with_self_reinforced(Some(0.25))
                .with_dense(dense)
                .with_batch_norm(batch_norm)
                .init(&device())
                .unwrap()
                .map(&mut Statistics);
            let fast = InferDenseModule::from(&module);
            assert_eq!(fast.output_width(), module.output_width());
            let want = module.forward(x.clone(), batch.adjacency()).unwrap();
            let got = fast.forward(&f, batch.adjacency()).unwrap();
            assert_close(
                &got,
                want,
                &format!("dense {dense}, batch norm {batch_norm}"),
            );
        }
    }
    let fast = InferDenseModule::from(&DenseGatModuleConfig::new(5, 2, 4).init(&device()).unwrap());
    let (wrong, _) = input(&mut rng, n, 4);
    assert!(matches!(
        fast.forward(&wrong, batch.adjacency()),
        Err(NnError::Shape { .. })
    ));
    let (short, _) = input(&mut rng, n - 1, 5);
    assert!(matches!(
        fast.forward(&short, batch.adjacency()),
        Err(NnError::NodeCount { .. })
    ));
    assert!(Features::new(vec![0.0; 7], 2).is_err());
}

#[test]
fn multires_module_equals_the_layer() {
    let mut rng = Rng::new(4);
    let n = 140;
    let batch = GraphBatch::single(&random_graph(&mut rng, n, 160));
    let (f, x) = input(&mut rng, n, 6);
    for global in [true, false] {
        let module = crate::MultiResGModuleConfig::new(6)
            .with_local_blocks(2)
            .with_channels(4)
            .with_heads(2)
            .with_global(global)
            .init(&device())
            .unwrap()
            .map(&mut Statistics);
        let fast = InferMultiRes::from(&module);
        assert_eq!(fast.output_width(), module.output_width());
        let want = module.forward(x.clone(), &batch).unwrap();
        let got = fast.forward(&f, &batch).unwrap();
        assert_close(&got, want, &format!("global {global}"));
    }
}

/// The processor's inference form equals its forward: more rows than one chunk of
/// [`InferMlp::map_rows`], a set whose edges leave most nodes out of their endpoints (the
/// split product's gathered rows), a set with no edges, nodes with no incoming edge, and
/// a schedule that reads the sets in different orders; the latents of a set no step
/// reads come back unchanged.
#[test]
fn processor_equals_the_layer() {
    let device = device();
    let (n, l) = (700, 8);
    let processor = ProcessorConfig::new(l, 4, vec![vec![0, 1], vec![2, 0], vec![1, 2], vec![0]])
        .init(&device)
        .unwrap()
        .map(&mut Statistics);
    let mut rng = Rng::new(11);
    let mesh: Vec<[u32; 2]> = (0..1500)
        .map(|_| [rng.below(n) as u32, rng.below(n) as u32])
        .collect();
    let few: Vec<[u32; 2]> = (0..300)
        .map(|_| [rng.below(60) as u32, 600 + rng.below(40) as u32])
        .collect();
    let lists: [&[[u32; 2]]; 4] = [&mesh, &few, &[], &mesh[..20]];
    let (fast_nodes, nodes) = input(&mut rng, n, l);
    let latents: Vec<(Features, Tensor<2>)> = lists
        .iter()
        .map(|list| input(&mut rng, list.len(), l))
        .collect();
    let sets: Vec<EdgeSet> = lists
        .iter()
        .map(|list| EdgeSet::new(n, list, &device).unwrap())
        .collect();
    let (want_nodes, want_edges) = processor
        .forward(
            nodes,
            &sets,
            latents.iter().map(|(_, t)| t.clone()).collect(),
        )
        .unwrap();

    let fast = InferProcessor::from(&processor);
    let fast_sets: Vec<InferEdgeSet> = lists
        .iter()
        .map(|list| InferEdgeSet::new(n, list).unwrap())
        .collect();
    let mut got_nodes = fast_nodes;
    let mut got_edges: Vec<Features> = latents.iter().map(|(f, _)| f.clone()).collect();
    fast.forward(&mut got_nodes, &fast_sets, &mut got_edges)
        .unwrap();
    assert_close(&got_nodes, want_nodes, "processor nodes");
    for (k, (got, want)) in got_edges.iter().zip(want_edges).enumerate() {
        assert_close(got, want, &format!("edge set {k}"));
    }
    assert_eq!(got_edges[3], latents[3].0, "set 3 is read by no step");

    // Wrong shapes are errors, not panics.
    let mut short = got_edges.clone();
    short[0] = Features::zeros(3, l);
    assert!(fast
        .forward(&mut got_nodes, &fast_sets, &mut short)
        .is_err());
    assert!(fast
        .forward(&mut got_nodes, &fast_sets[..3], &mut got_edges[..3])
        .is_err());
    assert!(InferEdgeSet::new(5, &[[0, 5]]).is_err());
}
