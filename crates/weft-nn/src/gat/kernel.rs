//! The fused CSR kernels of GAT attention on plain slices: forward (scores, per-destination
//! softmax, weighted aggregation in one pass) and the hand-written backward.
//!
//! Notation (seed 001 eq. 3.2 and 3.4, seed 000 eq. 4), per head `h` with `F` channels:
//! `z_j = W v_j` (computed outside, `z` is `[N, H·F]` row-major),
//! `s_i = a_dst·z_i`, `t_j = a_src·z_j` (the two halves of `aᵀ[z_i ‖ z_j]`),
//! `u_ij = s_i + t_j`, `e_ij = LeakyReLU(u_ij)`,
//! `α_ij = exp(e_ij − m_i) / Σ_k exp(e_ik − m_i)` with `m_i = max_k e_ik` (numerically stable),
//! `out_i = Σ_j α_ij z_j`.
//!
//! Backward, for `G = ∂L/∂out`:
//! `∂L/∂α_ij = G_i·z_j`; softmax gives `∂L/∂e_ij = α_ij (G_i·z_j − G_i·out_i)` since
//! `Σ_k α_ik G_i·z_k = G_i·out_i`; `∂L/∂u_ij = ∂L/∂e_ij · (u_ij > 0 ? 1 : slope)`;
//! `∂L/∂s_i = Σ_j ∂L/∂u_ij`, `∂L/∂t_j = Σ_i ∂L/∂u_ij`;
//! `∂L/∂z_j = Σ_i α_ij G_i + (∂L/∂s_j) a_dst + (∂L/∂t_j) a_src`;
//! `∂L/∂a_dst = Σ_i (∂L/∂s_i) z_i`, `∂L/∂a_src = Σ_j (∂L/∂t_j) z_j`.
//!
//! Parallelism: nodes are cut into fixed blocks of [`BLOCK`] rows, independent of the
//! thread count, and every block writes only its own rows; the sums over destinations
//! needed by the sources run over the transpose adjacency, and the parameter gradients are
//! per-block partial sums added in block order. So the result is bit-identical on any
//! number of threads.

use rayon::prelude::*;

use crate::adjacency::Adjacency;
use crate::real::{axpy, dot, simd, Real};

/// Rows per parallel block.
pub(crate) const BLOCK: usize = 64;

/// Dimensions of one attention call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Dims {
    /// Heads `H`.
    pub heads: usize,
    /// Channels per head `F`.
    pub channels: usize,
}

impl Dims {
    pub(crate) fn width(self) -> usize {
        self.heads * self.channels
    }
}

/// What the forward pass keeps for the backward pass.
#[derive(Clone, Debug)]
pub(crate) struct Cache<T> {
    /// `α`, `[entries, H]`.
    pub alpha: Vec<T>,
    /// `s_i = a_dst·z_i`, `[N, H]`.
    pub s_dst: Vec<T>,
    /// `t_j = a_src·z_j`, `[N, H]`.
    pub s_src: Vec<T>,
}

/// LeakyReLU without a data-dependent branch (the sign of a logit is a coin flip, so a
/// branch mispredicts half the time).
#[inline(always)]
pub(crate) fn leaky<T: Real>(u: T, slope: T) -> T {
    u * leaky_slope(u, slope)
}

/// The derivative of LeakyReLU at `u`: 1 above zero, `slope` below.
#[inline(always)]
pub(crate) fn leaky_slope<T: Real>(u: T, slope: T) -> T {
    // Exactly 1 or exactly `slope`: `p·1 + (1 − p)·slope` with `p ∈ {0, 1}`.
    let positive = T::from_bool(u > T::ZERO);
    positive + (T::ONE - positive) * slope
}

/// Splits `data` (rows of `row_len` over `n` rows) into the mutable slices of the row
/// blocks `[b·BLOCK, min((b+1)·BLOCK, n))`, where the rows of block `b` start at
/// `starts[b]` (in units of `row_len`-element rows when `starts` is `None`).
pub(crate) fn split_blocks<'a, T>(mut data: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(bounds.len().saturating_sub(1));
    for w in bounds.windows(2) {
        let (head, tail) = data.split_at_mut(w[1] - w[0]);
        out.push(head);
        data = tail;
    }
    out
}

pub(crate) fn block_count(n: usize) -> usize {
    n.div_ceil(BLOCK)
}

/// Per-node scores `s = z·a` per head, `[N, H]`.
fn scores<T: Real>(z: &[T], a: &[T], n: usize, dims: Dims) -> Vec<T> {
    let (h, f, w) = (dims.heads, dims.channels, dims.width());
    let mut s = vec![T::ZERO; n * h];
    s.par_chunks_mut(BLOCK * h)
        .enumerate()
        .for_each(|(b, chunk)| {
            simd(
                #[inline(always)]
                || {
                    for (r, row) in chunk.chunks_exact_mut(h).enumerate() {
                        let i = b * BLOCK + r;
                        let zi = &z[i * w..(i + 1) * w];
                        for (k, o) in row.iter_mut().enumerate() {
                            *o = dot(&zi[k * f..(k + 1) * f], &a[k * f..(k + 1) * f]);
                        }
                    }
                },
            )
        });
    s
}

