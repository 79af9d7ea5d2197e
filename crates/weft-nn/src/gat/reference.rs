//! GAT attention with generic burn tensor ops: the reference the fused kernel is tested
//! against, and the path any non-CPU backend (wgpu, cuda) takes.
//!
//! Edge tensors are kept rank 2 (`[entries, H]` and `[entries, H·F]`): burn's gather and
//! scatter are much faster on rank-2 views than on rank 3 (ARCHITECTURE.md). The steps are
//! PyG's message / aggregate split: per-node scores, edge logits by `select`, a
//! per-destination max by `select_assign(Max)` (detached: the softmax does not depend on
//! the shift), `exp`, the per-destination sum by `select_assign(Add)`, and the weighted
//! messages scattered to their destinations.

use burn::tensor::activation::leaky_relu;
use burn::tensor::{IndexingUpdateOp, Int, Tensor};

/// Reference attention: `z` `[N, H·F]`, `a_src`/`a_dst` `[H, F]`, edge lists `sources` and
/// `targets` (with self-loops), output `[N, H·F]`. Shapes are checked by the caller.
pub fn attention(
    z: Tensor<2>,
    a_src: Tensor<2>,
    a_dst: Tensor<2>,
    sources: Tensor<1, Int>,
    targets: Tensor<1, Int>,
    negative_slope: f64,
) -> Tensor<2> {
    let [n, width] = z.dims();
    let [heads, channels] = a_src.dims();
    let entries = sources.dims()[0];
    let (device, dtype) = (z.device(), z.dtype());
    let alpha = coefficients(
        z.clone(),
        a_src,
        a_dst,
        sources.clone(),
        targets.clone(),
        negative_slope,
    );
    let messages = (z.select(0, sources).reshape([entries * heads, channels])
        * alpha.reshape([entries * heads, 1]))
    .reshape([entries, width]);
    Tensor::<2>::zeros([n, width], (&device, dtype)).select_assign(
        0,
        targets,
        messages,
        IndexingUpdateOp::Add,
    )
}

/// The attention coefficients `α` `[entries, H]` of the edges `sources[e] → targets[e]`:
/// the softmax over each destination's entries. Same arguments as [`attention`].
pub fn coefficients(
    z: Tensor<2>,
    a_src: Tensor<2>,
    a_dst: Tensor<2>,
    sources: Tensor<1, Int>,
    targets: Tensor<1, Int>,
    negative_slope: f64,
) -> Tensor<2> {
    let [n, width] = z.dims();
    let [heads, channels] = a_src.dims();
    // Per-node scores s = z·a per head: [N, H].
    let score = |a: Tensor<2>| {
        (z.clone() * a.reshape([1, width]))
            .reshape([n * heads, channels])
            .sum_dim(1)
            .reshape([n, heads])
    };
    let s_dst = score(a_dst);
    let s_src = score(a_src);
    let logits = leaky_relu(
        s_dst.select(0, targets.clone()) + s_src.select(0, sources),
        negative_slope,
    );
    let device = z.device();
    let dtype = z.dtype();
    let max = Tensor::<2>::full([n, heads], f32::MIN, (&device, dtype)).select_assign(
        0,
        targets.clone(),
        logits.clone().detach(),
        IndexingUpdateOp::Max,
    );
    let weights = (logits - max.select(0, targets.clone()).detach()).exp();
    let total = Tensor::<2>::zeros([n, heads], (&device, dtype)).select_assign(
        0,
        targets.clone(),
        weights.clone(),
        IndexingUpdateOp::Add,
    );
    weights / total.select(0, targets)
}
