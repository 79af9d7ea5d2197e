//! Multilayer perceptrons: the garment-style and body-shape encoders of seed 000
//! (supplement §1: linear layers [256, 256, 128] and [512, 256, 128] with ReLU) and the
//! feature transformation modules of seed 001 (§3.2–3.3: tanh, with 1-D batch
//! normalisation after every layer), and the MLPs of MeshGraphNets / HOOD (seed 004:
//! Linear–ReLU–Linear–ReLU–Linear, then layer normalisation of the output, except in the
//! decoder).
//!
//! Kaiming-initialised ([`crate::init::kaiming`]).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{BatchNorm, BatchNormConfig, LayerNorm, LayerNormConfig, Linear, LinearConfig};
use burn::tensor::{Device, Tensor};

use crate::activation::Activation;
use crate::error::{check_shape, NnError, ANY};
use crate::init::kaiming;

/// Configuration of an [`Mlp`].
#[derive(Config, Debug)]
pub struct MlpConfig {
    /// Input width.
    pub d_input: usize,
    /// Output width of every layer, in order (the last is the MLP's output).
    pub widths: Vec<usize>,
    /// σ after every hidden layer.
    #[config(default = "Activation::Relu")]
    pub activation: Activation,
    /// σ after the last layer.
    #[config(default = "Activation::Relu")]
    pub output_activation: Activation,
    /// Batch normalisation (over the rows) after every layer, before σ.
    #[config(default = false)]
    pub batch_norm: bool,
    /// Layer normalisation (over the columns of each row) of the output, after the last
    /// σ: MeshGraphNets normalises every encoder and processor MLP's output this way, which
    /// keeps the residual latents of many message-passing steps at one scale.
    #[config(default = false)]
    pub layer_norm: bool,
}

/// ε of the output layer normalisation (PyTorch's and burn's default, as HOOD uses).
pub(crate) const LAYER_NORM_EPSILON: f64 = 1e-5;

/// A stack of linear layers; see the module documentation.
#[derive(Module, Debug)]
pub struct Mlp {
    /// The layers.
    pub layers: Vec<Linear>,
    /// One batch normalisation per layer, or none.
    pub norms: Vec<BatchNorm>,
    /// Layer normalisation of the output, or none. An `Option` that is `None` adds no
    /// tensor to the record, so records of MLPs without it (every checkpoint written before
    /// the field existed) load unchanged.
    pub layer_norm: Option<LayerNorm>,
    #[module(skip)]
    pub(crate) activation: Activation,
    #[module(skip)]
    pub(crate) output_activation: Activation,
}

impl MlpConfig {
    /// Builds the MLP; errors on no layers or a zero width.
    pub fn init(&self, device: &Device) -> crate::Result<Mlp> {
        if self.widths.is_empty() || self.d_input == 0 || self.widths.contains(&0) {
            return Err(NnError::Config(format!(
                "an MLP needs a positive input width and at least one positive layer width, got {} → {:?}",
                self.d_input, self.widths
            )));
        }
        let mut layers = Vec::with_capacity(self.widths.len());
        let mut norms = Vec::new();
        let mut d = self.d_input;
        for &w in &self.widths {
            layers.push(
                LinearConfig::new(d, w)
                    .with_initializer(kaiming())
                    .init(device),
            );
            if self.batch_norm {
                norms.push(BatchNormConfig::new(w).init(device));
            }
            d = w;
        }
        let layer_norm = self.layer_norm.then(|| {
            LayerNormConfig::new(d)
                .with_epsilon(LAYER_NORM_EPSILON)
                .init(device)
        });
        Ok(Mlp {
            layers,
            norms,
            layer_norm,
            activation: self.activation,
            output_activation: self.output_activation,
        })
    }
}

impl Mlp {
    /// Input width.
    pub fn input_width(&self) -> usize {
        self.layers
            .first()
            .map_or(0, |l| l.weight.shape().dims::<2>()[0])
    }

    /// Output width.
    pub fn output_width(&self) -> usize {
        self.layers
            .last()
            .map_or(0, |l| l.weight.shape().dims::<2>()[1])
    }

    /// `x`: `[B, d_input]` → `[B, widths.last]`.
    pub fn forward(&self, x: Tensor<2>) -> crate::Result<Tensor<2>> {
        check_shape("MLP input", &[ANY, self.input_width()], &x.dims())?;
        Ok(self.after_first_linear(self.layers[0].forward(x)))
    }

