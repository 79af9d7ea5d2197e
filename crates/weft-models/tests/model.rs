//! The Multilevel model end to end on a real garment, body and motion: shapes, skinning
//! weights, LBS, determinism, pair caching, gradients, every pooling kind.

mod common;

use burn::module::{Module, ModuleVisitor, Param};
use burn::tensor::Tensor;
use common::{case, host, model, Case};
use weft_body::features::SkinningWeights;
use weft_body::skinning::{lbs, SkinWeights};
use weft_models::multilevel::{FrameInputs, GarmentInput, MultilevelConfig, PoolingKind};
use weft_models::Clip;

fn inputs(
    c: &Case,
    cfg: &MultilevelConfig,
    frames: std::ops::Range<usize>,
) -> (GarmentInput, FrameInputs) {
    let g = GarmentInput::new(&c.garment, &c.body, &c.betas, cfg).expect("garment input");
    let f = FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &c.trans,
            fps: c.fps,
        },
        frames,
        cfg,
    )
    .expect("frame inputs");
    (g, f)
}

#[test]
fn forward_shapes_weights_and_lbs() {
    let c = case();
    let cfg = MultilevelConfig::new();
    let (g, f) = inputs(&c, &cfg, 2..6);
    let model = model(&cfg, 1, false);
    let pair = model.encode_pair(&g).unwrap();
    let p = model.forward(&pair, &g, &f).unwrap();
    let n = c.garment.vertex_count();
    assert_eq!(p.vertices.dims(), [4, n, 3]);
    assert_eq!(p.weights.dims(), [4, n, 24]);
    assert_eq!(p.blend.dims(), [4, n, 3]);
    let sums = host(p.weights.clone().sum_dim(2));
    assert!(
        sums.iter().all(|s| (s - 1.0).abs() < 1e-5),
        "W rows sum to 1"
    );
    assert!(host(p.vertices.clone()).iter().all(|x| x.is_finite()));
    // Untrained: blend shapes start near zero (blend_gain), and the vertices near the LBS
    // of the transferred weights.
    let blend = host(p.blend);
    let max_blend = blend.iter().fold(0.0f32, |a, &b| a.max(b.abs()));
    assert!(max_blend < 0.05, "initial blend shapes {max_blend} m");
    assert!(max_blend > 0.0, "blend shapes depend on the input");
}

/// With both gains zero the model is exactly LBS with the transferred weights (up to the
/// prior's ε): checks the tensor LBS against weft-body's.
#[test]
fn zero_gains_reproduce_transferred_lbs() {
    let c = case();
    let cfg = MultilevelConfig::new()
        .with_weight_gain(0.0)
        .with_blend_gain(0.0);
    let (g, f) = inputs(&c, &cfg, 3..5);
    let model = model(&cfg, 2, false);
    let p = model
        .forward(&model.encode_pair(&g).unwrap(), &g, &f)
        .unwrap();
    let got = host(p.vertices);
    let weights = SkinningWeights::from_f32(&g.transfer_weights, 24).unwrap();
    let sparse = SkinWeights::from_dense(weights.as_slice(), 24);
    let shaped = c.body.shaped(&[]).unwrap();
    let n = c.garment.vertex_count();
    for (k, t) in (3..5).enumerate() {
        let pose: Vec<[f64; 3]> = (0..24)
            .map(|j| std::array::from_fn(|a| f64::from(c.poses[t][j][a])))
            .collect();
        let a = c
            .body
            .skeleton()
            .skinning_transforms_axis_angle(&shaped.joints, &pose, c.trans[t].map(f64::from))
            .unwrap();
        let want = lbs(&c.garment.positions, &sparse, &a);
        for i in 0..n {
            for d in 0..3 {
                let e = (f64::from(got[(k * n + i) * 3 + d]) - want[i][d]).abs();
                assert!(e < 2e-3, "frame {t} vertex {i}: {e} m from LBS");
            }
        }
    }
}

#[test]
fn deterministic_for_a_seed_and_pair_cache_equals_recomputation() {
    let c = case();
    let cfg = MultilevelConfig::new();
    let (g, f) = inputs(&c, &cfg, 0..3);
    let run = |seed| {
        let model = model(&cfg, seed, false);
        let pair = model.encode_pair(&g).unwrap();
        let cached = host(model.forward(&pair, &g, &f).unwrap().vertices);
        let again = host(
            model
                .forward(&model.encode_pair(&g).unwrap(), &g, &f)
                .unwrap()
                .vertices,
        );
        assert!(cached == again, "cached pair encoding = recomputed");
        assert!(host(pair.fused) == host(model.encode_pair(&g).unwrap().fused));
        cached
    };
    let (a, b, other) = (run(7), run(7), run(8));
    assert!(a == b, "same seed, same output");
    assert!(a != other, "another seed, another model");
}

