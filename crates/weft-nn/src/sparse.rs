//! Constant sparse matrices times dense node features, `Y = S X`, with the backward
//! `∂L/∂X = Sᵀ G`.
//!
//! This is the unpooling of seed 000 (Algorithm 2: a fine × coarse matrix whose rows sum to
//! one, from [`weft_hierarchy::Unpooling::triplets`]) and the normalised adjacency of a GCN
//! scoring layer (SAGPool). `S` is data, not a parameter, so only `X` gets a gradient.
//!
//! On flex the product is a fused backend-extension operation (one CSR pass per row, rayon
//! over fixed row blocks, deterministic) whose backward walks the precomputed transpose; on
//! other backends it is a gather (`select`) of the source rows, a scale and a scatter-add
//! (`select_assign(Add)`) on rank-2 views, which burn differentiates itself.

use std::sync::Arc;

use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::CheckpointStrategy;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::autodiff::Autodiff;
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{backend_extension, Backend, Dispatch, Flex};
use burn::tensor::{DType, IndexingUpdateOp, Tensor, TensorData};
use rayon::prelude::*;

use crate::adjacency::index_tensor;
use crate::backend::is_flex;
use crate::error::{check_shape, NnError, Result, ANY};
use crate::flex::{contiguous, elements, from_vec};
use crate::real::{axpy, simd, Real};

/// Rows per parallel block.
const BLOCK: usize = 256;

/// One CSR matrix (row-major), values in f64.
#[derive(Clone, Debug, PartialEq)]
struct Csr {
    offsets: Vec<usize>,
    columns: Vec<u32>,
    values: Vec<f64>,
}

impl Csr {
    fn apply<T: Real>(&self, x: &[T], width: usize, rows: usize) -> Vec<T> {
        let mut y = vec![T::ZERO; rows * width];
        y.par_chunks_mut(BLOCK * width.max(1))
            .enumerate()
            .for_each(|(b, chunk)| {
                simd(
                    #[inline(always)]
                    || {
                        for (r, yi) in chunk.chunks_exact_mut(width.max(1)).enumerate() {
                            let i = b * BLOCK + r;
                            for e in self.offsets[i]..self.offsets[i + 1] {
                                let c = self.columns[e] as usize;
                                axpy(
                                    T::from_f64(self.values[e]),
                                    &x[c * width..(c + 1) * width],
                                    yi,
                                );
                            }
                        }
                    },
                )
            });
        y
    }
}

/// A constant sparse matrix `rows × cols`, stored with its transpose.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    rows: usize,
    cols: usize,
    forward: Csr,
    transpose: Csr,
    /// COO form for the generic path.
    coo_rows: Vec<u32>,
    coo_cols: Vec<u32>,
}

impl SparseMatrix {
    /// From `(row, column, value)` triplets; duplicates are summed. Errors on an index out
    /// of range or a non-finite value.
    pub fn from_triplets(
        rows: usize,
        cols: usize,
        triplets: impl IntoIterator<Item = (u32, u32, f64)>,
    ) -> Result<Self> {
        let mut entries: Vec<(u32, u32, f64)> = Vec::new();
        for (r, c, v) in triplets {
            if r as usize >= rows {
                return Err(NnError::Index {
                    what: "sparse matrix row",
                    index: r as usize,
                    len: rows,
                });
            }
            if c as usize >= cols {
                return Err(NnError::Index {
                    what: "sparse matrix column",
                    index: c as usize,
                    len: cols,
                });
            }
            if !v.is_finite() {
                return Err(NnError::Config(format!(
                    "sparse matrix entry ({r}, {c}) is not finite: {v}"
                )));
            }
            entries.push((r, c, v));
        }
        entries.sort_by_key(|&(r, c, _)| (r, c));
        let mut merged: Vec<(u32, u32, f64)> = Vec::with_capacity(entries.len());
        for (r, c, v) in entries {
            match merged.last_mut() {
                Some(last) if last.0 == r && last.1 == c => last.2 += v,
                _ => merged.push((r, c, v)),
            }
        }
        let build = |n: usize, transposed: bool| {
            let mut list: Vec<(u32, u32, f64)> = merged
                .iter()
                .map(|&(r, c, v)| if transposed { (c, r, v) } else { (r, c, v) })
                .collect();
            list.sort_by_key(|&(a, b, _)| (a, b));
            let mut offsets = vec![0usize; n + 1];
            for &(a, _, _) in &list {
                offsets[a as usize + 1] += 1;
            }
            for i in 0..n {
                offsets[i + 1] += offsets[i];
            }
            Csr {
                offsets,
                columns: list.iter().map(|t| t.1).collect(),
                values: list.iter().map(|t| t.2).collect(),
            }
        };
        let forward = build(rows, false);
        let transpose = build(cols, true);
        Ok(SparseMatrix {
            rows,
            cols,
            coo_rows: merged.iter().map(|t| t.0).collect(),
            coo_cols: merged.iter().map(|t| t.1).collect(),
            forward,
            transpose,
        })
    }