    /// The rest of [`Self::forward`] from the first linear layer's output `x W₀ + b₀`
    /// (`[B, widths[0]]`): for callers that form that product in parts (the graph net
    /// block's edge MLPs multiply the node rows once per node, not once per edge).
    pub(crate) fn after_first_linear(&self, first: Tensor<2>) -> Tensor<2> {
        let last = self.layers.len() - 1;
        let mut h = first;
        for (k, layer) in self.layers.iter().enumerate() {
            if k > 0 {
                h = layer.forward(h);
            }
            if let Some(norm) = self.norms.get(k) {
                h = norm.forward(h);
            }
            h = if k == last {
                self.output_activation.forward(h)
            } else {
                self.activation.forward(h)
            };
        }
        if let Some(norm) = &self.layer_norm {
            h = norm.forward(h);
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::cpu_autodiff;

    #[test]
    fn widths_batch_norm_and_errors() {
        let device = cpu_autodiff();
        let mlp = MlpConfig::new(6, vec![16, 8, 4])
            .with_batch_norm(true)
            .with_activation(Activation::Tanh)
            .with_output_activation(Activation::None)
            .init(&device)
            .unwrap();
        assert_eq!((mlp.input_width(), mlp.output_width()), (6, 4));
        let y = mlp.forward(Tensor::<2>::ones([5, 6], &device)).unwrap();
        assert_eq!(y.dims(), [5, 4]);
        assert!(mlp.forward(Tensor::<2>::ones([5, 7], &device)).is_err());
        assert!(MlpConfig::new(6, vec![]).init(&device).is_err());
        assert!(MlpConfig::new(6, vec![3, 0]).init(&device).is_err());
    }

    /// Every output row is normalised (γ = 1, β = 0 at initialisation), after the output
    /// σ: with ReLU output some values are zero before the norm and negative after it.
    #[test]
    fn layer_norm_normalises_each_output_row() {
        let device = cpu_autodiff();
        let mlp = MlpConfig::new(5, vec![12, 8])
            .with_layer_norm(true)
            .init(&device)
            .unwrap();
        assert!(mlp.layer_norm.is_some());
        let x = Tensor::<2>::random([9, 5], burn::tensor::Distribution::Default, &device);
        let y = mlp.forward(x.clone()).unwrap();
        let rows: Vec<f32> = y.to_data().convert::<f32>().try_into_vec().unwrap();
        for row in rows.chunks_exact(8) {
            let mean = row.iter().sum::<f32>() / 8.0;
            let var = row.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / 8.0;
            assert!(
                mean.abs() < 1e-5 && (var - 1.0).abs() < 1e-3,
                "{mean} {var}"
            );
        }
        // Without the norm the same layers give the un-normalised ReLU output.
        let plain = Mlp {
            layer_norm: None,
            ..mlp.clone()
        };
        let raw: Vec<f32> = plain
            .forward(x)
            .unwrap()
            .to_data()
            .convert::<f32>()
            .try_into_vec()
            .unwrap();
        assert!(raw.iter().all(|&v| v >= 0.0));
        assert!(rows.iter().any(|&v| v < 0.0));
    }

    /// The MLP as it was before `layer_norm` existed: the records of an MLP without the
    /// norm are byte for byte the old ones, so old checkpoints load.
    #[derive(Module, Debug)]
    struct OldMlp {
        layers: Vec<Linear>,
        norms: Vec<BatchNorm>,
    }

    #[test]
    fn records_without_layer_norm_are_unchanged() {
        use burn::store::ModuleRecord;
        let device = crate::backend::cpu();
        for batch_norm in [false, true] {
            let config = MlpConfig::new(4, vec![6, 3]).with_batch_norm(batch_norm);
            let mlp = config.init(&device).unwrap();
            let old = OldMlp {
                layers: mlp.layers.clone(),
                norms: mlp.norms.clone(),
            };
            let old_bytes = old.into_record().into_bytes().unwrap();
            let new_bytes = mlp.clone().into_record().into_bytes().unwrap();
            assert_eq!(&old_bytes[..], &new_bytes[..]);
            // An old record loads into a fresh MLP and reproduces the output.
            let fresh = config.init(&device).unwrap();
            let loaded = fresh
                .try_load_record(ModuleRecord::from_bytes(old_bytes.clone()).unwrap())
                .unwrap();
            let x = Tensor::<2>::ones([2, 4], &device);
            let (a, b) = (
                mlp.forward(x.clone()).unwrap().into_data(),
                loaded.forward(x).unwrap().into_data(),
            );
            assert_eq!(a, b);
            // An MLP with the norm refuses the old record (γ, β missing) instead of
            // loading it silently.
            let with_norm = config.clone().with_layer_norm(true).init(&device).unwrap();
            assert!(with_norm
                .try_load_record(ModuleRecord::from_bytes(old_bytes).unwrap())
                .is_err());
        }
    }
}
