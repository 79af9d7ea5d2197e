//! The hand-written backward of fused GAT attention, and its registration with burn's
//! autodiff as a custom backward step.
//!
//! The equations are in [`super::kernel`]; this pass walks the CSR twice: once over
//! destinations (softmax and LeakyReLU derivatives, `∂L/∂s_i`, the `a_dst` part of
//! `∂L/∂z_i`) and once over sources through the transpose adjacency (`Σ_i α_ij G_i`,
//! `∂L/∂t_j`, the `a_src` part). Each pass writes only its own rows, so it needs no atomics
//! and is deterministic on any number of threads.

use std::sync::Arc;

use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops};
use burn::backend::flex::FlexTensor;
use burn::backend::Flex;
use rayon::prelude::*;

use super::fused::AnyCache;
use super::kernel::{block_count, leaky_slope, split_blocks, Cache, Dims, BLOCK};
use crate::adjacency::Adjacency;
use crate::flex::{contiguous, elements, from_vec};
use crate::real::{axpy, dot, simd, Real};

/// The autodiff step of the fused operation (parents: `z`, `a_src`, `a_dst`).
#[derive(Debug)]
pub(crate) struct GatBackward;

/// What the forward pass hands to [`GatBackward`].
#[derive(Clone, Debug)]
pub(crate) struct GatState {
    pub z: FlexTensor,
    pub a_src: FlexTensor,
    pub a_dst: FlexTensor,
    pub out: FlexTensor,
    pub cache: Arc<AnyCache>,
    pub adjacency: Arc<Adjacency>,
    pub dims: Dims,
    pub negative_slope: f64,
}

impl Backward<Flex, 3> for GatBackward {
    type State = GatState;

    fn backward(self, ops: Ops<GatState, 3>, grads: &mut Gradients, _: &mut Checkpointer) {
        let [node_z, node_src, node_dst] = ops.parents;
        let grad = contiguous(grads.consume::<Flex>(&ops.node));
        let st = ops.state;
        let (gz, gs, gd) = backward_flex(&st, &grad);
        if let Some(node) = node_z {
            grads.register::<Flex>(node.id, gz);
        }
        if let Some(node) = node_src {
            grads.register::<Flex>(node.id, gs);
        }
        if let Some(node) = node_dst {
            grads.register::<Flex>(node.id, gd);
        }
    }
}

/// Runs [`backward_kernel`] on the flex tensors of a [`GatState`]; returns the gradients of
/// `z`, `a_src` and `a_dst`.
pub(crate) fn backward_flex(
    st: &GatState,
    grad: &FlexTensor,
) -> (FlexTensor, FlexTensor, FlexTensor) {
    let n = st.adjacency.node_count();
    let (h, f) = (st.dims.heads, st.dims.channels);
    fn run<T: Real>(
        st: &GatState,
        cache: &Cache<T>,
        grad: &FlexTensor,
        slope: T,
        n: usize,
        h: usize,
        f: usize,
    ) -> (FlexTensor, FlexTensor, FlexTensor) {
        let g = backward_kernel::<T>(
            &st.adjacency,
            elements(&st.z),
            elements(&st.a_src),
            elements(&st.a_dst),
            elements(&st.out),
            cache,
            elements(grad),
            st.dims,
            slope,
        );
        (
            from_vec(g.z, vec![n, h * f]),
            from_vec(g.a_src, vec![h, f]),
            from_vec(g.a_dst, vec![h, f]),
        )
    }
    match &*st.cache {
        AnyCache::F32(c) => run::<f32>(st, c, grad, st.negative_slope as f32, n, h, f),
        AnyCache::F64(c) => run::<f64>(st, c, grad, st.negative_slope, n, h, f),
    }
}

/// Gradients of one attention call.
pub(crate) struct Grads<T> {
    pub z: Vec<T>,
    pub a_src: Vec<T>,
    pub a_dst: Vec<T>,
}