/// Fused forward: returns `out` (`[N, H·F]`) and the cache for the backward pass.
pub(crate) fn forward<T: Real>(
    adj: &Adjacency,
    z: &[T],
    a_src: &[T],
    a_dst: &[T],
    dims: Dims,
    slope: T,
) -> (Vec<T>, Cache<T>) {
    let n = adj.node_count();
    let (h, f, w) = (dims.heads, dims.channels, dims.width());
    let s_dst = scores(z, a_dst, n, dims);
    let s_src = scores(z, a_src, n, dims);
    let offsets = adj.offsets();
    let sources = adj.sources();
    let mut out = vec![T::ZERO; n * w];
    let mut alpha = vec![T::ZERO; adj.entry_count() * h];
    let blocks = block_count(n);
    let row_bounds: Vec<usize> = (0..=blocks).map(|b| (b * BLOCK).min(n) * w).collect();
    let entry_bounds: Vec<usize> = (0..=blocks)
        .map(|b| offsets[(b * BLOCK).min(n)] * h)
        .collect();
    let out_blocks = split_blocks(&mut out, &row_bounds);
    let alpha_blocks = split_blocks(&mut alpha, &entry_bounds);
    out_blocks
        .into_par_iter()
        .zip(alpha_blocks)
        .enumerate()
        .for_each(|(b, (out_b, alpha_b))| {
            simd(
                #[inline(always)]
                || {
                    let first = b * BLOCK;
                    let base = offsets[first];
                    let mut max = vec![T::NEG_INFINITY; h];
                    let mut sum = vec![T::ZERO; h];
                    for (r, out_i) in out_b.chunks_exact_mut(w).enumerate() {
                        let i = first + r;
                        let (lo, hi) = (offsets[i], offsets[i + 1]);
                        let sd = &s_dst[i * h..(i + 1) * h];
                        max.fill(T::NEG_INFINITY);
                        // Logits into the α slots, then the per-destination max.
                        for e in lo..hi {
                            let j = sources[e] as usize;
                            let ss = &s_src[j * h..(j + 1) * h];
                            let slot = &mut alpha_b[(e - base) * h..(e - base + 1) * h];
                            for k in 0..h {
                                let l = leaky(sd[k] + ss[k], slope);
                                slot[k] = l;
                                if l > max[k] {
                                    max[k] = l;
                                }
                            }
                        }
                        sum.fill(T::ZERO);
                        for e in lo..hi {
                            let slot = &mut alpha_b[(e - base) * h..(e - base + 1) * h];
                            for k in 0..h {
                                let x = (slot[k] - max[k]).exp();
                                slot[k] = x;
                                sum[k] += x;
                            }
                        }
                        for s in sum.iter_mut() {
                            *s = T::ONE / *s;
                        }
                        for e in lo..hi {
                            let j = sources[e] as usize;
                            let zj = &z[j * w..(j + 1) * w];
                            let slot = &mut alpha_b[(e - base) * h..(e - base + 1) * h];
                            for k in 0..h {
                                slot[k] = slot[k] * sum[k];
                                axpy(
                                    slot[k],
                                    &zj[k * f..(k + 1) * f],
                                    &mut out_i[k * f..(k + 1) * f],
                                );
                            }
                        }
                    }
                },
            )
        });
    (
        out,
        Cache {
            alpha,
            s_dst,
            s_src,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::Graph;

    /// Plain sequential GAT on the same adjacency, for the kernel alone.
    fn naive(adj: &Adjacency, z: &[f64], a_src: &[f64], a_dst: &[f64], d: Dims) -> Vec<f64> {
        let (h, f, w) = (d.heads, d.channels, d.width());
        let mut out = vec![0.0; adj.node_count() * w];
        for i in 0..adj.node_count() {
            for k in 0..h {
                let score = |v: usize, a: &[f64]| {
                    (0..f)
                        .map(|c| z[v * w + k * f + c] * a[k * f + c])
                        .sum::<f64>()
                };
                let logits: Vec<f64> = adj
                    .incoming(i)
                    .iter()
                    .map(|&j| {
                        let u = score(i, a_dst) + score(j as usize, a_src);
                        if u > 0.0 {
                            u
                        } else {
                            0.2 * u
                        }
                    })
                    .collect();
                let total: f64 = logits.iter().map(|l| l.exp()).sum();
                for (&j, l) in adj.incoming(i).iter().zip(&logits) {
                    for c in 0..f {
                        out[i * w + k * f + c] += l.exp() / total * z[j as usize * w + k * f + c];
                    }
                }
            }
        }
        out
    }

    #[test]
    fn forward_matches_naive_sums() {
        let g = Graph::from_edges(70, &(0..69).map(|i| [i, i + 1]).collect::<Vec<_>>());
        let adj = Adjacency::from_graph(&g);
        let d = Dims {
            heads: 2,
            channels: 3,
        };
        let z: Vec<f64> = (0..70 * 6)
            .map(|i| ((i * 37 % 11) as f64 - 5.0) / 3.0)
            .collect();
        let a_src = [0.3, -0.2, 0.5, 0.1, 0.7, -0.4];
        let a_dst = [-0.6, 0.2, 0.1, 0.9, -0.3, 0.2];
        let (out, cache) = forward(&adj, &z, &a_src, &a_dst, d, 0.2);
        let want = naive(&adj, &z, &a_src, &a_dst, d);
        for (a, b) in out.iter().zip(&want) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
        // α sums to one per destination and head.
        for i in 0..70 {
            for k in 0..2 {
                let s: f64 = (adj.offsets()[i]..adj.offsets()[i + 1])
                    .map(|e| cache.alpha[e * 2 + k])
                    .sum();
                assert!((s - 1.0).abs() < 1e-12);
            }
        }
    }
}
