//! MultiResGNet: the thesis widths, the ablation, bad configurations and gradients of the
//! whole network against central differences.

use burn::module::{ModuleMapper, Param};
use burn::tensor::{DType, Distribution, TensorData};
use weft_mesh::primitives::grid;
use weft_nn::backend::{cpu, cpu_autodiff, seeded};

use super::*;

/// Casts every float tensor of a module (parameters and running statistics) to f64.
struct ToF64;

impl ModuleMapper for ToF64 {
    fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
        param.map(|t| t.cast(DType::F64))
    }
}

fn f64_tensor(values: Vec<f64>, shape: [usize; 2], device: &Device) -> Tensor<2> {
    Tensor::from_data(TensorData::new(values, shape), (device, DType::F64))
}

fn host(t: &Tensor<2>) -> Vec<f64> {
    t.to_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .expect("float tensor")
}

#[test]
fn paper_widths_follow_the_thesis_and_the_network_runs() {
    let device = cpu_autodiff();
    let net = MultiResGnetConfig::preset("paper")
        .unwrap()
        .init(&device)
        .unwrap();
    // M1: one dense module of six 256-wide blocks on the 32-wide input transform.
    assert_eq!(net.multires.local.output_width(), 32 + 6 * 256);
    assert_eq!(net.multires.local.output_width(), 1568);
    let global = net.multires.global.as_ref().unwrap();
    assert_eq!(global.pool.input_width(), 32);
    assert_eq!(global.coarse.blocks.len(), 2);
    assert_eq!(global.coarse.output_width(), 256);
    assert_eq!(global.after.output_width(), 256);
    let hidden = net.hidden.as_ref().unwrap();
    assert_eq!(
        (hidden.input_width(), hidden.output_width()),
        (1568 + 256, 64)
    );

    let mesh = grid(12, 10, 1.0);
    let graph = GraphBatch::single(&mesh.graph());
    let n = mesh.positions.len();
    let x = Tensor::<2>::random([n, 30], Distribution::Default, &device);
    let v = net.input.forward(x.clone()).unwrap();
    let pooled = global.pool.forward(v, &graph).unwrap();
    let kept = pooled.clusters.members.len() as f64 / n as f64;
    assert!(
        (0.5..=0.75).contains(&kept),
        "the pooled graph keeps {kept}"
    );
    assert_eq!(net.forward(x, &graph).unwrap().dims(), [n, 3]);
    assert!(net
        .forward(Tensor::<2>::zeros([n, 29], &device), &graph)
        .is_err());
}

#[test]
fn single_resolution_ablation_and_the_cpu_preset_run() {
    let mesh = grid(6, 5, 1.0);
    let graph = GraphBatch::single(&mesh.graph());
    let n = mesh.positions.len();
    let device = cpu_autodiff();
    let single = MultiResGnetConfig::new()
        .with_global(false)
        .with_global_blocks(0)
        .init(&device)
        .unwrap();
    assert!(single.multires.global.is_none());
    assert_eq!(single.hidden.as_ref().unwrap().input_width(), 1568);
    let x = Tensor::<2>::random([n, 30], Distribution::Default, &device);
    assert_eq!(single.forward(x, &graph).unwrap().dims(), [n, 3]);

    // Inference (running statistics, no autodiff), with PyG's score offset.
    let device = cpu();
    let config = MultiResGnetConfig::preset("cpu")
        .unwrap()
        .with_score_offset(0.5);
    assert_eq!(config.position, PositionFeature::Descriptor);
    let net = config.init(&device).unwrap();
    assert_eq!(net.multires.local.output_width(), 32 + 3 * 64);
    let x = Tensor::<2>::random([n, 30], Distribution::Default, &device);
    let y = host(&net.forward(x, &graph).unwrap());
    assert_eq!(y.len(), n * 3);
    assert!(y.iter().all(|v| v.is_finite()));
}

