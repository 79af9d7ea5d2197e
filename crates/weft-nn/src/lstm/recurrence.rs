//! The recurrence of one LSTM layer, after the input projections, as one operation on
//! flex with its own backward.
//!
//! Why: as tensor operations every step is four hidden products, three σ, two tanh and
//! the cell, and burn's autodiff differentiates each product alone. Each gate and step
//! then gets its own `H × H` weight gradient — of rank `B`, 8 rows in a `cpu` training
//! window of E^t2 — which is allocated, written and added to the others: E^t2's forward
//! and backward in a training window took 88 ms, for 2 GFLOP (43 ms now;
//! docs/benchmarks.md). Here the forward runs the steps (per step and gate one product
//! `h₋ W_h` into the gate's pre-activation, then σ, tanh and the cell in one pass), the
//! backward runs them back (per step the cell's derivative, then `∂h₋ = Σ_g ∂a_g W_gᵀ`),
//! and each weight gradient is formed once, `∂W_g = Σ_t h_{t−1}ᵀ ∂a_{g,t}`, as one
//! product over all steps.
//!
//! Gates in burn's order `i, f, o, c` (input, forget, output, candidate): `i = σ(aᵢ)`,
//! `f = σ(a_f)`, `o = σ(a_o)`, `g = tanh a_c`, `c = f c₋ + i g`, `h = o tanh c`, with
//! `a = p + b_h + h₋ W_h`, `p` the gate's input projection (`W_x x + b_x`, computed for all
//! steps by the caller) and the zero state before the first step. σ and tanh are the
//! inference passes' ([`crate::infer::math`], within 3e-7 of libm).

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
use rayon::prelude::*;

use crate::backend::is_flex;
use crate::flex::{contiguous, elements, from_vec, gemm_parallelism};
use crate::infer::math;
use crate::real::simd;

/// Whether [`hidden_sequence`] computes `layer` on inputs like `x`: burn's default
/// activations (σ gates, tanh cell and hidden), biases on the hidden transforms (as
/// [`super::LstmEncoderConfig`] builds them), f32 tensors on flex.
pub(crate) fn fused_for(layer: &Lstm, x: &Tensor<3>) -> bool {
    let hidden_biases = [
        Some(&layer.input_gate),
        layer.forget_gate.as_ref(),
        Some(&layer.output_gate),
        Some(&layer.cell_gate),
    ]
    .iter()
    .all(|g| g.is_some_and(|g| g.hidden_transform.bias.is_some()));
    x.dtype() == DType::F32
        && is_flex(&x.device())
        && hidden_biases
        && matches!(layer.gate_activation, Activation::Sigmoid(_))
        && matches!(layer.cell_activation, Activation::Tanh(_))
        && matches!(layer.hidden_activation, Activation::Tanh(_))
}

/// The hidden sequence `[B, T, H]` of one layer from the zero state, given each gate's
/// input projection `projected[g]` (`[B, T, H]`), hidden weight `weights[g]` (`[H, H]`,
/// burn's `[in, out]`) and hidden bias `biases[g]` (`[H]`), gates in the order `i, f,
/// o, c`; f32 tensors on flex ([`fused_for`]).
pub(crate) fn hidden_sequence(
    projected: [Tensor<3>; 4],
    weights: [Tensor<2>; 4],
    biases: [Tensor<1>; 4],
) -> Tensor<3> {
    let [p_i, p_f, p_o, p_c] = projected.map(Tensor::into_dispatch);
    let [w_i, w_f, w_o, w_c] = weights.map(Tensor::into_dispatch);
    let [b_i, b_f, b_o, b_c] = biases.map(Tensor::into_dispatch);
    Tensor::from_dispatch(<Dispatch as LstmRecurrenceOps>::lstm_recurrence(
        p_i, p_f, p_o, p_c, w_i, w_f, w_o, w_c, b_i, b_f, b_o, b_c,
    ))
}

