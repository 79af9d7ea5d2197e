//! Per-dimension z-score normalisation of node features, fitted on the training rows.
//!
//! MultiResGNet's features are "normalized using the mean and variance for each dimension"
//! (seed 001 §3.3.3.2); DenseGATs does the same (decision in §1.3 of the design notes).
//! The features mix units (positions in metres, unit normals, joint distances), so without
//! it the widest-ranged columns dominate the first layer.
//!
//! The statistics are accumulated in f64 with Welford's update ([`NormalizerFit`]), so a
//! training set can stream through in chunks without holding every row, and the result
//! ([`FeatureNormalizer`]) is plain serde data to store as JSON in a run directory: the
//! same statistics must normalise the features at inference.

use burn::tensor::{Tensor, TensorData};

use crate::error::{check_shape, NnError, Result, ANY};

/// Columns whose fitted standard deviation is below this are only centred (std set to 1).
///
/// A column that is constant on the training set (a joint that never moved, a flat
/// coordinate) has std 0; flooring it at a tiny value instead would multiply any deviation
/// at inference by that tiny value's inverse. Scikit-learn's `StandardScaler` does the same.
pub const MIN_STD: f32 = 1e-6;

/// Per-column mean and standard deviation: `x' = (x − mean) / std`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FeatureNormalizer {
    /// Mean of every column.
    pub mean: Vec<f32>,
    /// Population standard deviation of every column, ≥ [`MIN_STD`] (or 1 for a column
    /// that was constant).
    pub std: Vec<f32>,
}

/// Streaming fit of a [`FeatureNormalizer`] (Welford's algorithm, f64).
#[derive(Clone, Debug)]
pub struct NormalizerFit {
    width: usize,
    rows: usize,
    mean: Vec<f64>,
    /// Sum of squared deviations from the running mean, per column.
    m2: Vec<f64>,
}

/// Rows in a flat row-major slice of `width` columns, or a shape error.
fn row_count(what: &'static str, len: usize, width: usize) -> Result<usize> {
    if len.is_multiple_of(width) {
        Ok(len / width)
    } else {
        Err(NnError::Shape {
            what,
            expected: vec![ANY, width],
            got: vec![len],
        })
    }
}

/// The first non-finite value of a row-major matrix, as an error; rows count from `first_row`.
fn check_finite(what: &'static str, rows: &[f32], width: usize, first_row: usize) -> Result<()> {
    match rows.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(k) => Err(NnError::NonFinite {
            what,
            row: first_row + k / width,
            column: k % width,
            value: rows[k],
        }),
    }
}

impl NormalizerFit {
    /// An empty fit of `width` columns; errors on width 0.
    pub fn new(width: usize) -> Result<Self> {
        if width == 0 {
            return Err(NnError::Config(
                "a feature normaliser needs at least one column".into(),
            ));
        }
        Ok(NormalizerFit {
            width,
            rows: 0,
            mean: vec![0.0; width],
            m2: vec![0.0; width],
        })
    }

    /// Rows observed so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Adds `rows` (row-major, `width` columns). Errors, leaving the fit unchanged, when the
    /// length is not a whole number of rows or a value is not finite (its row counted over
    /// everything observed).
    pub fn observe(&mut self, rows: &[f32]) -> Result<()> {
        let w = self.width;
        row_count("normaliser rows (flat)", rows.len(), w)?;
        check_finite("normaliser rows", rows, w, self.rows)?;
        for row in rows.chunks_exact(w) {
            self.rows += 1;
            let count = self.rows as f64;
            for ((&x, mean), m2) in row.iter().zip(&mut self.mean).zip(&mut self.m2) {
                let x = f64::from(x);
                let delta = x - *mean;
                *mean += delta / count;
                *m2 += delta * (x - *mean);
            }
        }
        Ok(())
    }

