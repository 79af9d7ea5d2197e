//! Stacked LSTM encoders: the temporal encoders of seed 000 (§3.2, supplement §1): E^t1 over
//! the pose history (two layers, 128 channels) and E^t2 over body-vertex velocities (two
//! layers). burn 0.22 has a single-layer [`Lstm`]; this stacks them, each layer reading the
//! previous one's hidden sequence. Kaiming-initialised ([`crate::init::kaiming`]).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Lstm, LstmConfig};
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
            let (seq, state) = layer.forward(h, None);
            h = seq;
            last = Some(state.hidden);
        }
        let last = last.expect("an encoder has at least one layer");
        Ok((h, last))
    }
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
}
