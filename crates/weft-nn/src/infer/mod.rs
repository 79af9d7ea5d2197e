//! Inference-only forward passes on host buffers (evaluation, animation; no autodiff):
//! the arithmetic of the layers' `forward` on the inference device, where batch
//! normalisation uses its running statistics, arranged for speed.
//!
//! Why: burn runs every step of a layer as its own pass over the activations — the bias,
//! four batch-norm operations, σ in scalar libm on one thread, and in a dense GAT module
//! a new concatenation of all earlier features per block. At DenseGATs' paper widths on
//! 10 000 vertices those passes, not the products, were most of the frame
//! (docs/benchmarks.md). Here:
//!
//! - bias and batch normalisation are one per-channel affine map, applied with σ in the
//!   pass that writes each output ([`Epilogue`]); σ is vectorised f32 ([`math`]);
//! - GAT attention handles all heads of a node in one pass over its CSR row (scores,
//!   softmax, weighted sum) and keeps no `α`; the self-reinforced stream shares the
//!   block's product (`x [W ‖ H]`);
//! - a dense module writes each block's output into its column range of one buffer and
//!   each block's product reads its input columns in place (`gemm` with a row stride).
//!
//! Training keeps the burn layers; the forms here are built from them
//! (`InferMlp::from(&mlp)`, ...) and the tests hold them equal to the layers' forward.

mod gat;
mod graph_net;
mod linear;
pub(crate) mod math;
mod multires;

use std::ops::Range;

use burn::tensor::{Device, Tensor, TensorData};

pub use gat::{InferDenseModule, InferGat};
pub use graph_net::{InferEdgeSet, InferProcessor};
pub use linear::{Epilogue, InferLinear, InferMlp};
pub use multires::{InferGlobal, InferMultiRes};

use crate::error::{check_shape, NnError, ANY};

/// Rows per parallel block of the row-wise passes.
const BLOCK: usize = 64;

/// Node features on the host: `rows × width`, row-major f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Features {
    data: Vec<f32>,
    width: usize,
}

impl Features {
    /// `rows × width` zeros.
    pub fn zeros(rows: usize, width: usize) -> Self {
        Features {
            data: vec![0.0; rows * width],
            width,
        }
    }

    /// Row-major `values` of `width` columns; errors when they are not whole rows.
    pub fn new(values: Vec<f32>, width: usize) -> crate::Result<Self> {
        if width == 0 || !values.len().is_multiple_of(width) {
            return Err(NnError::Config(format!(
                "{} values are not rows of width {width}",
                values.len()
            )));
        }
        Ok(Features {
            data: values,
            width,
        })
    }

    /// The values of a `[N, d]` tensor (any float dtype, read as f32).
    pub fn from_tensor(t: Tensor<2>) -> crate::Result<Self> {
        let [_, width] = t.dims();
        let values = t
            .into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .map_err(|e| NnError::Config(format!("features: {e:?}")))?;
        Features::new(values, width.max(1))
    }

    /// As a `[rows, width]` f32 tensor on `device`.
    pub fn into_tensor(self, device: &Device) -> Tensor<2> {
        let shape = [self.rows(), self.width];
        Tensor::from_data(TensorData::new(self.data, shape), device)
    }

    /// Rows (nodes).
    pub fn rows(&self) -> usize {
        self.data.len() / self.width
    }

    /// Columns (features per node).
    pub fn width(&self) -> usize {
        self.width
    }

    /// The values, row-major.
    pub fn values(&self) -> &[f32] {
        &self.data
    }

    /// The values, row-major.
    pub fn into_values(self) -> Vec<f32> {
        self.data
    }

    /// Checks the width against a layer's input width.
    fn check_width(&self, what: &'static str, width: usize) -> crate::Result<()> {
        check_shape(what, &[ANY, width], &[self.rows(), self.width])
    }

    /// Columns `range` of every row, in place.
    fn columns(&self, range: Range<usize>) -> Columns<'_> {
        debug_assert!(range.start <= range.end && range.end <= self.width);
        Columns {
            data: &self.data,
            stride: self.width,
            start: range.start,
            width: range.end - range.start,
        }
    }

    /// Copies `src` into the columns from `start` on.
    fn write_columns(&mut self, start: usize, src: &Features) {
        let w = src.width;
        for (dst, src) in self
            .data
            .chunks_exact_mut(self.width)
            .zip(src.data.chunks_exact(w))
        {
            dst[start..start + w].copy_from_slice(src);
        }
    }
}

/// A column range of [`Features`]: the left operand of a product that reads part of a
/// wider buffer without copying it.
#[derive(Clone, Copy, Debug)]
struct Columns<'a> {
    data: &'a [f32],
    stride: usize,
    start: usize,
    width: usize,
}

impl Columns<'_> {
    fn rows(&self) -> usize {
        self.data.len() / self.stride
    }
}

/// `x w` with `w` `[x.width, n]` row-major, into a new `[rows, n]` buffer: burn flex's own
/// GEMM (`gemm`), reading `x`'s columns through its row stride.
fn matmul(x: Columns<'_>, w: &[f32], n: usize) -> Features {
    let mut out = Features::zeros(x.rows(), n);
    let parallelism = crate::flex::gemm_parallelism(x.rows(), n, x.width);
    product(&mut out.data, x, w, n, parallelism);
    out
}

/// `dst ← x w` with `w` `[x.width, n]` and `dst` `[x.rows(), n]`, both row-major.
fn product(dst: &mut [f32], x: Columns<'_>, w: &[f32], n: usize, parallelism: gemm::Parallelism) {
    let (m, k) = (x.rows(), x.width);
    assert_eq!(w.len(), k * n, "weight of {k} × {n}");
    assert_eq!(dst.len(), m * n, "product of {m} × {n}");
    if m == 0 || n == 0 {
        return;
    }
    if k == 0 {
        dst.fill(0.0);
        return;
    }
    // SAFETY: `dst` holds `m × n` values at row stride `n` (asserted); `w` holds `k × n`
    // at row stride `n` (asserted); `x` reads rows `r < m` at `start + r·stride + c` with
    // `c < k` and `start + k ≤ stride`, inside `x.data` (`m·stride` values). `gemm`
    // writes only `dst` and, with `read_dst = false`, does not read it.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            dst.as_mut_ptr(),
            1,
            n as isize,
            false,
            x.data.as_ptr().add(x.start),
            1,
            x.stride as isize,
            w.as_ptr(),
            1,
            n as isize,
            0.0,
            1.0,
            false,
            false,
            false,
            parallelism,
        );
    }
}

/// The values of a tensor as f32, for building the inference forms.
fn host<const D: usize>(t: Tensor<D>) -> Vec<f32> {
    t.into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .expect("converted to f32 just before")
}

#[cfg(test)]
mod tests;
