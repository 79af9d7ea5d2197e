//! Stacked LSTM encoders: the temporal encoders of seed 000 (§3.2, supplement §1): E^t1 over
//! the pose history (two layers, 128 channels) and E^t2 over body-vertex velocities (two
//! layers). burn 0.22 has a single-layer [`Lstm`]; this stacks them, each layer reading the
//! previous one's hidden sequence. Kaiming-initialised ([`crate::init::kaiming`]).
//!
//! The parameters and records are burn's; the forward pass is weft's ([`layer_forward`]):
//! the same arithmetic arranged so that E^t2 at `paper` widths (132 M parameters, bound
//! by reading its weights) reads each input weight once per window instead of once per
//! step, and skips the hidden products of the zero initial state. After the input
//! projections, the recurrence of a layer is one fused operation with its own backward
//! on flex ([`recurrence`]).
//!
//! ```text
//! x ─▶ W_x (all steps at once) ─┐
//! h₋ ─▶ W_h ────────────────────┴─▶ + ─▶ cell (σ, tanh, c = f c₋ + i g, h = o tanh c)
//! ```

mod recurrence;

use burn::config::Config;
use burn::module::Module;
use burn::nn::{GateController, Lstm, LstmConfig};
use burn::tensor::{Device, Tensor};

use crate::error::{check_shape, NnError, ANY};
use crate::init::kaiming;

/// Configuration of an [`LstmEncoder`].
#[derive(Config, Debug)]
pub struct LstmEncoderConfig {
    /// Features per time step.
    pub d_input: usize,
    /// Hidden width of every layer.
    pub d_hidden: usize,
    /// Stacked layers.
    #[config(default = 2)]
    pub layers: usize,
}

/// A stack of LSTMs over `[batch, time, features]` sequences.
#[derive(Module, Debug)]
pub struct LstmEncoder {
    /// The layers, input first.
    pub layers: Vec<Lstm>,
}

impl LstmEncoderConfig {
    /// Builds the encoder; errors on zero sizes.
    pub fn init(&self, device: &Device) -> crate::Result<LstmEncoder> {
        if self.d_input == 0 || self.d_hidden == 0 || self.layers == 0 {
            return Err(NnError::Config(format!(
                "an LSTM encoder needs positive sizes, got input {}, hidden {}, layers {}",
                self.d_input, self.d_hidden, self.layers
            )));
        }
        let layers = (0..self.layers)
            .map(|k| {
                let d_in = if k == 0 { self.d_input } else { self.d_hidden };
                LstmConfig::new(d_in, self.d_hidden, true)
                    .with_initializer(kaiming())
                    .init(device)
            })
            .collect();
        Ok(LstmEncoder { layers })
    }
}

impl LstmEncoder {
    /// Input features per step.
    pub fn input_width(&self) -> usize {
        self.layers.first().map_or(0, |l| {
            l.input_gate.input_transform.weight.shape().dims::<2>()[0]
        })
    }

    /// Hidden width.
    pub fn hidden_width(&self) -> usize {
        self.layers.last().map_or(0, |l| l.d_hidden)
    }

    /// Parameters applied to each step's input (`W_x`, `b_x` of every gate and layer) and
    /// to the previous hidden state (`W_h`, `b_h`): a window of `m` steps reads the first
    /// once and the second `m − 1` times (the forward pass skips the zero initial state).
    pub fn parameter_split(&self) -> (usize, usize) {
        let linear = |l: &burn::nn::Linear| {
            l.weight.shape().num_elements()
                + l.bias.as_ref().map_or(0, |b| b.shape().num_elements())
        };
        let mut split = (0, 0);
        for layer in &self.layers {
            let gates = [
                Some(&layer.input_gate),
                layer.forget_gate.as_ref(),
                Some(&layer.output_gate),
                Some(&layer.cell_gate),
            ];
            for g in gates.into_iter().flatten() {
                split.0 += linear(&g.input_transform);
                split.1 += linear(&g.hidden_transform);
            }
        }
        split
    }