#[test]
fn bad_configs_are_errors_naming_the_field() {
    let device = cpu();
    let error = |c: MultiResGnetConfig| c.init(&device).unwrap_err().to_string();
    assert!(error(MultiResGnetConfig::new().with_local_blocks(0)).contains("local_blocks"));
    assert!(error(MultiResGnetConfig::new().with_global_blocks(0)).contains("global_blocks"));
    assert!(error(MultiResGnetConfig::new().with_channels(0)).contains("channels"));
    assert!(error(MultiResGnetConfig::new().with_score_offset(-1.0)).contains("score_offset"));
    assert!(error(MultiResGnetConfig::new().with_score_offset(f64::NAN)).contains("score_offset"));
    assert!(
        error(MultiResGnetConfig::new().with_self_reinforced(Some(0.0)))
            .contains("self_reinforced")
    );
    assert!(error(MultiResGnetConfig::new().with_input_widths(vec![])).contains("input_widths"));
    assert!(
        error(MultiResGnetConfig::new().with_output_widths(vec![64, 0])).contains("output_widths")
    );
    assert!(MultiResGnetConfig::preset("huge").is_err());
}

/// `Σ out ⊙ R` of a small network (every part: input transform, dense local module,
/// pooling, coarse blocks, unpooling, `f_GATB`, output transform; batch normalisation
/// with the batch's statistics) against central differences in the input features and
/// in the pooling attention's transform, which reaches the loss only through the scores
/// of eq. 3.11–3.12. The matching must not change under the perturbations.
#[test]
fn gradients_match_central_differences_in_f64() {
    let mesh = grid(4, 3, 1.0);
    let graph = GraphBatch::single(&mesh.graph());
    let (n, d) = (mesh.positions.len(), 8);
    let device = seeded(&cpu_autodiff(), 11);
    let net = MultiResGnetConfig::new()
        .with_joints(2)
        .with_input_widths(vec![6, 5])
        .with_local_blocks(2)
        .with_channels(2)
        .with_heads(2)
        .with_self_reinforced(Some(0.5))
        .with_output_widths(vec![7])
        .init(&device)
        .unwrap()
        .map(&mut ToF64);
    let x0 = host(&Tensor::<2>::random(
        [n, d],
        Distribution::Uniform(-1.0, 1.0),
        &device,
    ));
    let r = host(&Tensor::<2>::random(
        [n, 3],
        Distribution::Uniform(-1.0, 1.0),
        &device,
    ));
    let pool_weight =
        |net: &MultiResGnet| net.multires.global.as_ref().unwrap().pool.weight.clone();
    let w0 = host(&pool_weight(&net).val());
    let w_shape = pool_weight(&net).dims();

    // The loss, the input and the pooling weight (tracked) and the matching.
    let loss = |x: &[f64], w: &[f64]| {
        let mut m = net.clone();
        let weight = Param::from_tensor(f64_tensor(w.to_vec(), w_shape, &device));
        m.multires.global.as_mut().unwrap().pool.weight = weight;
        let x = f64_tensor(x.to_vec(), [n, d], &device).require_grad();
        let v = m.input.forward(x.clone()).unwrap();
        let pool = &m.multires.global.as_ref().unwrap().pool;
        let members = pool.forward(v, &graph).unwrap().clusters.members;
        let out = m.forward(x.clone(), &graph).unwrap();
        let l = (out * f64_tensor(r.clone(), [n, 3], &device)).sum();
        (l, x, pool_weight(&m).val(), members)
    };
    let (l, x, w, members) = loss(&x0, &w0);
    assert!(members.iter().any(|m| m.1.is_some()));
    let grads = l.backward();
    let gx = host(&x.grad(&grads).unwrap());
    let gw = host(&w.grad(&grads).unwrap());
    assert!(gw.iter().any(|g| g.abs() > 1e-6), "{gw:?}");
    let value = |x: &[f64], w: &[f64]| {
        let (l, _, _, m) = loss(x, w);
        assert_eq!(m, members, "the perturbation changed the matching");
        host(&l.unsqueeze_dim(0))[0]
    };
    let eps = 1e-6;
    let central = |f: &dyn Fn(f64) -> f64| (f(eps) - f(-eps)) / (2.0 * eps);
    let nx: Vec<f64> = (0..x0.len())
        .map(|k| {
            central(&|e| {
                let mut x = x0.clone();
                x[k] += e;
                value(&x, &w0)
            })
        })
        .collect();
    let nw: Vec<f64> = (0..w0.len())
        .map(|k| {
            central(&|e| {
                let mut w = w0.clone();
                w[k] += e;
                value(&x0, &w)
            })
        })
        .collect();
    let relative = |a: &[f64], b: &[f64]| {
        let scale = b.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        a.iter()
            .zip(b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max)
            / scale
    };
    assert!(relative(&gx, &nx) < 1e-6, "input: {}", relative(&gx, &nx));
    assert!(relative(&gw, &nw) < 1e-6, "pooling: {}", relative(&gw, &nw));
}
