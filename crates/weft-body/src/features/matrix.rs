//! [`FeatureMatrix`]: a dense row-major `rows × cols` matrix of `f64`, the storage of
//! per-vertex × per-joint features (joint distances, skinning weights), with the `f32`
//! conversion at the boundary where a network consumes it.

use super::error::FeatureError;

/// A dense row-major matrix: row `i` is `data[i * cols..(i + 1) * cols]`.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureMatrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl FeatureMatrix {
    /// A matrix from a flat row-major buffer; `cols` must be positive and divide its
    /// length. Values are not checked here (see the constructors that give them meaning).
    pub fn new(data: Vec<f64>, cols: usize) -> Result<Self, FeatureError> {
        if cols == 0 || data.len() % cols != 0 {
            return Err(FeatureError::Shape {
                len: data.len(),
                cols,
            });
        }
        Ok(FeatureMatrix {
            rows: data.len() / cols,
            cols,
            data,
        })
    }

    /// A `rows × cols` matrix of zeros (`cols` > 0 is the caller's business).
    pub(crate) fn zeros(rows: usize, cols: usize) -> Self {
        FeatureMatrix {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }

    /// Number of rows (vertices or points).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns (joints).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Row `i`. Panics if `i >= rows()`, like slice indexing.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.cols..(i + 1) * self.cols]
    }

    /// Row `i`, mutable.
    pub(crate) fn row_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.data[i * self.cols..(i + 1) * self.cols]
    }

    /// Element `(i, j)`, `None` out of range.
    pub fn get(&self, i: usize, j: usize) -> Option<f64> {
        (i < self.rows && j < self.cols).then(|| self.data[i * self.cols + j])
    }

    /// The flat row-major buffer.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    /// The flat row-major buffer, mutable (the shape stays).
    pub(crate) fn as_mut_slice(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// The buffer, giving up the shape.
    pub fn into_vec(self) -> Vec<f64> {
        self.data
    }

    /// The buffer as `f32`, row-major: the network boundary (physics stays `f64`).
    pub fn to_f32(&self) -> Vec<f32> {
        self.data.iter().map(|&x| x as f32).collect()
    }
}
