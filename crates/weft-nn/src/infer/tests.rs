//! Each inference form equals its layer's forward on the inference device.

use burn::module::{Module, ModuleMapper, Param};
use burn::tensor::{DType, Distribution, Tensor};

use super::*;
use crate::backend::{cpu, seeded};
use crate::batch::GraphBatch;
use crate::testutil::{host, max_diff, random_graph, tensor, Rng};
use crate::{
    Activation, DenseGatModuleConfig, GatBlockConfig, HeadMerge, MlpConfig, NormedGatConfig,
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
