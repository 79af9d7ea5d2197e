//! Structure-preserving pooling and unpooling (seed 000 §3.3, Appendix A), applied to node
//! features.
//!
//! The graph work — Algorithm 1 (keep the vertices at even hop distance from the
//! minimum-eccentricity vertex, connect across the removed ones) and Algorithm 2 (fill a
//! removed vertex with the neighbour-weighted mean of its kept neighbours) — is done once
//! per garment by weft-hierarchy. What is left for the network is cheap and has no
//! parameters: pooling selects the kept rows (its gradient scatters back into them),
//! unpooling is the sparse product with the unpooling matrix (its gradient is the transpose
//! product; [`crate::sparse`]).

use burn::tensor::Tensor;

use crate::adjacency::index_tensor;
use crate::batch::BatchLevel;
use crate::error::{check_shape, Result, ANY};
use crate::sparse::{sparse_matmul, SparseImpl};

/// Pooling to a coarser hierarchy level: `X_coarse = X_fine[kept]`.
#[derive(Clone, Copy, Debug, Default)]
pub struct StructurePool;

impl StructurePool {
    /// `x`: `[N_fine, C]` of the batch one level finer than `level`; returns
    /// `[N_coarse, C]`.
    pub fn forward(&self, x: Tensor<2>, level: &BatchLevel) -> Result<Tensor<2>> {
        check_shape(
            "structure pooling input",
            &[level.unpooling.rows(), ANY],
            &x.dims(),
        )?;
        let device = x.device();
        Ok(x.select(0, index_tensor(&level.kept, &device)))
    }
}

/// Unpooling back to the finer level: `X_fine = U X_coarse` with `U` of Algorithm 2.
#[derive(Clone, Copy, Debug, Default)]
pub struct StructureUnpool {
    /// Fused sparse kernel or generic path.
    pub implementation: SparseImpl,
}

impl StructureUnpool {
    /// `x`: `[N_coarse, C]` on `level`; returns `[N_fine, C]` on the level above.
    pub fn forward(&self, x: Tensor<2>, level: &BatchLevel) -> Result<Tensor<2>> {
        sparse_matmul(&level.unpooling, x, self.implementation)
    }
}
