//! One LSTM step after the gate pre-activations, as one fused operation on flex with its
//! own backward.
//!
//! Why: as tensor operations the step is three σ, two tanh, three products and a sum,
//! each with its own allocation, thread dispatch and autodiff node, on tensors of
//! `frames × hidden` elements (8 × 768 for E^t2 in a `cpu` training window): the
//! bookkeeping costs more than the arithmetic, for 2 layers × 5 steps per window. Here
//! the forward is one pass (σ and tanh from the inference passes' polynomials,
//! [`crate::infer::math`], within 3e-7 of libm) and the backward another.
//!
//! With `aᵢ, a_f, a_o, a_c` the pre-activations and `c₋` the previous cell:
//! `i = σ(aᵢ)`, `f = σ(a_f)`, `o = σ(a_o)`, `g = tanh a_c`, `c = f c₋ + i g`,
//! `h = o tanh c`. The operation returns `[h | c]` side by side (`[B, 2W]`), as burn's
//! autodiff has one output per operation.

use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::CheckpointStrategy;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::autodiff::Autodiff;
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{backend_extension, Backend, Dispatch, Flex};
use burn::nn::activation::Activation;
use burn::nn::Lstm;
use burn::tensor::{DType, Tensor};

use crate::backend::is_flex;
use crate::flex::{contiguous, elements, from_vec};
use crate::infer::math;
use crate::real::simd;

/// Whether [`lstm_cell`] computes `layer`'s steps on inputs like `x`: burn's default
/// activations (σ gates, tanh cell and hidden) on f32 tensors on flex.
pub(crate) fn fused_for(layer: &Lstm, x: &Tensor<3>) -> bool {
    x.dtype() == DType::F32
        && is_flex(&x.device())
        && matches!(layer.gate_activation, Activation::Sigmoid(_))
        && matches!(layer.cell_activation, Activation::Tanh(_))
        && matches!(layer.hidden_activation, Activation::Tanh(_))
}

/// `(h, c)` of one step from the gate pre-activations `[aᵢ, a_f, a_o, a_c]` (each
/// `[B, W]`) and the previous cell `c₋` (`None`: the zero state); f32 tensors on flex
/// ([`fused_for`]).
pub(crate) fn lstm_cell(gates: [Tensor<2>; 4], cell: Option<Tensor<2>>) -> (Tensor<2>, Tensor<2>) {
    let [b, w] = gates[0].dims();
    let cell = cell.unwrap_or_else(|| Tensor::zeros([b, w], (&gates[0].device(), DType::F32)));
    let [i, f, o, c] = gates.map(Tensor::into_dispatch);
    let out = Tensor::<2>::from_dispatch(<Dispatch as LstmCellOps>::fused_lstm_cell(
        i,
        f,
        o,
        c,
        cell.into_dispatch(),
    ));
    (out.clone().slice([0..b, 0..w]), out.slice([0..b, w..2 * w]))
}

/// The backend extension: one operation, the fused f32 LSTM step.
#[backend_extension(Flex, Autodiff)]
pub trait LstmCellOps: Backend {
    /// `[h | c]` (`[B, 2W]`) from `aᵢ, a_f, a_o, a_c, c₋` (each `[B, W]`, f32 on flex).
    /// Low level: shapes are not checked; call [`lstm_cell`].
    fn fused_lstm_cell(
        input: FloatTensor<Self>,
        forget: FloatTensor<Self>,
        output: FloatTensor<Self>,
        candidate: FloatTensor<Self>,
        cell: FloatTensor<Self>,
    ) -> FloatTensor<Self>;
}

impl LstmCellOps for Flex {
    fn fused_lstm_cell(
        input: FloatTensor<Self>,
        forget: FloatTensor<Self>,
        output: FloatTensor<Self>,
        candidate: FloatTensor<Self>,
        cell: FloatTensor<Self>,
    ) -> FloatTensor<Self> {
        forward([input, forget, output, candidate, cell].map(contiguous)).0
    }
}