    /// The fitted normaliser; errors when no row was observed.
    pub fn finish(&self) -> Result<FeatureNormalizer> {
        if self.rows == 0 {
            return Err(NnError::Config(
                "a feature normaliser needs at least one training row".into(),
            ));
        }
        let count = self.rows as f64;
        let std = self
            .m2
            .iter()
            .map(|m2| {
                let s = (m2 / count).sqrt() as f32;
                if s < MIN_STD {
                    1.0
                } else {
                    s
                }
            })
            .collect();
        Ok(FeatureNormalizer {
            mean: self.mean.iter().map(|&m| m as f32).collect(),
            std,
        })
    }
}

impl FeatureNormalizer {
    /// Columns.
    pub fn width(&self) -> usize {
        self.mean.len()
    }

    /// Checks a normaliser that did not come from [`NormalizerFit`] (a loaded JSON file):
    /// equal non-zero lengths, finite means, finite standard deviations ≥ [`MIN_STD`].
    pub fn validate(&self) -> Result<()> {
        if self.mean.is_empty() || self.mean.len() != self.std.len() {
            return Err(NnError::Config(format!(
                "a feature normaliser needs as many means as deviations (at least one), got {} and {}",
                self.mean.len(),
                self.std.len()
            )));
        }
        check_finite("normaliser mean", &self.mean, self.width(), 0)?;
        check_finite("normaliser std", &self.std, self.width(), 0)?;
        match self.std.iter().position(|&s| s < MIN_STD) {
            Some(c) => Err(NnError::Config(format!(
                "normaliser std of column {c} is {}, below {MIN_STD}",
                self.std[c]
            ))),
            None => Ok(()),
        }
    }

    /// Normalises `rows` (row-major, [`Self::width`] columns) in place. Errors, leaving
    /// `rows` unchanged, on an invalid normaliser, a length that is not whole rows, or a
    /// non-finite value.
    pub fn apply(&self, rows: &mut [f32]) -> Result<()> {
        self.validate()?;
        let w = self.width();
        row_count("normalised rows (flat)", rows.len(), w)?;
        check_finite("normalised rows", rows, w, 0)?;
        for row in rows.chunks_exact_mut(w) {
            for ((x, &m), &s) in row.iter_mut().zip(&self.mean).zip(&self.std) {
                *x = (*x - m) / s;
            }
        }
        Ok(())
    }

    /// `x`: `[N, width]` → `(x − mean) / std`, on `x`'s device and dtype. Errors on an invalid
    /// normaliser or a wrong width; values are not checked for finiteness (that would read
    /// the tensor back), use [`Self::apply`] on host features for that.
    pub fn apply_tensor(&self, x: Tensor<2>) -> Result<Tensor<2>> {
        self.validate()?;
        let w = self.width();
        check_shape("normalised features", &[ANY, w], &x.dims())?;
        let row = |values: &[f32]| {
            Tensor::<2>::from_data(
                TensorData::new(values.to_vec(), [1, w]),
                (&x.device(), x.dtype()),
            )
        };
        let (mean, std) = (row(&self.mean), row(&self.std));
        Ok((x - mean) / std)
    }
}

#[cfg(test)]
mod tests {
    use burn::tensor::DType;

    use super::*;
    use crate::backend::cpu;
    use crate::testutil::{host, max_diff, tensor, Rng};

    /// `rows` rows of 3 columns with different offsets and scales.
    fn data(rng: &mut Rng, rows: usize) -> Vec<f32> {
        (0..rows)
            .flat_map(|_| {
                [
                    100.0 + 5.0 * rng.uniform() as f32,
                    0.01 * rng.uniform() as f32,
                    -3.0 + rng.uniform() as f32,
                ]
            })
            .collect()
    }

    fn column_stats(rows: &[f32], width: usize) -> Vec<(f64, f64)> {
        (0..width)
            .map(|c| {
                let col: Vec<f64> = rows
                    .iter()
                    .skip(c)
                    .step_by(width)
                    .map(|&v| v.into())
                    .collect();
                let n = col.len() as f64;
                let mean = col.iter().sum::<f64>() / n;
                let var = col.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
                (mean, var.sqrt())
            })
            .collect()
    }

