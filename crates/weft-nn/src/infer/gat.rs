//! GAT blocks (with their normalisation and σ) and dense GAT modules for inference.

use rayon::prelude::*;

use super::linear::Epilogue;
use super::{host, math, matmul, Columns, Features, BLOCK};
use crate::adjacency::Adjacency;
use crate::dense::{DenseGatModule, NormedGat};
use crate::error::NnError;
use crate::gat::kernel::leaky;
use crate::real::{axpy, dot, simd};

/// A [`NormedGat`] for inference: `σ(BN(‖_k Σ_j α^k_ij z^k_j + b ‖ H x_i))`.
#[derive(Clone, Debug)]
pub struct InferGat {
    /// `[W ‖ H]`, `[d_in, K·F + S]` row-major: one product gives both streams.
    weight: Vec<f32>,
    d_input: usize,
    heads: usize,
    channels: usize,
    /// Width `S` of the self-reinforced stream (0: none).
    self_width: usize,
    mean_heads: bool,
    negative_slope: f32,
    /// `[K, F]` each.
    att_src: Vec<f32>,
    att_dst: Vec<f32>,
    /// Over the block output, aggregation then self stream.
    epilogue: Epilogue,
}

impl From<&NormedGat> for InferGat {
    fn from(block: &NormedGat) -> Self {
        let gat = &block.gat;
        let (d_input, kf) = (gat.input_width(), gat.heads * gat.channels);
        let w = host(gat.weight.val());
        let h = gat
            .self_stream
            .as_ref()
            .map_or_else(Vec::new, |s| host(s.weight.val()));
        let self_width = h.len() / d_input;
        let weight = (0..d_input)
            .flat_map(|r| {
                w[r * kf..(r + 1) * kf]
                    .iter()
                    .chain(&h[r * self_width..(r + 1) * self_width])
                    .copied()
            })
            .collect();
        let agg = gat.output_width() - self_width;
        let bias = gat.bias.as_ref().map(|b| {
            let mut b = host(b.val());
            b.resize(agg + self_width, 0.0);
            b
        });
        InferGat {
            weight,
            d_input,
            heads: gat.heads,
            channels: gat.channels,
            self_width,
            mean_heads: gat.mean_heads,
            negative_slope: gat.negative_slope as f32,
            att_src: host(gat.att_src.val()),
            att_dst: host(gat.att_dst.val()),
            epilogue: Epilogue::new(
                agg + self_width,
                bias,
                block.norm.as_ref(),
                block.activation,
            ),
        }
    }
}

impl InferGat {
    /// Input features per node.
    pub fn input_width(&self) -> usize {
        self.d_input
    }

    /// Output features per node.
    pub fn output_width(&self) -> usize {
        self.epilogue.width()
    }

    /// `x`: `[N, input_width]` on the graph of `adjacency` → `[N, output_width]`, as
    /// [`NormedGat::forward`] on the inference device.
    pub fn forward(&self, x: &Features, adjacency: &Adjacency) -> crate::Result<Features> {
        x.check_width("GAT block input", self.d_input)?;
        let z = self.transform(x.columns(0..x.width));
        let mut out = Features::zeros(x.rows(), self.output_width());
        self.attend(&z, adjacency, &mut out, 0)?;
        Ok(out)
    }

    /// `x [W ‖ H]`: `[N, K·F + S]`.
    fn transform(&self, x: Columns<'_>) -> Features {
        matmul(
            x,
            &self.weight,
            self.heads * self.channels + self.self_width,
        )
    }