impl<C: CheckpointStrategy> LstmCellOps for Autodiff<Flex, C> {
    fn fused_lstm_cell(
        input: FloatTensor<Self>,
        forget: FloatTensor<Self>,
        output: FloatTensor<Self>,
        candidate: FloatTensor<Self>,
        cell: FloatTensor<Self>,
    ) -> FloatTensor<Self> {
        let nodes = [
            input.node(),
            forget.node(),
            output.node(),
            candidate.node(),
            cell.node(),
        ];
        let inputs =
            [input, forget, output, candidate, cell].map(|t| contiguous(t.into_primitive()));
        match CellBackward.prepare::<C>(nodes).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let (out, state) = forward(inputs);
                prep.finish(state, out)
            }
            OpsKind::UnTracked(prep) => prep.finish(forward(inputs).0),
        }
    }
}

/// What the backward needs: `i, f, o, g, tanh c` side by side per element (`[5, B·W]`),
/// and `c₋`.
#[derive(Clone, Debug)]
struct CellState {
    activations: Vec<f32>,
    cell: FlexTensor,
    shape: [usize; 2],
}

/// The forward pass: `[h | c]` and the state for the backward.
fn forward(inputs: [FlexTensor; 5]) -> (FlexTensor, CellState) {
    let shape = inputs[0].layout().shape().to_vec();
    let (b, w) = (shape[0], shape[1]);
    let n = b * w;
    let [ai, af, ao, ac, prev] = inputs.each_ref().map(|t| &elements::<f32>(t)[..n]);
    let mut out = vec![0.0f32; 2 * n];
    let mut act = vec![0.0f32; 5 * n];
    simd(|| {
        let (acts, rest) = act.split_at_mut(n);
        let (actf, rest) = rest.split_at_mut(n);
        let (acto, rest) = rest.split_at_mut(n);
        let (actg, acttc) = rest.split_at_mut(n);
        for r in 0..b {
            let (h_row, c_row) = out[2 * r * w..2 * (r + 1) * w].split_at_mut(w);
            for k in 0..w {
                let j = r * w + k;
                let (i, f, o, g) = (
                    math::sigmoid(ai[j]),
                    math::sigmoid(af[j]),
                    math::sigmoid(ao[j]),
                    math::tanh(ac[j]),
                );
                let c = f * prev[j] + i * g;
                let tc = math::tanh(c);
                h_row[k] = o * tc;
                c_row[k] = c;
                (acts[j], actf[j], acto[j], actg[j], acttc[j]) = (i, f, o, g, tc);
            }
        }
    });
    let state = CellState {
        activations: act,
        cell: inputs[4].clone(),
        shape: [b, w],
    };
    (from_vec(out, vec![b, 2 * w]), state)
}

/// The autodiff step (parents: `aᵢ, a_f, a_o, a_c, c₋`). With `δc = ∂L/∂c + ∂L/∂h · o
/// (1 − tanh²c)`: `∂aᵢ = δc g i(1−i)`, `∂a_f = δc c₋ f(1−f)`, `∂a_o = ∂L/∂h tanh c
/// o(1−o)`, `∂a_c = δc i (1−g²)`, `∂c₋ = δc f`.
#[derive(Debug)]
struct CellBackward;

impl Backward<Flex, 5> for CellBackward {
    type State = CellState;

