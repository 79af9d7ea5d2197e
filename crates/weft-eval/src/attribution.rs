//! Aumann–Shapley attribution (seed 000 §4.1, eq. 9): how much each input feature of the
//! garment graph contributes to one output of the network.
//!
//! For an output `f_i` (a scalar made from the position of vertex `i`) and the graph
//! features `X` (N × F), the attribution is the path integral of the gradient along the
//! straight line from a baseline `X₀` to `X`:
//!
//! ```text
//! R_i = (X − X₀) ⊙ ∫₀¹ ∂f_i(X₀ + α (X − X₀)) / ∂X dα
//!     ≈ (X − X₀) ⊙ Σ_k  w_k/2 · ∂f_i(X₀ + α_k (X − X₀)) / ∂X,   α_k = (1 + ξ_k)/2,
//! ```
//!
//! with the `N_s`-point Gauss–Legendre rule (`w_k/2 = 1 / ((1 − ξ_k²) P'_{N_s}(ξ_k)²)`,
//! [`crate::quadrature`]). The paper's baseline is `X₀ = 0` and `N_s = 50`. `R_i` has the
//! shape of `X`; its entries sum to `f_i(X) − f_i(X₀)` up to the quadrature error
//! (completeness), which [`Attribution::completeness_gap`] reports so a caller can see
//! whether `N_s` was enough.
//!
//! The network is any function from a tracked `[N, F]` tensor to a one-element tensor on
//! a burn autodiff device; gradients come from burn's reverse mode, one backward pass per
//! quadrature node.

use burn::tensor::{Tensor, TensorData};
use weft_nn::burn;

use crate::error::EvalError;
use crate::quadrature::GaussLegendre;

/// The paper's number of quadrature nodes.
pub const DEFAULT_SAMPLES: usize = 50;

/// The attribution of one scalar output to every entry of an `[rows, cols]` input.
#[derive(Clone, Debug, PartialEq)]
pub struct Attribution {
    /// Row-major `[rows, cols]`, the shape of the input.
    pub values: Vec<f64>,
    /// Rows of the input (garment vertices).
    pub rows: usize,
    /// Columns of the input (features per vertex).
    pub cols: usize,
    /// `f(X)`.
    pub output: f64,
    /// `f(X₀)`.
    pub baseline_output: f64,
    /// Quadrature nodes used.
    pub samples: usize,
}

impl Attribution {
    /// `Σ R − (f(X) − f(X₀))`: zero for an exact integral; its size against
    /// `|f(X) − f(X₀)|` says whether the quadrature resolved the path.
    pub fn completeness_gap(&self) -> f64 {
        self.values.iter().sum::<f64>() - (self.output - self.baseline_output)
    }

    /// One score per row: the signed sum of the attributions in `columns` (e.g. the three
    /// normal features, as the paper's heat maps). Fails on columns outside the input.
    pub fn row_scores(&self, columns: std::ops::Range<usize>) -> Result<Vec<f64>, EvalError> {
        if columns.end > self.cols || columns.is_empty() {
            return Err(EvalError::Invalid(format!(
                "attribution columns {columns:?} outside the input's {} feature columns",
                self.cols
            )));
        }
        Ok(self
            .values
            .chunks_exact(self.cols)
            .map(|row| row[columns.clone()].iter().sum())
            .collect())
    }
}

fn host(t: &Tensor<2>) -> Result<Vec<f64>, EvalError> {
    t.to_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .map_err(|e| EvalError::Network(format!("reading a tensor: {e:?}")))
}

fn scalar(t: Tensor<1>) -> Result<f64, EvalError> {
    let dims = t.dims();
    if dims != [1] {
        return Err(EvalError::Invalid(format!(
            "the attributed output must be one value, got a tensor of shape {dims:?}"
        )));
    }
    let v = t
        .to_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .map_err(|e| EvalError::Network(format!("reading the output: {e:?}")))?;
    Ok(v[0])
}

/// Eq. 9 for the output `f` at `input` (a `[rows, cols]` tensor on an autodiff device),
/// from `baseline` (zeros when `None`), with `samples` Gauss–Legendre nodes.
///
/// `f` is called once per node on a fresh tracked tensor and must return a one-element
/// tensor; it may build any graph from its argument. Fails when the output is not one
/// value or when `f` does not depend on its input (no gradient).
pub fn attribute(
    input: &Tensor<2>,
    baseline: Option<&Tensor<2>>,
    samples: usize,
    mut f: impl FnMut(Tensor<2>) -> Result<Tensor<1>, EvalError>,
) -> Result<Attribution, EvalError> {
    let rule = GaussLegendre::new(samples)?;
    let [rows, cols] = input.dims();
    let x = input.clone().detach();
    let x0 = match baseline {
        Some(b) => {
            if b.dims() != [rows, cols] {
                return Err(EvalError::Invalid(format!(
                    "attribution baseline of shape {:?} for an input of shape {:?}",
                    b.dims(),
                    [rows, cols]
                )));
            }
            b.clone().detach()
        }
        None => x.zeros_like(),
    };
    let delta = x.clone() - x0.clone();
    let mut integral = vec![0.0f64; rows * cols];
    for (alpha, weight) in rule.unit_interval() {
        let point = (x0.clone() + delta.clone().mul_scalar(alpha))
            .detach()
            .require_grad();
        let out = f(point.clone())?;
        let grads = out.backward();
        let g = point.grad(&grads).ok_or_else(|| {
            EvalError::Invalid(
                "the attributed output does not depend on the input features (no gradient)"
                    .to_owned(),
            )
        })?;
        for (acc, gi) in integral.iter_mut().zip(host(&g)?) {
            *acc += weight * gi;
        }
    }
    let delta = host(&delta)?;
    let values = delta.iter().zip(&integral).map(|(d, g)| d * g).collect();
    let output = scalar(f(x)?)?;
    let baseline_output = scalar(f(x0)?)?;
    Ok(Attribution {
        values,
        rows,
        cols,
        output,
        baseline_output,
        samples,
    })
}