/// The backend extension: one operation, the fused f32 LSTM recurrence.
#[backend_extension(Flex, Autodiff)]
pub trait LstmRecurrenceOps: Backend {
    /// The hidden sequence `[B, T, H]` from the gates' input projections (`[B, T, H]`),
    /// hidden weights (`[H, H]`) and hidden biases (`[H]`), gates `i, f, o, c`; f32 on
    /// flex. Low level: shapes are not checked; call [`hidden_sequence`].
    #[allow(clippy::too_many_arguments)]
    fn lstm_recurrence(
        p_i: FloatTensor<Self>,
        p_f: FloatTensor<Self>,
        p_o: FloatTensor<Self>,
        p_c: FloatTensor<Self>,
        w_i: FloatTensor<Self>,
        w_f: FloatTensor<Self>,
        w_o: FloatTensor<Self>,
        w_c: FloatTensor<Self>,
        b_i: FloatTensor<Self>,
        b_f: FloatTensor<Self>,
        b_o: FloatTensor<Self>,
        b_c: FloatTensor<Self>,
    ) -> FloatTensor<Self>;
}

impl LstmRecurrenceOps for Flex {
    fn lstm_recurrence(
        p_i: FloatTensor<Self>,
        p_f: FloatTensor<Self>,
        p_o: FloatTensor<Self>,
        p_c: FloatTensor<Self>,
        w_i: FloatTensor<Self>,
        w_f: FloatTensor<Self>,
        w_o: FloatTensor<Self>,
        w_c: FloatTensor<Self>,
        b_i: FloatTensor<Self>,
        b_f: FloatTensor<Self>,
        b_o: FloatTensor<Self>,
        b_c: FloatTensor<Self>,
    ) -> FloatTensor<Self> {
        let inputs = [p_i, p_f, p_o, p_c, w_i, w_f, w_o, w_c, b_i, b_f, b_o, b_c].map(contiguous);
        let (sequence, _) = forward(inputs);
        sequence
    }
}

impl<C: CheckpointStrategy> LstmRecurrenceOps for Autodiff<Flex, C> {
    fn lstm_recurrence(
        p_i: FloatTensor<Self>,
        p_f: FloatTensor<Self>,
        p_o: FloatTensor<Self>,
        p_c: FloatTensor<Self>,
        w_i: FloatTensor<Self>,
        w_f: FloatTensor<Self>,
        w_o: FloatTensor<Self>,
        w_c: FloatTensor<Self>,
        b_i: FloatTensor<Self>,
        b_f: FloatTensor<Self>,
        b_o: FloatTensor<Self>,
        b_c: FloatTensor<Self>,
    ) -> FloatTensor<Self> {
        let all = [p_i, p_f, p_o, p_c, w_i, w_f, w_o, w_c, b_i, b_f, b_o, b_c];
        let nodes = all.each_ref().map(|t| t.node());
        let inputs = all.map(|t| contiguous(t.into_primitive()));
        match RecurrenceBackward
            .prepare::<C>(nodes)
            .compute_bound()
            .stateful()
        {
            OpsKind::Tracked(prep) => {
                let (sequence, state) = forward(inputs);
                prep.finish(state, sequence)
            }
            OpsKind::UnTracked(prep) => prep.finish(forward(inputs).0),
        }
    }
}

/// Sizes: batch `B`, steps `T`, hidden width `H`.
#[derive(Clone, Copy, Debug)]
struct Dims {
    b: usize,
    t: usize,
    h: usize,
}

impl Dims {
    /// Offset of row `(batch, step)` in a `[B, T, H]` buffer.
    fn row(&self, batch: usize, step: usize) -> usize {
        (batch * self.t + step) * self.h
    }
}

/// What the backward needs: the hidden sequence (the operation's output, `[B, T, H]`),
/// every step's `i, f, o, g, tanh c` (`[T, 5, B·H]`) and cell (`[T, B·H]`), and the
/// hidden weights.
#[derive(Clone, Debug)]
struct RecurrenceState {
    dims: Dims,
    hidden: FlexTensor,
    activations: Vec<f32>,
    cells: Vec<f32>,
    weights: [FlexTensor; 4],
}