    fn backward(self, ops: Ops<CellState, 5>, grads: &mut Gradients, _: &mut Checkpointer) {
        let grad = contiguous(grads.consume::<Flex>(&ops.node));
        let st = ops.state;
        let [b, w] = st.shape;
        let n = b * w;
        let grad = &elements::<f32>(&grad)[..2 * n];
        let prev = &elements::<f32>(&st.cell)[..n];
        let act = &st.activations;
        let (ai, af, ao, ag, atc) = (
            &act[..n],
            &act[n..2 * n],
            &act[2 * n..3 * n],
            &act[3 * n..4 * n],
            &act[4 * n..5 * n],
        );
        let mut d = [(); 5].map(|_| vec![0.0f32; n]);
        simd(|| {
            let [di, df, d_o, dg, dc_prev] = d.each_mut();
            for r in 0..b {
                let (dh_row, dc_row) = grad[2 * r * w..2 * (r + 1) * w].split_at(w);
                for k in 0..w {
                    let j = r * w + k;
                    let (i, f, o, g, tc) = (ai[j], af[j], ao[j], ag[j], atc[j]);
                    let dh = dh_row[k];
                    let dc = dc_row[k] + dh * o * (1.0 - tc * tc);
                    di[j] = dc * g * i * (1.0 - i);
                    df[j] = dc * prev[j] * f * (1.0 - f);
                    d_o[j] = dh * tc * o * (1.0 - o);
                    dg[j] = dc * i * (1.0 - g * g);
                    dc_prev[j] = dc * f;
                }
            }
        });
        for (node, values) in ops.parents.into_iter().zip(d) {
            if let Some(node) = node {
                grads.register::<Flex>(node.id, from_vec(values, vec![b, w]));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::cpu_autodiff;
    use crate::testutil::{tensor, Rng};

    /// The step in f64 from the definitions, for the references below.
    fn reference(a: [f64; 4], prev: f64) -> (f64, f64) {
        let s = |x: f64| 1.0 / (1.0 + (-x).exp());
        let c = s(a[1]) * prev + s(a[0]) * a[3].tanh();
        (s(a[2]) * c.tanh(), c)
    }

    /// Values against the f64 definitions, and every gradient against central
    /// differences of them, through weighted sums of `h` and `c`.
    #[test]
    fn values_and_gradients_match_the_definitions() {
        let device = cpu_autodiff();
        let mut rng = Rng::new(5);
        let (b, w) = (3, 4);
        let n = b * w;
        let vals: Vec<Vec<f64>> = (0..5)
            .map(|_| rng.values(n).iter().map(|x| 3.0 * x).collect())
            .collect();
        let (wh, wc) = (rng.values(n), rng.values(n));
        let leaves: Vec<Tensor<2>> = vals
            .iter()
            .map(|v| tensor(v.clone(), [b, w], &device, DType::F32).require_grad())
            .collect();
        let gates = [0, 1, 2, 3].map(|k| leaves[k].clone());
        let (h, c) = lstm_cell(gates, Some(leaves[4].clone()));
        let loss = (h.clone() * tensor(wh.clone(), [b, w], &device, DType::F32)).sum()
            + (c.clone() * tensor(wc.clone(), [b, w], &device, DType::F32)).sum();
        let grads = loss.backward();
        let (h, c): (Vec<f32>, Vec<f32>) = (
            h.into_data().try_to_vec().unwrap(),
            c.into_data().try_to_vec().unwrap(),
        );
        let at = |j: usize, k: usize, delta: f64| {
            let mut x = [0.0; 5];
            for (m, v) in x.iter_mut().enumerate() {
                *v = vals[m][j] + if m == k { delta } else { 0.0 };
            }
            let (h, c) = reference([x[0], x[1], x[2], x[3]], x[4]);
            wh[j] * h + wc[j] * c
        };
        for j in 0..n {
            let x: Vec<f64> = (0..5).map(|m| vals[m][j]).collect();
            let (rh, rc) = reference([x[0], x[1], x[2], x[3]], x[4]);
            assert!((f64::from(h[j]) - rh).abs() < 1e-6, "h {j}");
            assert!((f64::from(c[j]) - rc).abs() < 1e-6, "c {j}");
        }
        let step = 1e-4;
        for (k, leaf) in leaves.iter().enumerate() {
            let g: Vec<f32> = leaf.grad(&grads).unwrap().into_data().try_to_vec().unwrap();
            for (j, &g) in g.iter().enumerate() {
                let fd = (at(j, k, step) - at(j, k, -step)) / (2.0 * step);
                assert!(
                    (f64::from(g) - fd).abs() < 2e-5,
                    "input {k}, {j}: {g} vs {fd}"
                );
            }
        }
    }
}