    #[test]
    fn streamed_fit_matches_two_pass_statistics_and_normalises() {
        let mut rng = Rng::new(1);
        let rows = data(&mut rng, 500);
        let mut fit = NormalizerFit::new(3).unwrap();
        for chunk in rows.chunks(3 * 70) {
            fit.observe(chunk).unwrap();
        }
        assert_eq!(fit.rows(), 500);
        let norm = fit.finish().unwrap();
        for (c, (mean, std)) in column_stats(&rows, 3).into_iter().enumerate() {
            assert!((f64::from(norm.mean[c]) - mean).abs() < 1e-5 * mean.abs().max(1.0));
            assert!((f64::from(norm.std[c]) - std).abs() < 1e-5 * std);
        }
        let mut applied = rows.clone();
        norm.apply(&mut applied).unwrap();
        for (mean, std) in column_stats(&applied, 3) {
            assert!(mean.abs() < 1e-4, "{mean}");
            assert!((std - 1.0).abs() < 1e-4, "{std}");
        }
        let on_device = norm
            .apply_tensor(tensor(
                rows.iter().map(|&v| v.into()).collect(),
                [500, 3],
                &cpu(),
                DType::F32,
            ))
            .unwrap();
        let host_rows: Vec<f64> = applied.iter().map(|&v| v.into()).collect();
        assert!(max_diff(&host(&on_device), &host_rows) < 1e-5);
        let json = serde_json::to_string(&norm).unwrap();
        assert_eq!(
            serde_json::from_str::<FeatureNormalizer>(&json).unwrap(),
            norm
        );
    }

    #[test]
    fn constant_column_is_only_centred() {
        let rows = [1.0f32, 7.5, 2.0, 7.5, 3.0, 7.5];
        let mut fit = NormalizerFit::new(2).unwrap();
        fit.observe(&rows).unwrap();
        let norm = fit.finish().unwrap();
        assert_eq!((norm.mean[1], norm.std[1]), (7.5, 1.0));
        let mut applied = rows;
        norm.apply(&mut applied).unwrap();
        assert!(applied.iter().all(|v| v.is_finite()));
        assert_eq!([applied[1], applied[3], applied[5]], [0.0; 3]);
        let mut unseen = [2.0f32, 7.6];
        norm.apply(&mut unseen).unwrap();
        assert!((unseen[1] - 0.1).abs() < 1e-5);
    }

    #[test]
    fn errors_name_the_shape_and_the_offending_value() {
        let mut fit = NormalizerFit::new(3).unwrap();
        assert!(matches!(fit.observe(&[1.0; 7]), Err(NnError::Shape { .. })));
        fit.observe(&[1.0; 6]).unwrap();
        let err = fit
            .observe(&[0.0, 1.0, 2.0, 3.0, f32::NAN, 5.0])
            .unwrap_err();
        assert!(
            matches!(
                err,
                NnError::NonFinite {
                    row: 3,
                    column: 1,
                    ..
                }
            ),
            "{err}"
        );
        assert_eq!(fit.rows(), 2, "a failed observe leaves the fit unchanged");
        let norm = fit.finish().unwrap();
        let mut wrong = [0.0f32; 4];
        assert!(matches!(norm.apply(&mut wrong), Err(NnError::Shape { .. })));
        let mut inf = [0.0, 0.0, 0.0, f32::INFINITY, 0.0, 0.0];
        assert!(matches!(
            norm.apply(&mut inf),
            Err(NnError::NonFinite {
                row: 1,
                column: 0,
                ..
            })
        ));
        assert_eq!(inf[0], 0.0);
        assert!(norm
            .apply_tensor(Tensor::<2>::zeros([4, 2], &cpu()))
            .is_err());
        assert!(NormalizerFit::new(0).is_err());
        assert!(NormalizerFit::new(2).unwrap().finish().is_err());
        let bad = FeatureNormalizer {
            mean: vec![0.0, 0.0],
            std: vec![1.0, 0.0],
        };
        assert!(bad.validate().is_err());
        let short = FeatureNormalizer {
            mean: vec![0.0, 0.0],
            std: vec![1.0],
        };
        assert!(short.apply(&mut [0.0, 0.0]).is_err());
    }
}
