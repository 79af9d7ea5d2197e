//! End to end: two GAT blocks (fused kernel) on a batch of two different graphs, trained
//! with Adamax under cosine annealing, fit a smooth per-vertex target; the same seed gives
//! the same losses.

use weft_mesh::primitives::{builtin_garment, grid};
use weft_nn::backend::{cpu_autodiff, seeded};
use weft_nn::burn::module::Module;
use weft_nn::burn::optim::GradientsParams;
use weft_nn::burn::tensor::{Tensor, TensorData};
use weft_nn::{
    cosine_annealing, Activation, AdamaxConfig, GatBlock, GatBlockConfig, GraphBatch, HeadMerge,
};

#[derive(Module, Debug)]
struct Net {
    first: GatBlock,
    second: GatBlock,
}

fn train(seed: u64) -> Vec<f64> {
    let garment = builtin_garment();
    let sheet = grid(12, 9, 0.1);
    let batch = GraphBatch::new(&[&garment.graph(), &sheet.graph()]).unwrap();
    let positions: Vec<[f64; 3]> = garment
        .positions
        .iter()
        .chain(&sheet.positions)
        .copied()
        .collect();
    let n = positions.len();
    let device = seeded(&cpu_autodiff(), seed);
    let x = Tensor::<2>::from_data(
        TensorData::new(
            positions
                .iter()
                .flatten()
                .map(|&v| v as f32)
                .collect::<Vec<_>>(),
            [n, 3],
        ),
        &device,
    );
    // Target: a smooth function of position, one channel.
    let target = Tensor::<2>::from_data(
        TensorData::new(
            positions
                .iter()
                .map(|p| (3.0 * p[0]).sin() as f32 + p[1] as f32)
                .collect::<Vec<_>>(),
            [n, 1],
        ),
        &device,
    );
    let mut net = Net {
        first: GatBlockConfig::new(3, 8)
            .with_heads(4)
            .with_self_reinforced(Some(0.125))
            .with_activation(Activation::Tanhshrink)
            .init(&device)
            .unwrap(),
        second: GatBlockConfig::new(36, 1)
            .with_heads(4)
            .with_merge(HeadMerge::Mean)
            .init(&device)
            .unwrap(),
    };
    let mut optim = AdamaxConfig::new().init();
    let mut schedule = cosine_annealing(3e-2, 1e-4, 60).unwrap();
    let adjacency = batch.adjacency();
    let mut losses = Vec::new();
    for _ in 0..60 {
        let h = net.first.forward(x.clone(), adjacency).unwrap();
        let y = net.second.forward(h, adjacency).unwrap();
        let loss = (y - target.clone()).powf_scalar(2.0).mean();
        losses.push(f64::from(loss.clone().into_scalar::<f32>()));
        let grads = GradientsParams::from_grads(loss.backward(), &net);
        net = optim.step(schedule.step(), net, grads);
    }
    losses
}

#[test]
fn gat_blocks_fit_a_target_with_adamax_deterministically() {
    let losses = train(3);
    let (first, last) = (losses[0], *losses.last().unwrap());
    assert!(last.is_finite() && last < 0.5 * first, "{first} → {last}");
    assert_eq!(losses, train(3));
}
