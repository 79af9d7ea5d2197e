//! `tanh` as one fused operation on flex, with its own backward.
//!
//! Why: flex computes `Tensor::tanh` with libm's scalar `tanhf`, and the form M^mp used
//! instead, `2σ(2x) − 1`, is four element-wise passes forward and four backward, each
//! with its own allocation and thread dispatch, over scalar `expf` (perf of a `cpu`
//! training step on the tiny dataset: `expf` 6 % of the samples, flex's unary kernel
//! 3 %). Here the forward is one vectorised pass (the inference passes' polynomial,
//! [`crate::infer::math::tanh`], within 3e-7 of libm) that keeps its output, and the
//! backward one pass `∂L/∂x = ∂L/∂y · (1 − y²)`. Other backends and dtypes take
//! `Tensor::tanh`.

use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::CheckpointStrategy;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::autodiff::Autodiff;
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{backend_extension, Backend, Dispatch, Flex};
use burn::tensor::{DType, Tensor};
use rayon::prelude::*;

use crate::backend::is_flex;
use crate::flex::{contiguous, elements, from_vec, PARALLEL_CHUNK as CHUNK};
use crate::infer::math;
use crate::real::simd;

/// `tanh x` element-wise; see the module documentation.
pub fn tanh<const D: usize>(x: Tensor<D>) -> Tensor<D> {
    if x.dtype() == DType::F32 && is_flex(&x.device()) {
        Tensor::from_dispatch(<Dispatch as TanhOps>::fused_tanh(x.into_dispatch()))
    } else {
        x.tanh()
    }
}

/// The backend extension: one operation, fused f32 tanh.
#[backend_extension(Flex, Autodiff)]
pub trait TanhOps: Backend {
    /// `tanh x` of an f32 flex tensor (low level: call [`tanh`], which routes).
    fn fused_tanh(x: FloatTensor<Self>) -> FloatTensor<Self>;
}

impl TanhOps for Flex {
    fn fused_tanh(x: FloatTensor<Self>) -> FloatTensor<Self> {
        forward(x)
    }
}

impl<C: CheckpointStrategy> TanhOps for Autodiff<Flex, C> {
    fn fused_tanh(x: FloatTensor<Self>) -> FloatTensor<Self> {
        match TanhBackward
            .prepare::<C>([x.node()])
            .compute_bound()
            .stateful()
        {
            OpsKind::Tracked(prep) => {
                let y = forward(x.into_primitive());
                prep.finish(y.clone(), y)
            }
            OpsKind::UnTracked(prep) => prep.finish(forward(x.into_primitive())),
        }
    }
}

/// `y = tanh x`, in place where `x` is not shared.
fn forward(x: FlexTensor) -> FlexTensor {
    let mut x = contiguous(x);
    let n = x.layout().num_elements();
    let apply = |v: &mut [f32]| {
        v.par_chunks_mut(CHUNK).for_each(|c| {
            simd(|| {
                for e in c {
                    *e = math::tanh(*e);
                }
            })
        })
    };
    if let Some(s) = x.try_storage_mut::<f32>() {
        apply(&mut s[..n]);
        return x;
    }
    let mut v = elements::<f32>(&x).to_vec();
    apply(&mut v);
    from_vec(v, x.layout().shape().to_vec())
}

/// The autodiff step of the fused operation (parent: `x`; state: `y`).
#[derive(Debug)]
struct TanhBackward;

impl Backward<Flex, 1> for TanhBackward {
    type State = FlexTensor;

    fn backward(self, ops: Ops<FlexTensor, 1>, grads: &mut Gradients, _: &mut Checkpointer) {
        let [node] = ops.parents;
        let grad = contiguous(grads.consume::<Flex>(&ops.node));
        let Some(node) = node else {
            return;
        };
        let y = contiguous(ops.state);
        let mut dx = elements::<f32>(&grad).to_vec();
        dx.par_chunks_mut(CHUNK)
            .zip(elements::<f32>(&y).par_chunks(CHUNK))
            .for_each(|(g, y)| {
                simd(|| {
                    for (g, &y) in g.iter_mut().zip(y) {
                        *g *= 1.0 - y * y;
                    }
                })
            });
        grads.register::<Flex>(node.id, from_vec(dx, y.layout().shape().to_vec()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{cpu, cpu_autodiff};
    use crate::testutil::{tensor, Rng};

    /// Forward within 3e-7 of libm's tanh, on a shared input too (left unchanged).
    #[test]
    fn forward_matches_libm() {
        let mut rng = Rng::new(3);
        let v: Vec<f32> = rng
            .values(40_000)
            .iter()
            .map(|x| (12.0 * x) as f32)
            .collect();
        let x = tensor(
            v.iter().map(|&x| x as f64).collect(),
            [200, 200],
            &cpu(),
            DType::F32,
        );
        let kept = x.clone();
        let y: Vec<f32> = tanh(x).into_data().try_to_vec().unwrap();
        for (&x, &y) in v.iter().zip(&y) {
            assert!((y - x.tanh()).abs() <= 3e-7, "tanh {x}: {y}");
        }
        let kept: Vec<f32> = kept.into_data().try_to_vec().unwrap();
        assert_eq!(kept, v);
    }

    /// The backward against central differences of the f64 reference, through a
    /// weighted sum so that every element's gradient differs.
    #[test]
    fn backward_matches_central_differences() {
        let device = cpu_autodiff();
        let mut rng = Rng::new(4);
        let v: Vec<f64> = rng.values(64).iter().map(|x| 4.0 * x).collect();
        let w: Vec<f64> = rng.values(64);
        let x = tensor(v.clone(), [8, 8], &device, DType::F32).require_grad();
        let wt = tensor(w.clone(), [8, 8], &device, DType::F32);
        let loss = (tanh(x.clone()) * wt).sum();
        let grads = loss.backward();
        let g: Vec<f32> = x.grad(&grads).unwrap().into_data().try_to_vec().unwrap();
        let h = 1e-4;
        for i in 0..64 {
            let fd = w[i] * ((v[i] + h).tanh() - (v[i] - h).tanh()) / (2.0 * h);
            assert!((g[i] as f64 - fd).abs() < 2e-6, "{i}: {} vs {fd}", g[i]);
        }
    }
}