/// Hand-written backward of [`forward`], for `grad = ∂L/∂out` (`[N, H·F]`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn backward_kernel<T: Real>(
    adj: &Adjacency,
    z: &[T],
    a_src: &[T],
    a_dst: &[T],
    out: &[T],
    cache: &Cache<T>,
    grad: &[T],
    dims: Dims,
    slope: T,
) -> Grads<T> {
    let n = adj.node_count();
    let (h, f, w) = (dims.heads, dims.channels, dims.width());
    let offsets = adj.offsets();
    let sources = adj.sources();
    let targets = adj.targets();
    let blocks = block_count(n);
    let mut gz = vec![T::ZERO; n * w];
    // ∂L/∂u per entry and head.
    let mut du = vec![T::ZERO; adj.entry_count() * h];

    // Pass A, over destinations: ∂L/∂u, ∂L/∂s_i, the a_dst part of ∂L/∂z_i and the
    // per-block partial sums of ∂L/∂a_dst.
    let entry_bounds: Vec<usize> = (0..=blocks)
        .map(|b| offsets[(b * BLOCK).min(n)] * h)
        .collect();
    let row_bounds: Vec<usize> = (0..=blocks).map(|b| (b * BLOCK).min(n) * w).collect();
    let partial_dst: Vec<Vec<T>> = split_blocks(&mut du, &entry_bounds)
        .into_par_iter()
        .zip(split_blocks(&mut gz, &row_bounds))
        .enumerate()
        .map(|(b, (du_b, gz_b))| {
            simd(
                #[inline(always)]
                || {
                    let first = b * BLOCK;
                    let base = offsets[first];
                    let mut g_a = vec![T::ZERO; w];
                    let mut c = vec![T::ZERO; h];
                    let mut ds = vec![T::ZERO; h];
                    for (r, gz_i) in gz_b.chunks_exact_mut(w).enumerate() {
                        let i = first + r;
                        let gi = &grad[i * w..(i + 1) * w];
                        let oi = &out[i * w..(i + 1) * w];
                        let sd = &cache.s_dst[i * h..(i + 1) * h];
                        for k in 0..h {
                            c[k] = dot(&gi[k * f..(k + 1) * f], &oi[k * f..(k + 1) * f]);
                        }
                        ds.fill(T::ZERO);
                        for e in offsets[i]..offsets[i + 1] {
                            let j = sources[e] as usize;
                            let zj = &z[j * w..(j + 1) * w];
                            let ss = &cache.s_src[j * h..(j + 1) * h];
                            let al = &cache.alpha[e * h..(e + 1) * h];
                            let slot = &mut du_b[(e - base) * h..(e - base + 1) * h];
                            for k in 0..h {
                                let da = dot(&gi[k * f..(k + 1) * f], &zj[k * f..(k + 1) * f]);
                                let de = al[k] * (da - c[k]);
                                let d = de * leaky_slope(sd[k] + ss[k], slope);
                                slot[k] = d;
                                ds[k] += d;
                            }
                        }
                        let zi = &z[i * w..(i + 1) * w];
                        for (k, &d) in ds.iter().enumerate() {
                            let r = k * f..(k + 1) * f;
                            axpy(d, &a_dst[r.clone()], &mut gz_i[r.clone()]);
                            axpy(d, &zi[r.clone()], &mut g_a[r]);
                        }
                    }
                    g_a
                },
            )
        })
        .collect();

    // Pass B, over sources (transpose adjacency): Σ_i α_ij G_i, ∂L/∂t_j and its a_src part,
    // and the partial sums of ∂L/∂a_src.
    let t_offsets = adj.transpose_offsets();
    let t_entries = adj.transpose_entries();
    let du = &du;
    let partial_src: Vec<Vec<T>> = gz
        .par_chunks_mut(BLOCK * w)
        .enumerate()
        .map(|(b, gz_b)| {
            simd(
                #[inline(always)]
                || {
                    let first = b * BLOCK;
                    let mut g_a = vec![T::ZERO; w];
                    let mut dt = vec![T::ZERO; h];
                    for (r, gz_j) in gz_b.chunks_exact_mut(w).enumerate() {
                        let j = first + r;
                        dt.fill(T::ZERO);
                        for &e in &t_entries[t_offsets[j]..t_offsets[j + 1]] {
                            let e = e as usize;
                            let i = targets[e] as usize;
                            let gi = &grad[i * w..(i + 1) * w];
                            let al = &cache.alpha[e * h..(e + 1) * h];
                            let d = &du[e * h..(e + 1) * h];
                            for k in 0..h {
                                let r = k * f..(k + 1) * f;
                                axpy(al[k], &gi[r.clone()], &mut gz_j[r]);
                                dt[k] += d[k];
                            }
                        }
                        let zj = &z[j * w..(j + 1) * w];
                        for (k, &d) in dt.iter().enumerate() {
                            let r = k * f..(k + 1) * f;
                            axpy(d, &a_src[r.clone()], &mut gz_j[r.clone()]);
                            axpy(d, &zj[r.clone()], &mut g_a[r]);
                        }
                    }
                    g_a
                },
            )
        })
        .collect();

    let reduce = |parts: Vec<Vec<T>>| {
        let mut acc = vec![T::ZERO; w];
        for p in parts {
            axpy(T::ONE, &p, &mut acc);
        }
        acc
    };
    Grads {
        z: gz,
        a_src: reduce(partial_src),
        a_dst: reduce(partial_dst),
    }
}