/// The forward pass: the hidden sequence, and the state for the backward.
fn forward(inputs: [FlexTensor; 12]) -> (FlexTensor, RecurrenceState) {
    let shape = inputs[0].layout().shape().to_vec();
    let dims = Dims {
        b: shape[0],
        t: shape[1],
        h: shape[2],
    };
    let Dims { b, t, h } = dims;
    let n = b * h;
    let values = inputs.each_ref().map(elements::<f32>);
    let (projected, weights, biases) = (&values[0..4], &values[4..8], &values[8..12]);
    let mut hidden = vec![0.0f32; b * t * h];
    let mut activations = vec![0.0f32; t * 5 * n];
    let mut cells = vec![0.0f32; t * n];
    let mut pre = [(); 4].map(|_| vec![0.0f32; n]);
    for step in 0..t {
        // The gates in parallel (at `cpu` widths a step's products are too small for
        // `gemm` to split them over threads).
        let previous_hidden = &hidden;
        pre.par_iter_mut().enumerate().for_each(|(g, a)| {
            for r in 0..b {
                let p = &projected[g][dims.row(r, step)..][..h];
                for ((a, &p), &bias) in a[r * h..(r + 1) * h].iter_mut().zip(p).zip(biases[g]) {
                    *a = p + bias;
                }
            }
            if step > 0 {
                // a += h₋ W_g, h₋ the rows of step − 1 in the hidden sequence.
                product(
                    a,
                    h,
                    Operand::rows(&previous_hidden[dims.row(0, step - 1)..], t * h, b, h),
                    Operand::rows(weights[g], h, h, h),
                    true,
                );
            }
        });
        let (act, rest) = activations[step * 5 * n..(step + 1) * 5 * n].split_at_mut(n);
        let (act_f, rest) = rest.split_at_mut(n);
        let (act_o, rest) = rest.split_at_mut(n);
        let (act_g, act_tc) = rest.split_at_mut(n);
        let (before, now) = cells.split_at_mut(step * n);
        let previous = (step > 0).then(|| &before[(step - 1) * n..]);
        let now = &mut now[..n];
        simd(|| {
            for r in 0..b {
                let out = &mut hidden[dims.row(r, step)..][..h];
                for (k, out) in out.iter_mut().enumerate() {
                    let j = r * h + k;
                    let (i, f, o, g) = (
                        math::sigmoid(pre[0][j]),
                        math::sigmoid(pre[1][j]),
                        math::sigmoid(pre[2][j]),
                        math::tanh(pre[3][j]),
                    );
                    let c = previous.map_or(0.0, |p| f * p[j]) + i * g;
                    let tc = math::tanh(c);
                    *out = o * tc;
                    now[j] = c;
                    (act[j], act_f[j], act_o[j], act_g[j], act_tc[j]) = (i, f, o, g, tc);
                }
            }
        });
    }
    let sequence = from_vec(hidden, vec![b, t, h]);
    let state = RecurrenceState {
        dims,
        hidden: sequence.clone(),
        activations,
        cells,
        weights: [4, 5, 6, 7].map(|k| inputs[k].clone()),
    };
    (sequence, state)
}

/// The autodiff step (parents: the four projections, weights and biases). Backwards over
/// the steps, with `∂h` the sequence's gradient plus what step `t + 1` sends back and
/// `δc = ∂c + ∂h o (1 − tanh²c)`: `∂aᵢ = δc g i(1−i)`, `∂a_f = δc c₋ f(1−f)`,
/// `∂a_o = ∂h tanh c o(1−o)`, `∂a_c = δc i (1−g²)`; step `t − 1` receives `∂c₋ = δc f`
/// and `∂h₋ = Σ_g ∂a_g W_gᵀ`. Each `∂a_g` is its projection's gradient; `∂b_g` sums it
/// over rows and steps, `∂W_g = Σ_{t≥1} h_{t−1}ᵀ ∂a_{g,t}`.
#[derive(Debug)]
struct RecurrenceBackward;

impl Backward<Flex, 12> for RecurrenceBackward {
    type State = RecurrenceState;