    /// Attention on `z` (from [`Self::transform`]), heads merged, the self stream, the
    /// epilogue: written into `out`'s columns from `start` on.
    ///
    /// One pass per destination over its CSR row for all heads: logits, max, `exp` (over
    /// the whole row at once, vectorised), sum, and `Σ α z_j`, as the fused kernel's
    /// forward ([`crate::gat`]) computes them, without keeping `α`.
    fn attend(
        &self,
        z: &Features,
        adjacency: &Adjacency,
        out: &mut Features,
        start: usize,
    ) -> crate::Result<()> {
        let n = z.rows();
        if n != adjacency.node_count() {
            return Err(NnError::NodeCount {
                what: "GAT attention",
                graph: adjacency.node_count(),
                features: n,
            });
        }
        let (h, f, zw, ow) = (self.heads, self.channels, z.width, out.width);
        let kf = h * f;
        let width = self.output_width();
        let agg = width - self.self_width;
        let s_dst = self.scores(z, &self.att_dst);
        let s_src = self.scores(z, &self.att_src);
        let (offsets, sources) = (adjacency.offsets(), adjacency.sources());
        let slope = self.negative_slope;
        let inv_heads = 1.0 / h as f32;
        out.data
            .par_chunks_mut(BLOCK * ow)
            .enumerate()
            .for_each(|(b, rows)| {
                simd(
                    #[inline(always)]
                    || {
                        let mut logits = Vec::new();
                        let mut acc = vec![0.0f32; kf];
                        let mut row = vec![0.0f32; width];
                        let (mut max, mut inv) = (vec![0.0f32; h], vec![0.0f32; h]);
                        for (r, out_row) in rows.chunks_exact_mut(ow).enumerate() {
                            let i = b * BLOCK + r;
                            let (lo, hi) = (offsets[i], offsets[i + 1]);
                            let sd = &s_dst[i * h..(i + 1) * h];
                            logits.clear();
                            logits.resize((hi - lo) * h, 0.0f32);
                            max.fill(f32::NEG_INFINITY);
                            for (l, &j) in logits.chunks_exact_mut(h).zip(&sources[lo..hi]) {
                                let ss = &s_src[j as usize * h..(j as usize + 1) * h];
                                for k in 0..h {
                                    l[k] = leaky(sd[k] + ss[k], slope);
                                    max[k] = max[k].max(l[k]);
                                }
                            }
                            for l in logits.chunks_exact_mut(h) {
                                for k in 0..h {
                                    l[k] -= max[k];
                                }
                            }
                            math::exp_in_place(&mut logits);
                            inv.fill(0.0);
                            for l in logits.chunks_exact(h) {
                                for k in 0..h {
                                    inv[k] += l[k];
                                }
                            }
                            for s in inv.iter_mut() {
                                *s = 1.0 / *s;
                            }
                            acc.fill(0.0);
                            for (l, &j) in logits.chunks_exact(h).zip(&sources[lo..hi]) {
                                let zj = &z.data[j as usize * zw..j as usize * zw + kf];
                                for k in 0..h {
                                    axpy(
                                        l[k] * inv[k],
                                        &zj[k * f..(k + 1) * f],
                                        &mut acc[k * f..(k + 1) * f],
                                    );
                                }
                            }
                            if self.mean_heads {
                                row[..f].fill(0.0);
                                for head in acc.chunks_exact(f) {
                                    axpy(1.0, head, &mut row[..f]);
                                }
                                row[..f].iter_mut().for_each(|v| *v *= inv_heads);
                            } else {
                                row[..kf].copy_from_slice(&acc);
                            }
                            row[agg..].copy_from_slice(&z.data[i * zw + kf..(i + 1) * zw]);
                            self.epilogue.apply(&mut row);
                            out_row[start..start + width].copy_from_slice(&row);
                        }
                    },
                )
            });
        Ok(())
    }

    /// Per-node scores `z^k · a^k` per head, `[N, K]`.
    fn scores(&self, z: &Features, a: &[f32]) -> Vec<f32> {
        let (h, f) = (self.heads, self.channels);
        let mut s = vec![0.0f32; z.rows() * h];
        s.par_chunks_mut(BLOCK * h)
            .zip(z.data.par_chunks(BLOCK * z.width))
            .for_each(|(s, z_rows)| {
                simd(
                    #[inline(always)]
                    || {
                        for (o, zi) in s.chunks_exact_mut(h).zip(z_rows.chunks_exact(z.width)) {
                            for (k, o) in o.iter_mut().enumerate() {
                                *o = dot(&zi[k * f..(k + 1) * f], &a[k * f..(k + 1) * f]);
                            }
                        }
                    },
                )
            });
        s
    }
}

/// A [`DenseGatModule`] for inference. Dense: one buffer `[N, d_in + m·d']` laid out as
/// eq. 3.6 (the input in the last `d_in` columns, block `k`'s output just left of block
/// `k − 1`'s), each block reading the columns right of its own; chained: block by block.
#[derive(Clone, Debug)]
pub struct InferDenseModule {
    blocks: Vec<InferGat>,
    dense: bool,
}

impl From<&DenseGatModule> for InferDenseModule {
    fn from(module: &DenseGatModule) -> Self {
        InferDenseModule {
            blocks: module.blocks.iter().map(InferGat::from).collect(),
            dense: module.dense,
        }
    }
}

impl InferDenseModule {
    /// Input features per node.
    pub fn input_width(&self) -> usize {
        self.blocks[0].input_width()
    }

    /// Output features per node.
    pub fn output_width(&self) -> usize {
        let last = &self.blocks[self.blocks.len() - 1];
        if self.dense {
            last.input_width() + last.output_width()
        } else {
            last.output_width()
        }
    }

    /// `x`: `[N, input_width]` → `[N, output_width]`, as [`DenseGatModule::forward`] on
    /// the inference device.
    pub fn forward(&self, x: &Features, adjacency: &Adjacency) -> crate::Result<Features> {
        x.check_width("dense GAT module input", self.input_width())?;
        if !self.dense {
            let mut h = self.blocks[0].forward(x, adjacency)?;
            for block in &self.blocks[1..] {
                h = block.forward(&h, adjacency)?;
            }
            return Ok(h);
        }
        let width = self.output_width();
        let mut buffer = Features::zeros(x.rows(), width);
        let mut start = width - x.width;
        buffer.write_columns(start, x);
        for block in &self.blocks {
            let z = block.transform(buffer.columns(start..width));
            start -= block.output_width();
            block.attend(&z, adjacency, &mut buffer, start)?;
        }
        Ok(buffer)
    }
}