    /// The unpooling matrix of one hierarchy level (fine × coarse, Algorithm 2).
    pub fn from_unpooling(unpooling: &weft_hierarchy::Unpooling) -> Self {
        Self::from_triplets(
            unpooling.fine_count(),
            unpooling.coarse_count(),
            unpooling.triplets(),
        )
        .expect("an Unpooling's triplets are in range and finite by construction")
    }

    /// Rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Stored non-zeros.
    pub fn nnz(&self) -> usize {
        self.forward.values.len()
    }

    /// The transpose as a new matrix.
    pub fn transposed(&self) -> Self {
        SparseMatrix {
            rows: self.cols,
            cols: self.rows,
            forward: self.transpose.clone(),
            transpose: self.forward.clone(),
            coo_rows: self.coo_cols.clone(),
            coo_cols: self.coo_rows.clone(),
        }
    }

    /// Block-diagonal stack of several matrices (a batch of disjoint graphs).
    pub fn block_diagonal(blocks: &[&SparseMatrix]) -> Self {
        let (mut r0, mut c0) = (0u32, 0u32);
        let mut triplets = Vec::new();
        for b in blocks {
            for i in 0..b.rows {
                for e in b.forward.offsets[i]..b.forward.offsets[i + 1] {
                    triplets.push((
                        r0 + i as u32,
                        c0 + b.forward.columns[e],
                        b.forward.values[e],
                    ));
                }
            }
            r0 += b.rows as u32;
            c0 += b.cols as u32;
        }
        Self::from_triplets(r0 as usize, c0 as usize, triplets)
            .expect("blocks are valid, so is their diagonal stack")
    }
}

/// The backend extension: constant sparse × dense.
#[backend_extension(Flex, Autodiff)]
pub trait SparseOps: Backend {
    /// `S x` for `x` `[cols, C]`; returns `[rows, C]`.
    fn sparse_matmul(x: FloatTensor<Self>, matrix: Arc<SparseMatrix>) -> FloatTensor<Self>;
}

fn apply_flex(x: FlexTensor, csr: &Csr, rows: usize) -> FlexTensor {
    let x = contiguous(x);
    let width = x.layout().shape()[1];
    match x.dtype() {
        DType::F64 => from_vec(
            csr.apply::<f64>(elements(&x), width, rows),
            vec![rows, width],
        ),
        DType::F32 => from_vec(
            csr.apply::<f32>(elements(&x), width, rows),
            vec![rows, width],
        ),
        other => panic!("sparse product supports f32 and f64 tensors, got {other:?}"),
    }
}

impl SparseOps for Flex {
    fn sparse_matmul(x: FloatTensor<Self>, matrix: Arc<SparseMatrix>) -> FloatTensor<Self> {
        apply_flex(x, &matrix.forward, matrix.rows)
    }
}

#[derive(Debug)]
struct SparseBackward;

impl Backward<Flex, 1> for SparseBackward {
    type State = Arc<SparseMatrix>;

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _: &mut Checkpointer) {
        let [node] = ops.parents;
        let grad = grads.consume::<Flex>(&ops.node);
        if let Some(node) = node {
            let m = ops.state;
            grads.register::<Flex>(node.id, apply_flex(grad, &m.transpose, m.cols));
        }
    }
}

impl<C: CheckpointStrategy> SparseOps for Autodiff<Flex, C> {
    fn sparse_matmul(x: FloatTensor<Self>, matrix: Arc<SparseMatrix>) -> FloatTensor<Self> {
        match SparseBackward
            .prepare::<C>([x.node()])
            .compute_bound()
            .stateful()
        {
            OpsKind::Tracked(prep) => {
                let out = <Flex as SparseOps>::sparse_matmul(x.into_primitive(), matrix.clone());
                prep.finish(matrix, out)
            }
            OpsKind::UnTracked(prep) => prep.finish(<Flex as SparseOps>::sparse_matmul(
                x.into_primitive(),
                matrix,
            )),
        }
    }
}

/// Which implementation [`sparse_matmul`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SparseImpl {
    /// The fused CSR kernel on flex, the generic path elsewhere.
    #[default]
    Auto,
    /// Always gather / scale / scatter-add with burn ops.
    Reference,
}