    fn backward(self, ops: Ops<RecurrenceState, 12>, grads: &mut Gradients, _: &mut Checkpointer) {
        let upstream = contiguous(grads.consume::<Flex>(&ops.node));
        let st = ops.state;
        let dims = st.dims;
        let Dims { b, t, h } = dims;
        let n = b * h;
        let upstream = elements::<f32>(&upstream);
        let weights = st.weights.each_ref().map(elements::<f32>);
        // ∂a of every gate, laid out as its projection `[B, T, H]`.
        let mut da = [(); 4].map(|_| vec![0.0f32; b * t * h]);
        let mut dh_next = vec![0.0f32; n];
        let mut parts = [(); 4].map(|_| vec![0.0f32; n]);
        let mut dc_next = vec![0.0f32; n];
        for step in (0..t).rev() {
            let act = &st.activations[step * 5 * n..(step + 1) * 5 * n];
            let (ai, af, ao, ag, atc) = (
                &act[..n],
                &act[n..2 * n],
                &act[2 * n..3 * n],
                &act[3 * n..4 * n],
                &act[4 * n..],
            );
            let previous = (step > 0).then(|| &st.cells[(step - 1) * n..step * n]);
            simd(|| {
                let [di, df, d_o, dg] = da.each_mut();
                for r in 0..b {
                    let row = dims.row(r, step);
                    for k in 0..h {
                        let j = r * h + k;
                        let (i, f, o, g, tc) = (ai[j], af[j], ao[j], ag[j], atc[j]);
                        let dh = upstream[row + k] + dh_next[j];
                        let dc = dc_next[j] + dh * o * (1.0 - tc * tc);
                        di[row + k] = dc * g * i * (1.0 - i);
                        df[row + k] = previous.map_or(0.0, |p| dc * p[j] * f * (1.0 - f));
                        d_o[row + k] = dh * tc * o * (1.0 - o);
                        dg[row + k] = dc * i * (1.0 - g * g);
                        dc_next[j] = dc * f;
                    }
                }
            });
            if step > 0 {
                // ∂h₋ = Σ_g ∂a_g W_gᵀ, the gates' products in parallel, summed in gate order.
                parts.par_iter_mut().enumerate().for_each(|(g, part)| {
                    product(
                        part,
                        h,
                        Operand::rows(&da[g][dims.row(0, step)..], t * h, b, h),
                        Operand::transposed(weights[g], h, h, h),
                        false,
                    );
                });
                for (j, d) in dh_next.iter_mut().enumerate() {
                    *d = parts[0][j] + parts[1][j] + parts[2][j] + parts[3][j];
                }
            }
        }
        // The rows of steps 1.. of ∂a and of steps ..T−1 of h, packed for the weight
        // gradients (one product each over all steps).
        let pairs = b * t.saturating_sub(1);
        let pack = |values: &[f32], steps: std::ops::Range<usize>| -> Vec<f32> {
            let mut out = Vec::with_capacity(pairs * h);
            for r in 0..b {
                out.extend_from_slice(&values[dims.row(r, steps.start)..dims.row(r, steps.end)]);
            }
            out
        };
        let h_previous = (pairs > 0).then(|| pack(elements::<f32>(&st.hidden), 0..t - 1));
        let [p_i, p_f, p_o, p_c, w_i, w_f, w_o, w_c, b_i, b_f, b_o, b_c] = ops.parents;
        let weight_nodes = [w_i, w_f, w_o, w_c];
        let weight_grads: Vec<Option<Vec<f32>>> = (0..4)
            .into_par_iter()
            .map(|g| {
                weight_nodes[g].as_ref()?;
                let mut dw = vec![0.0f32; h * h];
                if let Some(hp) = &h_previous {
                    let dag = pack(&da[g], 1..t);
                    product(
                        &mut dw,
                        h,
                        Operand::transposed(hp, h, h, pairs),
                        Operand::rows(&dag, h, pairs, h),
                        false,
                    );
                }
                Some(dw)
            })
            .collect();
        for (node, dw) in weight_nodes.iter().zip(weight_grads) {
            if let (Some(node), Some(dw)) = (node, dw) {
                grads.register::<Flex>(node.id, from_vec(dw, vec![h, h]));
            }
        }
        for ((da, projection), bias) in da
            .into_iter()
            .zip([p_i, p_f, p_o, p_c])
            .zip([b_i, b_f, b_o, b_c])
        {
            if let Some(node) = bias {
                let mut db = vec![0.0f32; h];
                for row in da.chunks_exact(h) {
                    for (d, &x) in db.iter_mut().zip(row) {
                        *d += x;
                    }
                }
                grads.register::<Flex>(node.id, from_vec(db, vec![h]));
            }
            if let Some(node) = projection {
                grads.register::<Flex>(node.id, from_vec(da, vec![b, t, h]));
            }
        }
    }
}

/// A matrix operand of [`product`]: `rows × cols` values read at `data[r·row_stride +
/// c·col_stride]`.
struct Operand<'a> {
    data: &'a [f32],
    rows: usize,
    cols: usize,
    row_stride: usize,
    col_stride: usize,
}

