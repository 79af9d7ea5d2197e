//! [`SkinningWeights`]: per-vertex skinning weights `W ∈ ℝ^{N×S}` (the `weights` array
//! of an SMPL-format model, or weights transferred to a garment), kept non-negative
//! with rows summing to one, the two properties linear blend skinning relies on (seed
//! 001 eq. 2.1: a convex combination of bone transforms) and that seed 000's softmax
//! output has by construction.

use super::error::FeatureError;
use super::matrix::FeatureMatrix;

/// Skinning weights: a row per vertex, a column per joint; every entry finite and
/// non-negative, every row summing to one (up to rounding).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinningWeights {
    matrix: FeatureMatrix,
}

impl SkinningWeights {
    /// Weights from a flat row-major `N × joints` buffer.
    ///
    /// Checks that the shape fits, that every value is finite and non-negative and that
    /// no row is all zero, then divides each row by its sum, so that weights stored in
    /// `f32` (SMPL's rows sum to one only to ~1e-7) become exact convex combinations.
    pub fn new(data: Vec<f64>, joints: usize) -> Result<Self, FeatureError> {
        let matrix = FeatureMatrix::new(data, joints)?;
        for (k, &w) in matrix.as_slice().iter().enumerate() {
            if !w.is_finite() {
                return Err(FeatureError::NonFinite {
                    what: "skinning weight",
                    index: k,
                });
            }
            if w < 0.0 {
                return Err(FeatureError::NegativeWeight {
                    vertex: k / joints,
                    joint: k % joints,
                    value: w,
                });
            }
        }
        let mut w = SkinningWeights { matrix };
        w.normalize_rows()?;
        Ok(w)
    }

    /// [`SkinningWeights::new`] from a borrowed buffer (copied).
    pub fn from_slice(data: &[f64], joints: usize) -> Result<Self, FeatureError> {
        Self::new(data.to_vec(), joints)
    }

    /// [`SkinningWeights::new`] from `f32` storage (an SMPL `.npz`).
    pub fn from_f32(data: &[f32], joints: usize) -> Result<Self, FeatureError> {
        Self::new(data.iter().map(|&x| f64::from(x)).collect(), joints)
    }

    /// Wraps a matrix the caller built as non-negative; rows are renormalised.
    pub(crate) fn from_matrix(matrix: FeatureMatrix) -> Result<Self, FeatureError> {
        let mut w = SkinningWeights { matrix };
        w.normalize_rows()?;
        Ok(w)
    }

    fn normalize_rows(&mut self) -> Result<(), FeatureError> {
        for i in 0..self.matrix.rows() {
            let row = self.matrix.row_mut(i);
            let s: f64 = row.iter().sum();
            if !(s > 0.0 && s.is_finite()) {
                return Err(FeatureError::ZeroWeightRow { vertex: i });
            }
            row.iter_mut().for_each(|w| *w /= s);
        }
        Ok(())
    }

    /// Number of vertices (rows).
    pub fn vertex_count(&self) -> usize {
        self.matrix.rows()
    }

    /// Number of joints (columns).
    pub fn joint_count(&self) -> usize {
        self.matrix.cols()
    }

    /// The weights of vertex `i` (one per joint). Panics if `i` is out of range.
    pub fn row(&self, i: usize) -> &[f64] {
        self.matrix.row(i)
    }

    /// The weights as a matrix.
    pub fn as_matrix(&self) -> &FeatureMatrix {
        &self.matrix
    }

    /// The flat row-major buffer.
    pub fn as_slice(&self) -> &[f64] {
        self.matrix.as_slice()
    }

    /// The weights as `f32`, row-major (network boundary).
    pub fn to_f32(&self) -> Vec<f32> {
        self.matrix.to_f32()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_normalised_and_bad_input_named() {
        let w = SkinningWeights::new(vec![1.0, 3.0, 0.0, 2.0], 2).unwrap();
        assert_eq!(w.row(0), &[0.25, 0.75]);
        assert_eq!(w.row(1), &[0.0, 1.0]);
        assert_eq!(
            SkinningWeights::new(vec![1.0, 2.0, 3.0], 2),
            Err(FeatureError::Shape { len: 3, cols: 2 })
        );
        assert!(matches!(
            SkinningWeights::new(vec![1.0, -0.5], 2),
            Err(FeatureError::NegativeWeight {
                vertex: 0,
                joint: 1,
                ..
            })
        ));
        assert_eq!(
            SkinningWeights::new(vec![1.0, 0.0, 0.0, 0.0], 2),
            Err(FeatureError::ZeroWeightRow { vertex: 1 })
        );
        assert!(matches!(
            SkinningWeights::new(vec![f64::NAN, 1.0], 2),
            Err(FeatureError::NonFinite { index: 0, .. })
        ));
    }
}