/// `Y = S X` with `X` `[S.cols, C]`; errors when the row count of `X` is not `S.cols`.
pub fn sparse_matmul(
    matrix: &Arc<SparseMatrix>,
    x: Tensor<2>,
    implementation: SparseImpl,
) -> Result<Tensor<2>> {
    check_shape("sparse product input", &[matrix.cols, ANY], &x.dims())?;
    let dtype = x.dtype();
    if implementation == SparseImpl::Auto
        && matches!(dtype, DType::F32 | DType::F64)
        && is_flex(&x.device())
    {
        return Ok(Tensor::from_dispatch(
            <Dispatch as SparseOps>::sparse_matmul(x.into_dispatch(), matrix.clone()),
        ));
    }
    let device = x.device();
    let width = x.dims()[1];
    let nnz = matrix.coo_rows.len();
    let values: Vec<f64> = matrix.forward.values.clone();
    let weights = Tensor::<2>::from_data(TensorData::new(values, [nnz, 1]), (&device, dtype));
    let gathered = x.select(0, index_tensor(&matrix.coo_cols, &device)) * weights;
    Ok(
        Tensor::<2>::zeros([matrix.rows, width], (&device, dtype)).select_assign(
            0,
            index_tensor(&matrix.coo_rows, &device),
            gathered,
            IndexingUpdateOp::Add,
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{cpu, cpu_autodiff};
    use crate::testutil::{host, max_diff, random_graph, tensor, Rng};
    use weft_hierarchy::Hierarchy;

    fn random_matrix(rng: &mut Rng, rows: usize, cols: usize, nnz: usize) -> SparseMatrix {
        let triplets: Vec<(u32, u32, f64)> = (0..nnz)
            .map(|_| {
                (
                    rng.below(rows) as u32,
                    rng.below(cols) as u32,
                    rng.uniform(),
                )
            })
            .collect();
        SparseMatrix::from_triplets(rows, cols, triplets).unwrap()
    }

    fn product_and_grad(
        m: &Arc<SparseMatrix>,
        x: &[f64],
        r: &[f64],
        width: usize,
        implementation: SparseImpl,
        dtype: DType,
    ) -> (Vec<f64>, Vec<f64>) {
        let device = cpu_autodiff();
        let xt = tensor(x.to_vec(), [m.cols(), width], &device, dtype).require_grad();
        let y = sparse_matmul(m, xt.clone(), implementation).unwrap();
        let rt = tensor(r.to_vec(), [m.rows(), width], &device, dtype);
        let grads = (y.clone() * rt).sum().backward();
        (host(&y), host(&xt.grad(&grads).unwrap()))
    }

    #[test]
    fn fused_product_matches_reference_and_finite_differences() {
        let mut rng = Rng::new(21);
        let m = Arc::new(random_matrix(&mut rng, 40, 25, 120));
        let x = rng.values(25 * 3);
        let r = rng.values(40 * 3);
        let (yf, gf) = product_and_grad(&m, &x, &r, 3, SparseImpl::Auto, DType::F32);
        let (yr, gr) = product_and_grad(&m, &x, &r, 3, SparseImpl::Reference, DType::F32);
        assert!(max_diff(&yf, &yr) < 1e-5);
        assert!(max_diff(&gf, &gr) < 1e-5);
        // The product is linear, so the gradient is exactly Sᵀ R; check it numerically.
        let (_, g64) = product_and_grad(&m, &x, &r, 3, SparseImpl::Auto, DType::F64);
        let device = cpu();
        let loss = |x: &[f64]| -> f64 {
            let y = sparse_matmul(
                &m,
                tensor(x.to_vec(), [25, 3], &device, DType::F64),
                SparseImpl::Auto,
            )
            .unwrap();
            host(&y).iter().zip(&r).map(|(a, b)| a * b).sum()
        };
        let numeric: Vec<f64> = (0..x.len())
            .map(|k| {
                let (mut p, mut q) = (x.clone(), x.clone());
                p[k] += 1e-6;
                q[k] -= 1e-6;
                (loss(&p) - loss(&q)) / 2e-6
            })
            .collect();
        assert!(max_diff(&g64, &numeric) < 1e-7);
    }

    #[test]
    fn unpooling_matrix_reproduces_the_hierarchy_unpooling() {
        let mut rng = Rng::new(2);
        let g = random_graph(&mut rng, 50, 30);
        let h = Hierarchy::build(g, 2).unwrap();
        let u = h.levels()[1].unpooling.as_ref().unwrap();
        let m = Arc::new(SparseMatrix::from_unpooling(u));
        let coarse = rng.values(u.coarse_count() * 2);
        let want = u.apply(&coarse, 2);
        let y = sparse_matmul(
            &m,
            tensor(coarse, [u.coarse_count(), 2], &cpu(), DType::F64),
            SparseImpl::Auto,
        )
        .unwrap();
        assert!(max_diff(&host(&y), &want) < 1e-12);
        assert!(sparse_matmul(&m, Tensor::<2>::zeros([3, 2], &cpu()), SparseImpl::Auto).is_err());
        assert!(SparseMatrix::from_triplets(2, 2, [(0, 2, 1.0)]).is_err());
        assert!(SparseMatrix::from_triplets(2, 2, [(0, 1, f64::NAN)]).is_err());
    }
}
