//! Deterministic test data: a SplitMix64 stream, random graphs and tensors.

use burn::tensor::{DType, Device, Tensor, TensorData};
use weft_mesh::rng::SplitMix64;
use weft_mesh::Graph;

use crate::adjacency::Adjacency;

/// Test-data draws over weft-mesh's seeded generator.
pub(crate) struct Rng(SplitMix64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Rng(SplitMix64::new(seed))
    }

    /// Uniform in `[-1, 1)`.
    pub(crate) fn uniform(&mut self) -> f64 {
        self.0.uniform(-1.0, 1.0)
    }

    /// In `0..n`, by remainder (the test data's draws; [`SplitMix64::below`] differs).
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.0.next_u64() % n as u64) as usize
    }

    pub(crate) fn values(&mut self, len: usize) -> Vec<f64> {
        (0..len).map(|_| self.uniform()).collect()
    }
}

/// A random undirected graph: a ring (so no node is isolated) plus `extra` random chords.
pub(crate) fn random_graph(rng: &mut Rng, n: usize, extra: usize) -> Graph {
    let mut edges: Vec<[u32; 2]> = (0..n).map(|i| [i as u32, ((i + 1) % n) as u32]).collect();
    for _ in 0..extra {
        edges.push([rng.below(n) as u32, rng.below(n) as u32]);
    }
    Graph::from_edges(n, &edges)
}

/// A random directed adjacency (not symmetric), with self-loops.
pub(crate) fn random_directed(rng: &mut Rng, n: usize, edges: usize) -> Adjacency {
    let list: Vec<[u32; 2]> = (0..edges)
        .map(|_| [rng.below(n) as u32, rng.below(n) as u32])
        .collect();
    Adjacency::from_edges(n, &list, true).expect("indices in range")
}

/// A `[rows, cols]` tensor of the given values and dtype.
pub(crate) fn tensor(
    values: Vec<f64>,
    shape: [usize; 2],
    device: &Device,
    dtype: DType,
) -> Tensor<2> {
    Tensor::from_data(TensorData::new(values, shape), (device, dtype))
}

/// The elements of a tensor as f64.
pub(crate) fn host(t: &Tensor<2>) -> Vec<f64> {
    t.to_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .expect("float tensor")
}

/// Largest absolute difference.
pub(crate) fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}