    /// `x`: `[B, T, d_input]`. Returns the last layer's hidden sequence `[B, T, H]` and its
    /// final hidden state `[B, H]` (the encoding of the whole history).
    pub fn forward(&self, x: Tensor<3>) -> crate::Result<(Tensor<3>, Tensor<2>)> {
        check_shape("LSTM input", &[ANY, ANY, self.input_width()], &x.dims())?;
        if x.dims()[1] == 0 {
            return Err(NnError::Config(
                "an LSTM needs at least one time step".into(),
            ));
        }
        let mut h = x;
        let mut last = None;
        for layer in &self.layers {
            let (seq, state) = layer_forward(layer, h);
            h = seq;
            last = Some(state);
        }
        let last = last.expect("an encoder has at least one layer");
        Ok((h, last))
    }
}

/// One layer over `x` `[B, T, D]` from the zero state: `(hidden sequence [B, T, H], last
/// hidden state [B, H])`, as [`Lstm::forward`] computes them, with changes of
/// arrangement only:
/// - each gate's input projection `W_x x + b_x` is one GEMM over all `T` steps (burn
///   multiplies step by step, reading the input weights `T` times);
/// - at step 0 the hidden state is zero, so `W_h h + b_h` is just `b_h` (burn multiplies
///   the zeros);
/// - on flex, the steps after the projections are one operation
///   ([`recurrence::hidden_sequence`]); elsewhere they are tensor operations.
///
/// A layer configured otherwise than [`LstmEncoderConfig`] makes them (reversed, time
/// first, clipped, coupled gates) goes through burn's own forward.
fn layer_forward(layer: &Lstm, x: Tensor<3>) -> (Tensor<3>, Tensor<2>) {
    let forget = match &layer.forget_gate {
        Some(f) if layer.batch_first && !layer.reverse && layer.clip.is_none() => f,
        _ => {
            let (seq, state) = layer.forward(x, None);
            return (seq, state.hidden);
        }
    };
    let [b, t, d] = x.dims();
    let fused = recurrence::fused_for(layer, &x);
    let width = layer.d_hidden;
    let flat = x.reshape([b * t, d]);
    let gates = [
        &layer.input_gate,
        forget,
        &layer.output_gate,
        &layer.cell_gate,
    ];
    let projected = gates.map(|g| {
        g.input_transform
            .forward(flat.clone())
            .reshape([b, t, width])
    });
    if fused {
        let weights = gates.map(|g| g.hidden_transform.weight.val());
        let biases = gates.map(|g| {
            g.hidden_transform
                .bias
                .as_ref()
                .expect("fused_for checks the hidden biases")
                .val()
        });
        let sequence = recurrence::hidden_sequence(projected, weights, biases);
        let last = sequence
            .clone()
            .slice([0..b, t - 1..t, 0..width])
            .reshape([b, width]);
        return (sequence, last);
    }
    // `W_h h + b_h` of gate `g`; `None` for the zero state.
    let hidden_term = |g: &GateController, h: Option<&Tensor<2>>| match h {
        Some(h) => Some(g.hidden_transform.forward(h.clone())),
        None => g
            .hidden_transform
            .bias
            .as_ref()
            .map(|bias| bias.val().unsqueeze_dim::<2>(0)),
    };
    let mut cell: Option<Tensor<2>> = None;
    let mut hidden: Option<Tensor<2>> = None;
    let mut sequence = Vec::with_capacity(t);
    for step in 0..t {
        let [i, f, o, c] = std::array::from_fn(|k| {
            let x_term = projected[k]
                .clone()
                .slice([0..b, step..step + 1, 0..width])
                .reshape([b, width]);
            match hidden_term(gates[k], hidden.as_ref()) {
                Some(h_term) => x_term + h_term,
                None => x_term,
            }
        });
        let i = layer.gate_activation.forward(i);
        let f = layer.gate_activation.forward(f);
        let o = layer.gate_activation.forward(o);
        let candidate = layer.cell_activation.forward(c);
        let c = match cell {
            Some(previous) => f * previous + i * candidate,
            None => i * candidate,
        };
        let h = o * layer.hidden_activation.forward(c.clone());
        sequence.push(h.clone());
        cell = Some(c);
        hidden = Some(h);
    }
    let last = hidden.expect("at least one step (checked by the caller)");
    (Tensor::stack(sequence, 1), last)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::cpu_autodiff;
    use burn::tensor::Distribution;

    #[test]
    fn two_layers_encode_a_sequence() {
        let device = cpu_autodiff();
        let enc = LstmEncoderConfig::new(5, 8).init(&device).unwrap();
        assert_eq!(enc.layers.len(), 2);
        assert_eq!((enc.input_width(), enc.hidden_width()), (5, 8));
        // Per layer and gate: W_x, b_x on the input side; W_h, b_h on the hidden side.
        assert_eq!(
            enc.parameter_split(),
            (4 * (5 * 8 + 8) + 4 * (8 * 8 + 8), 2 * 4 * (8 * 8 + 8))
        );
        let x = Tensor::<3>::random([3, 7, 5], Distribution::Normal(0.0, 1.0), &device);
        let (seq, last) = enc.forward(x).unwrap();
        assert_eq!(seq.dims(), [3, 7, 8]);
        assert_eq!(last.dims(), [3, 8]);
        // The final state is the last step of the sequence.
        let tail = seq.slice([0..3, 6..7, 0..8]).reshape([3, 8]);
        tail.into_data()
            .assert_approx_eq::<f32>(&last.into_data(), Default::default());
        assert!(enc.forward(Tensor::<3>::zeros([3, 7, 4], &device)).is_err());
        assert!(LstmEncoderConfig::new(5, 8)
            .with_layers(0)
            .init(&device)
            .is_err());
    }

    /// weft's arrangement of the layer equals burn's `Lstm::forward` (the reference):
    /// the hidden sequence, the last state, and the gradients of the input and of an
    /// input, a hidden and a bias parameter of every gate.
    #[test]
    fn the_layer_equals_burns_lstm_values_and_gradients() {
        let device = cpu_autodiff();
        device.seed(7);
        let enc = LstmEncoderConfig::new(6, 5).init(&device).unwrap();
        let layer = &enc.layers[0];
        let x =
            Tensor::<3>::random([4, 5, 6], Distribution::Normal(0.0, 1.0), &device).require_grad();
        let (seq, last) = layer_forward(layer, x.clone());
        let (ref_seq, ref_state) = layer.forward(x.clone(), None);
        seq.clone()
            .into_data()
            .assert_approx_eq::<f32>(&ref_seq.clone().into_data(), Default::default());
        last.clone()
            .into_data()
            .assert_approx_eq::<f32>(&ref_state.hidden.clone().into_data(), Default::default());

        // A loss touching every step: gradients through both arrangements.
        let weights = Tensor::<3>::random([4, 5, 5], Distribution::Normal(0.0, 1.0), &device);
        let loss = (seq * weights.clone()).sum() + last.powi_scalar(2).sum();
        let ref_loss = (ref_seq * weights).sum() + ref_state.hidden.powi_scalar(2).sum();
        let (grads, ref_grads) = (loss.backward(), ref_loss.backward());
        let same = |a: Option<Tensor<2>>, b: Option<Tensor<2>>, what: &str| {
            let (a, b) = (a.expect(what), b.expect(what));
            a.into_data()
                .assert_approx_eq::<f32>(&b.into_data(), Default::default());
        };
        let gx = x.grad(&grads).expect("input gradient");
        gx.into_data().assert_approx_eq::<f32>(
            &x.grad(&ref_grads).expect("input gradient").into_data(),
            Default::default(),
        );
        let gates = [
            &layer.input_gate,
            layer.forget_gate.as_ref().unwrap(),
            &layer.output_gate,
            &layer.cell_gate,
        ];
        for g in gates {
            let wx = g.input_transform.weight.val();
            same(wx.grad(&grads), wx.grad(&ref_grads), "input weight");
            let wh = g.hidden_transform.weight.val();
            same(wh.grad(&grads), wh.grad(&ref_grads), "hidden weight");
            let bh = g.hidden_transform.bias.as_ref().unwrap().val();
            let (a, b) = (bh.grad(&grads).unwrap(), bh.grad(&ref_grads).unwrap());
            a.into_data()
                .assert_approx_eq::<f32>(&b.into_data(), Default::default());
        }
    }
}