/// One backward on the autodiff device reaches every parameter.
#[test]
fn gradients_reach_every_parameter() {
    struct Check<'a> {
        grads: &'a burn::tensor::Gradients,
        missing: Vec<String>,
        path: Vec<String>,
        count: usize,
    }
    impl ModuleVisitor for Check<'_> {
        fn enter_module(&mut self, name: &str, _: &str) {
            self.path.push(name.to_string());
        }
        fn exit_module(&mut self, _: &str, _: &str) {
            self.path.pop();
        }
        fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
            self.count += 1;
            let ok = param.val().grad(self.grads).is_some_and(|g| {
                host(g.abs().sum())
                    .first()
                    .is_some_and(|&s| s > 0.0 && s.is_finite())
            });
            if !ok {
                self.missing.push(self.path.join("."));
            }
        }
    }
    let c = case();
    let cfg = MultilevelConfig::new();
    let (g, f) = inputs(&c, &cfg, 1..3);
    let model = model(&cfg, 3, true);
    let p = model
        .forward(&model.encode_pair(&g).unwrap(), &g, &f)
        .unwrap();
    let target = p.vertices.clone().detach() + 0.01;
    let loss = (p.vertices - target).powi_scalar(2).sum();
    let grads = loss.backward();
    let mut check = Check {
        grads: &grads,
        missing: Vec::new(),
        path: Vec::new(),
        count: 0,
    };
    model.visit(&mut check);
    assert!(check.count > 50, "visited {} parameters", check.count);
    assert!(check.missing.is_empty(), "no gradient: {:?}", check.missing);
}

#[test]
fn every_pooling_kind_runs() {
    let c = case();
    for pooling in PoolingKind::ALL {
        let cfg = MultilevelConfig::new()
            .with_pooling(pooling)
            .with_mp_submodules(1);
        let (g, f) = inputs(&c, &cfg, 0..2);
        let model = model(&cfg, 4, false);
        let p = model
            .forward(&model.encode_pair(&g).unwrap(), &g, &f)
            .unwrap_or_else(|e| panic!("{}: {e}", pooling.name()));
        assert_eq!(p.blend.dims(), [2, c.garment.vertex_count(), 3]);
        assert!(host(p.vertices).iter().all(|x| x.is_finite()));
    }
}

/// Attribution's entry point: the pair encoding from a node-feature tensor equals
/// `encode_pair`, and the output is differentiable with respect to those features.
#[test]
fn pair_encoding_from_feature_tensor() {
    let c = case();
    let cfg = MultilevelConfig::new().with_mp_submodules(1);
    let (g, f) = inputs(&c, &cfg, 2..3);
    let net = model(&cfg, 9, true);
    let device = net.device();
    let n = g.vertex_count();
    let x = Tensor::<2>::from_data(
        burn::tensor::TensorData::new(g.node_features.clone(), [n, g.node_feature_width()]),
        &device,
    )
    .require_grad();
    let pair = net.encode_pair_features(&g, x.clone()).unwrap();
    assert!(host(pair.fused.clone()) == host(net.encode_pair(&g).unwrap().fused));
    let v = net.forward(&pair, &g, &f).unwrap().vertices;
    let grads = v.slice([0..1, 10..11, 0..3]).sum().backward();
    let gx = host(x.grad(&grads).expect("gradient of the node features"));
    assert!(gx.iter().any(|&v| v != 0.0) && gx.iter().all(|v| v.is_finite()));
    let wrong = Tensor::<2>::zeros([n, 5], &device);
    assert!(net.encode_pair_features(&g, wrong).is_err());
}

/// `body_contact`: the inputs hold a scaled distance in [−1, 1] and a unit normal per
/// vertex and frame, the blend shapes depend on them, their map gets a gradient, and
/// inputs built for the other setting are refused.
#[test]
fn body_contact_enters_the_blend_shapes() {
    let c = case();
    let cfg = MultilevelConfig::new();
    assert!(cfg.body_contact, "the cpu preset reads body contact");
    assert!(!MultilevelConfig::paper().body_contact, "seed 000 has none");
    let (g, f) = inputs(&c, &cfg, 1..3);
    let contact = f.contact.clone().expect("contact features");
    assert_eq!(contact.len(), 2 * g.vertex_count() * 4);
    for row in contact.chunks(4) {
        assert!((-1.0..=1.0).contains(&row[0]), "{row:?}");
        let len = row[1..].iter().map(|x| x * x).sum::<f32>().sqrt();
        assert!((len - 1.0).abs() < 1e-4, "{row:?}");
    }
    // A skirt on the body: some vertices near it, none all the way out.
    assert!(
        contact.chunks(4).any(|r| r[0] < 0.5),
        "no vertex near the body"
    );

    let net = model(&cfg, 5, true);
    let pair = net.encode_pair(&g).unwrap();
    let p = net.forward(&pair, &g, &f).unwrap();
    let mut zeroed = f.clone();
    zeroed.contact = Some(vec![0.0; contact.len()]);
    let q = net.forward(&pair, &g, &zeroed).unwrap();
    assert!(
        host(p.blend.clone()) != host(q.blend),
        "blend shapes read the contact"
    );
    let grads = p.vertices.sum().backward();
    for sub in &net.mp {
        let map = sub.contact.as_ref().expect("contact map");
        let gw = host(map.weight.val().grad(&grads).expect("contact gradient"));
        assert!(gw.iter().any(|&x| x != 0.0) && gw.iter().all(|x| x.is_finite()));
    }

    let off = MultilevelConfig::new().with_body_contact(false);
    let (_, plain) = inputs(&c, &off, 1..3);
    assert!(plain.contact.is_none());
    let e = net.forward(&pair, &g, &plain).unwrap_err().to_string();
    assert!(e.contains("body contact"), "{e}");
    let without = model(&off, 5, false);
    let e = without
        .forward(&without.encode_pair(&g).unwrap(), &g, &f)
        .unwrap_err()
        .to_string();
    assert!(e.contains("body contact"), "{e}");
}