impl<'a> Operand<'a> {
    /// `rows × cols` row-major with row stride `stride`.
    fn rows(data: &'a [f32], stride: usize, rows: usize, cols: usize) -> Self {
        Operand {
            data,
            rows,
            cols,
            row_stride: stride,
            col_stride: 1,
        }
    }

    /// The transpose of a `cols × rows` row-major matrix of row stride `stride`.
    fn transposed(data: &'a [f32], stride: usize, rows: usize, cols: usize) -> Self {
        Operand {
            data,
            rows,
            cols,
            row_stride: 1,
            col_stride: stride,
        }
    }

    /// The same values read as the transposed matrix.
    fn transpose(self) -> Self {
        Operand {
            data: self.data,
            rows: self.cols,
            cols: self.rows,
            row_stride: self.col_stride,
            col_stride: self.row_stride,
        }
    }

    /// Whether every element read lies inside `data`.
    fn in_bounds(&self) -> bool {
        self.rows == 0
            || self.cols == 0
            || (self.rows - 1) * self.row_stride + (self.cols - 1) * self.col_stride
                < self.data.len()
    }
}

/// `out = lhs rhs`, or `out += lhs rhs` with `accumulate`; `out` row-major
/// `lhs.rows × rhs.cols` with row stride `stride`. burn flex's own GEMM (`gemm`), called
/// directly because the operands are strided views of the sequence buffers (a step's
/// rows, a transposed weight) that tensors would have to copy out first.
fn product(out: &mut [f32], stride: usize, lhs: Operand<'_>, rhs: Operand<'_>, accumulate: bool) {
    let (m, k, n) = (lhs.rows, lhs.cols, rhs.cols);
    assert_eq!(rhs.rows, k, "inner dimensions of the product");
    assert!(
        lhs.in_bounds() && rhs.in_bounds(),
        "operands of the product"
    );
    assert!(
        m == 0 || n == 0 || (m - 1) * stride + n <= out.len(),
        "output of the product"
    );
    if m == 0 || n == 0 || k == 0 {
        return;
    }
    let parallelism = gemm_parallelism(m, n, k);
    // `gemm`'s kernels are tall (many rows of the output per register block): with the
    // few rows of a step (`B`), multiply `outᵀ = rhsᵀ lhsᵀ` instead, the same products
    // read through swapped strides.
    let (m, n, lhs, rhs, out_rs, out_cs) = if m < n {
        (n, m, rhs.transpose(), lhs.transpose(), 1, stride)
    } else {
        (m, n, lhs, rhs, stride, 1)
    };
    // SAFETY: every element `gemm` reads lies inside `lhs.data` and `rhs.data`, and every
    // one it writes inside `out` (asserted above, before any transposition, which only
    // swaps strides); `out` is borrowed mutably, so nothing else reads or writes it
    // meanwhile.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            out.as_mut_ptr(),
            out_cs as isize,
            out_rs as isize,
            accumulate,
            lhs.data.as_ptr(),
            lhs.col_stride as isize,
            lhs.row_stride as isize,
            rhs.data.as_ptr(),
            rhs.col_stride as isize,
            rhs.row_stride as isize,
            1.0,
            1.0,
            false,
            false,
            false,
            parallelism,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::cpu_autodiff;
    use crate::testutil::{tensor, Rng};

    /// Parameters of one layer in f64, gates `i, f, o, c`: projections `[g][B·T·H]`,
    /// weights `[g][H·H]`, biases `[g][H]`.
    struct Layer {
        p: Vec<Vec<f64>>,
        w: Vec<Vec<f64>>,
        bias: Vec<Vec<f64>>,
    }

    /// The hidden sequence `[B·T·H]` from the definitions, in f64.
    fn reference(l: &Layer, (b, t, h): (usize, usize, usize)) -> Vec<f64> {
        let s = |x: f64| 1.0 / (1.0 + (-x).exp());
        let mut out = vec![0.0; b * t * h];
        for r in 0..b {
            let (mut hp, mut cp) = (vec![0.0; h], vec![0.0; h]);
            for step in 0..t {
                let a: Vec<Vec<f64>> = (0..4)
                    .map(|g| {
                        (0..h)
                            .map(|n| {
                                l.p[g][(r * t + step) * h + n]
                                    + l.bias[g][n]
                                    + (0..h).map(|k| hp[k] * l.w[g][k * h + n]).sum::<f64>()
                            })
                            .collect()
                    })
                    .collect();
                for n in 0..h {
                    let c = s(a[1][n]) * cp[n] + s(a[0][n]) * a[3][n].tanh();
                    cp[n] = c;
                    out[(r * t + step) * h + n] = s(a[2][n]) * c.tanh();
                }
                hp.copy_from_slice(&out[(r * t + step) * h..(r * t + step + 1) * h]);
            }
        }
        out
    }

    /// Values against the f64 definitions, and the gradient of every input (projections,
    /// weights, biases) against central differences of them, through a weighted sum of
    /// the sequence; with several steps and with one (no hidden products).
    #[test]
    fn values_and_gradients_match_the_definitions() {
        for (b, t, h) in [(2, 4, 3), (3, 1, 2)] {
            let device = cpu_autodiff();
            let mut rng = Rng::new(11);
            let scaled = |rng: &mut Rng, n: usize, k: f64| -> Vec<f64> {
                rng.values(n).iter().map(|x| k * x).collect()
            };
            let layer = Layer {
                p: (0..4).map(|_| scaled(&mut rng, b * t * h, 2.0)).collect(),
                w: (0..4).map(|_| scaled(&mut rng, h * h, 1.0)).collect(),
                bias: (0..4).map(|_| scaled(&mut rng, h, 0.5)).collect(),
            };
            let mix = rng.values(b * t * h);
            let leaf = |v: &[f64], shape: [usize; 2]| {
                tensor(v.to_vec(), shape, &device, DType::F32).require_grad()
            };
            let p: Vec<Tensor<2>> = layer.p.iter().map(|v| leaf(v, [b * t, h])).collect();
            let w: Vec<Tensor<2>> = layer.w.iter().map(|v| leaf(v, [h, h])).collect();
            let bias: Vec<Tensor<2>> = layer.bias.iter().map(|v| leaf(v, [1, h])).collect();
            let seq = hidden_sequence(
                [0, 1, 2, 3].map(|g| p[g].clone().reshape([b, t, h])),
                [0, 1, 2, 3].map(|g| w[g].clone()),
                [0, 1, 2, 3].map(|g| bias[g].clone().reshape([h])),
            );
            let weights = tensor(mix.clone(), [b * t, h], &device, DType::F32).reshape([b, t, h]);
            let grads = (seq.clone() * weights).sum().backward();
            let got: Vec<f32> = seq.into_data().try_to_vec().unwrap();
            let want = reference(&layer, (b, t, h));
            for (j, (&g, &r)) in got.iter().zip(&want).enumerate() {
                assert!((f64::from(g) - r).abs() < 1e-6, "h[{j}]: {g} vs {r}");
            }
            let loss = |l: &Layer| -> f64 {
                reference(l, (b, t, h))
                    .iter()
                    .zip(&mix)
                    .map(|(x, m)| x * m)
                    .sum()
            };
            let step = 1e-4;
            let check =
                |name: &str, leaves: &[Tensor<2>], pick: fn(&mut Layer) -> &mut Vec<Vec<f64>>| {
                    for (g, leaf) in leaves.iter().enumerate() {
                        let grad: Vec<f32> =
                            leaf.grad(&grads).unwrap().into_data().try_to_vec().unwrap();
                        for (j, &grad) in grad.iter().enumerate() {
                            let at = |delta: f64| {
                                let mut l = Layer {
                                    p: layer.p.clone(),
                                    w: layer.w.clone(),
                                    bias: layer.bias.clone(),
                                };
                                pick(&mut l)[g][j] += delta;
                                loss(&l)
                            };
                            let fd = (at(step) - at(-step)) / (2.0 * step);
                            assert!(
                                (f64::from(grad) - fd).abs() < 1e-4,
                                "{name} of gate {g}, {j} (B {b}, T {t}): {grad} vs {fd}"
                            );
                        }
                    }
                };
            check("projection", &p, |l| &mut l.p);
            check("weight", &w, |l| &mut l.w);
            check("bias", &bias, |l| &mut l.bias);
        }
    }
}