/// A `[rows, cols]` f32 tensor from row-major values on `device`.
pub fn tensor2(
    values: &[f32],
    shape: [usize; 2],
    device: &burn::tensor::Device,
) -> Result<Tensor<2>, EvalError> {
    if values.len() != shape[0] * shape[1] {
        return Err(EvalError::Count {
            what: "tensor values vs rows × cols",
            expected: shape[0] * shape[1],
            found: values.len(),
        });
    }
    Ok(Tensor::from_data(
        TensorData::new(values.to_vec(), shape),
        device,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_nn::backend::cpu_autodiff;
    use weft_nn::{Activation, MlpConfig};

    /// A small network on a graph-like input: per-row MLP, then one output row's value
    /// plus a global mean (so every row matters, as message passing would make it).
    fn model_fn(
        mlp: &weft_nn::Mlp,
        target: usize,
    ) -> impl FnMut(Tensor<2>) -> Result<Tensor<1>, EvalError> + '_ {
        move |x: Tensor<2>| {
            let h = mlp
                .forward(x)
                .map_err(|e| EvalError::Network(e.to_string()))?;
            let [n, _] = h.dims();
            let own = h.clone().slice([target..target + 1, 0..1]).reshape([1]);
            let all = h.slice([0..n, 0..1]).mean().reshape([1]);
            Ok(own + all.mul_scalar(0.5))
        }
    }

    #[test]
    fn completeness_on_a_small_network() {
        let device = weft_nn::backend::seeded(&cpu_autodiff(), 3);
        let mlp = MlpConfig {
            d_input: 4,
            widths: vec![16, 8, 1],
            activation: Activation::Tanh,
            output_activation: Activation::None,
            batch_norm: false,
            layer_norm: false,
        }
        .init(&device)
        .unwrap();
        let rows = 12;
        let values: Vec<f32> = (0..rows * 4)
            .map(|k| ((k as f32) * 0.37).sin() * 1.5)
            .collect();
        let x = tensor2(&values, [rows, 4], &device).unwrap();
        let a = attribute(&x, None, DEFAULT_SAMPLES, model_fn(&mlp, 5)).unwrap();
        let change = a.output - a.baseline_output;
        assert!(
            change.abs() > 1e-3,
            "the test needs an output that changes: {change}"
        );
        // f32 network: completeness to float accuracy, far below the change itself.
        assert!(
            a.completeness_gap().abs() < 1e-4 * change.abs().max(1.0),
            "gap {} for a change of {change}",
            a.completeness_gap()
        );
        // Too few nodes leave a visible gap on the same nonlinear path: the rule is doing
        // the work.
        let coarse = attribute(&x, None, 1, model_fn(&mlp, 5)).unwrap();
        assert!(coarse.completeness_gap().abs() > a.completeness_gap().abs());
        // Row scores over all columns carry the whole attribution.
        let scores = a.row_scores(0..4).unwrap();
        assert_eq!(scores.len(), rows);
        let total: f64 = a.values.iter().sum();
        assert!((scores.iter().sum::<f64>() - total).abs() < 1e-9);
        assert!(a.row_scores(2..5).is_err());
    }

    #[test]
    fn linear_function_is_attributed_exactly_with_any_baseline() {
        // f(X) = Σ c ⊙ X: R = c ⊙ (X − X₀) for every rule.
        let device = cpu_autodiff();
        let c: Vec<f32> = (0..6).map(|k| k as f32 - 2.5).collect();
        let ct = tensor2(&c, [3, 2], &device).unwrap();
        let x = tensor2(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], [3, 2], &device).unwrap();
        let b = tensor2(&[0.5; 6], [3, 2], &device).unwrap();
        let a = attribute(&x, Some(&b), 3, |t| Ok((t * ct.clone()).sum())).unwrap();
        for (k, v) in a.values.iter().enumerate() {
            let want = f64::from(c[k]) * (f64::from(k as u8 + 1) - 0.5);
            assert!((v - want).abs() < 1e-5, "{k}: {v} vs {want}");
        }
        assert!(a.completeness_gap().abs() < 1e-4);
        let wrong = tensor2(&[0.0; 4], [2, 2], &device).unwrap();
        assert!(attribute(&x, Some(&wrong), 3, |t| Ok(t.sum())).is_err());
    }
}
