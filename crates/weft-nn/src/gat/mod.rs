//! Graph attention (Veličković et al. 2018) on CSR adjacency: the message passing of every
//! GAT block in weft (seed 000 eq. 4, seed 001 eq. 3.4–3.5).
//!
//! - [`attention`]: scores, per-destination softmax and aggregation for all heads at once,
//!   on `z = W h`. On the flex CPU backend it runs the fused kernel ([`kernel`], [`fused`])
//!   with its hand-written backward ([`backward`]); on other backends, or on request, the
//!   generic tensor path ([`reference`]).
//! - [`attention_coefficients`]: the softmax weights α alone, per edge (edge pooling's
//!   scores).
//! - [`GatBlock`]: the layer (linear transform, attention, heads concatenated or averaged,
//!   activation, the self-reinforced stream of seed 001).

mod backward;
mod block;
mod fused;
pub(crate) mod kernel;
pub mod reference;

use std::sync::Arc;

use burn::tensor::{DType, Tensor};

pub use block::{GatBlock, GatBlockConfig, HeadMerge};
pub use fused::GatOps;

use crate::adjacency::Adjacency;
use crate::backend::is_flex;
use crate::error::{check_shape, NnError, Result, ANY};

/// The LeakyReLU slope of the attention logits in GAT (Veličković et al. 2018).
pub const DEFAULT_NEGATIVE_SLOPE: f64 = 0.2;

/// Which implementation [`attention`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AttentionImpl {
    /// The fused kernel where the backend has it (flex), the reference path elsewhere.
    #[default]
    Auto,
    /// Always the generic tensor path.
    Reference,
}

/// Multi-head GAT attention on node features already transformed, `z = W h`.
///
/// - `z`: `[N, H·F]`, head `k` in columns `k·F..(k+1)·F`;
/// - `a_src`, `a_dst`: `[H, F]`, the two halves of the attention vector `a` of eq. 3.4
///   (`aᵀ[z_i ‖ z_j] = a_dst·z_i + a_src·z_j`, `i` the destination);
/// - returns `[N, H·F]`: `Σ_{j∈N(i)} α_ij z_j` per head, heads concatenated.
///
/// Errors when the shapes disagree with each other or with the adjacency.
pub fn attention(
    z: Tensor<2>,
    a_src: Tensor<2>,
    a_dst: Tensor<2>,
    adjacency: &Arc<Adjacency>,
    negative_slope: f64,
    implementation: AttentionImpl,
) -> Result<Tensor<2>> {
    let heads = check_inputs(&z, &a_src, &a_dst, adjacency)?;
    let dtype = z.dtype();
    let (a_src, a_dst) = (a_src.cast(dtype), a_dst.cast(dtype));
    let fused_dtype = matches!(dtype, DType::F32 | DType::F64);
    if implementation == AttentionImpl::Auto && fused_dtype && is_flex(&z.device()) {
        Ok(fused::dispatch(
            z,
            a_src,
            a_dst,
            adjacency.clone(),
            heads,
            negative_slope,
        ))
    } else {
        let (sources, targets) = adjacency.index_tensors(&z.device());
        Ok(reference::attention(
            z,
            a_src,
            a_dst,
            sources,
            targets,
            negative_slope,
        ))
    }
}

/// The attention coefficients `α_ij` of eq. 3.4 themselves, `[entries, H]`.
///
/// Row `e` is the edge `j → i` with `j = adjacency.sources()[e]` and
/// `i = adjacency.targets()[e]`: the adjacency's CSR order, destination-major (all edges
/// into node 0, then node 1, ...) with ascending sources, so the coefficients of node `i`'s
/// softmax are the rows `adjacency.offsets()[i]..adjacency.offsets()[i + 1]` and sum to 1.
/// Arguments as [`attention`]. Always the generic tensor path: the fused kernel never
/// materialises α, and callers that need it (edge pooling's scores) need its autodiff.
pub fn attention_coefficients(
    z: Tensor<2>,
    a_src: Tensor<2>,
    a_dst: Tensor<2>,
    adjacency: &Adjacency,
    negative_slope: f64,
) -> Result<Tensor<2>> {
    check_inputs(&z, &a_src, &a_dst, adjacency)?;
    let dtype = z.dtype();
    let (sources, targets) = adjacency.index_tensors(&z.device());
    Ok(reference::coefficients(
        z,
        a_src.cast(dtype),
        a_dst.cast(dtype),
        sources,
        targets,
        negative_slope,
    ))
}

/// Checks the shapes of an attention call against each other and the adjacency; returns
/// the head count.
fn check_inputs(
    z: &Tensor<2>,
    a_src: &Tensor<2>,
    a_dst: &Tensor<2>,
    adjacency: &Adjacency,
) -> Result<usize> {
    let [heads, channels] = a_src.dims();
    if heads == 0 || channels == 0 {
        return Err(NnError::Config(format!(
            "attention needs at least one head and one channel, got {heads}×{channels}"
        )));
    }
    check_shape("a_dst", &[heads, channels], &a_dst.dims())?;
    check_shape("z", &[ANY, heads * channels], &z.dims())?;
    let n = z.dims()[0];
    if n != adjacency.node_count() {
        return Err(NnError::NodeCount {
            what: "GAT attention",
            graph: adjacency.node_count(),
            features: n,
        });
    }
    Ok(heads)
}

#[cfg(test)]
mod tests;
