//! Block-sparse symmetric matrices with 3×3 blocks (one block per vertex pair), the
//! shape of every Hessian here.
//!
//! The sparsity pattern is fixed by the energies' stencils (faces, hinges, the diagonal)
//! and built once per garment; Newton iterations only zero the values and scatter
//! per-element dense blocks into them. Both triangles of the symmetric matrix are stored
//! so that the product `H v` (what conjugate gradients needs) is one pass over the rows,
//! and the diagonal blocks (a block-Jacobi preconditioner) are one lookup per row.

use nalgebra::{Matrix3, SMatrix, Vector3};
use rayon::prelude::*;

use crate::error::{check_len, SimError};

/// Collects the vertex sets of elements (stencils) and builds a [`BlockCsr`] whose
/// pattern holds every pair of vertices that share an element, plus the diagonal.
#[derive(Clone, Debug)]
pub struct PatternBuilder {
    rows: Vec<Vec<u32>>,
}

impl PatternBuilder {
    /// An empty pattern over `n` vertices (the diagonal is always included).
    pub fn new(n: usize) -> Self {
        PatternBuilder {
            rows: (0..n as u32).map(|i| vec![i]).collect(),
        }
    }

    /// Couples every pair of vertices in `stencil`. Out-of-range vertices are ignored
    /// (energies validate their indices when they are built).
    pub fn add(&mut self, stencil: &[u32]) {
        let n = self.rows.len();
        for &a in stencil {
            if (a as usize) >= n {
                continue;
            }
            for &b in stencil {
                if (b as usize) < n && a != b {
                    self.rows[a as usize].push(b);
                }
            }
        }
    }

    /// The matrix with this pattern and all values zero.
    pub fn build(self) -> BlockCsr {
        let mut row_offsets = Vec::with_capacity(self.rows.len() + 1);
        row_offsets.push(0);
        let mut cols = Vec::new();
        for mut r in self.rows {
            r.sort_unstable();
            r.dedup();
            cols.extend_from_slice(&r);
            row_offsets.push(cols.len());
        }
        let values = vec![Matrix3::zeros(); cols.len()];
        BlockCsr {
            row_offsets,
            cols,
            values,
        }
    }
}

/// Storage slots of an element's `K × K` blocks (see [`BlockCsr::element_slots`]).
pub type ElementSlots<const K: usize> = [[usize; K]; K];

/// A square block-sparse matrix of `n × n` blocks of size 3×3 (compressed rows).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockCsr {
    /// `row_offsets[i]..row_offsets[i + 1]` indexes `cols` and `values` for block row `i`.
    row_offsets: Vec<usize>,
    /// Block column of each stored block, ascending within a row.
    cols: Vec<u32>,
    /// The blocks.
    values: Vec<Matrix3<f64>>,
}

impl BlockCsr {
    /// Number of block rows (vertices).
    pub fn block_rows(&self) -> usize {
        self.row_offsets.len() - 1
    }

    /// Number of stored blocks.
    pub fn stored_blocks(&self) -> usize {
        self.cols.len()
    }

    /// Sets every stored value to zero, keeping the pattern.
    pub fn set_zero(&mut self) {
        self.values.iter_mut().for_each(|b| *b = Matrix3::zeros());
    }

    fn position(&self, row: usize, col: usize) -> Option<usize> {
        let start = *self.row_offsets.get(row)?;
        let end = *self.row_offsets.get(row + 1)?;
        let k = self.cols[start..end].binary_search(&(col as u32)).ok()?;
        Some(start + k)
    }

    /// The stored block `(row, col)`, `None` when it is outside the pattern.
    pub fn block(&self, row: usize, col: usize) -> Option<&Matrix3<f64>> {
        self.position(row, col).map(|k| &self.values[k])
    }

    /// Adds `m` to block `(row, col)`.
    pub fn add_block(&mut self, row: usize, col: usize, m: &Matrix3<f64>) -> Result<(), SimError> {
        let k = self
            .position(row, col)
            .ok_or(SimError::NotInPattern { row, col })?;
        self.values[k] += m;
        Ok(())
    }

    /// Adds a dense element matrix (`3k × 3k`, `k = verts.len()`, vertex-major: the
    /// coordinates of `verts[0]` first) times `scale` into the blocks of `verts`.
    pub fn add_element<const R: usize>(
        &mut self,
        verts: &[u32],
        m: &SMatrix<f64, R, R>,
        scale: f64,
    ) -> Result<(), SimError> {
        if 3 * verts.len() != R {
            return Err(SimError::InvalidParameter {
                what: format!("element matrix of size {R} for {} vertices", verts.len()),
                value: R as f64,
                expected: "expected 3 rows per vertex",
            });
        }
        for (a, &va) in verts.iter().enumerate() {
            for (b, &vb) in verts.iter().enumerate() {
                let block: Matrix3<f64> = m.fixed_view::<3, 3>(3 * a, 3 * b).into_owned() * scale;
                self.add_block(va as usize, vb as usize, &block)?;
            }
        }
        Ok(())
    }

    /// The storage slots of the blocks `(verts[a], verts[b])` of an element, row-major
    /// over `(a, b)`: looked up (binary search) where the element matrix is computed,
    /// in parallel, so the serial scatter of [`BlockCsr::add_element_at`] only adds.
    pub fn element_slots<const K: usize>(
        &self,
        verts: &[u32; K],
    ) -> Result<[[usize; K]; K], SimError> {
        let mut out = [[0; K]; K];
        for (a, &va) in verts.iter().enumerate() {
            for (b, &vb) in verts.iter().enumerate() {
                out[a][b] =
                    self.position(va as usize, vb as usize)
                        .ok_or(SimError::NotInPattern {
                            row: va as usize,
                            col: vb as usize,
                        })?;
            }
        }
        Ok(out)
    }

    /// Adds a dense element matrix (`R = 3K`, vertex-major) times `scale` into the
    /// slots from [`BlockCsr::element_slots`] of the same matrix.
    pub fn add_element_at<const K: usize, const R: usize>(
        &mut self,
        slots: &ElementSlots<K>,
        m: &SMatrix<f64, R, R>,
        scale: f64,
    ) {
        for (a, row) in slots.iter().enumerate() {
            for (b, &k) in row.iter().enumerate() {
                let v = &mut self.values[k];
                for r in 0..3 {
                    for c in 0..3 {
                        v[(r, c)] += scale * m[(3 * a + r, 3 * b + c)];
                    }
                }
            }
        }
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[[f64; 3]], y: &mut [[f64; 3]]) -> Result<(), SimError> {
        let n = self.block_rows();
        check_len("matrix-vector input", n, x.len())?;
        check_len("matrix-vector output", n, y.len())?;
        // Rows are independent: split them over threads in chunks big enough to pay
        // for the scheduling.
        y.par_chunks_mut(1024).enumerate().for_each(|(c, ys)| {
            for (o, yi) in ys.iter_mut().enumerate() {
                let i = c * 1024 + o;
                let mut acc = Vector3::zeros();
                for k in self.row_offsets[i]..self.row_offsets[i + 1] {
                    acc += self.values[k] * Vector3::from(x[self.cols[k] as usize]);
                }
                *yi = [acc.x, acc.y, acc.z];
            }
        });
        Ok(())
    }

    /// The diagonal blocks (zero where a row stores none, which the builder never does).
    pub fn diagonal_blocks(&self) -> Vec<Matrix3<f64>> {
        (0..self.block_rows())
            .map(|i| self.block(i, i).copied().unwrap_or_else(Matrix3::zeros))
            .collect()
    }

    /// Replaces row and column `i` by those of the identity (a pinned vertex: its
    /// Newton step is then zero whenever its right-hand side is).
    pub fn pin(&mut self, i: usize) {
        if i >= self.block_rows() {
            return;
        }
        for k in self.row_offsets[i]..self.row_offsets[i + 1] {
            let j = self.cols[k] as usize;
            self.values[k] = if j == i {
                Matrix3::identity()
            } else {
                Matrix3::zeros()
            };
            if j != i {
                if let Some(t) = self.position(j, i) {
                    self.values[t] = Matrix3::zeros();
                }
            }
        }
    }

    /// Every stored scalar as `(row, col, value)` in scalar (not block) coordinates, for
    /// export to other sparse formats.
    pub fn triplets(&self) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::with_capacity(9 * self.cols.len());
        for i in 0..self.block_rows() {
            for k in self.row_offsets[i]..self.row_offsets[i + 1] {
                let j = self.cols[k] as usize;
                for r in 0..3 {
                    for c in 0..3 {
                        out.push((3 * i + r, 3 * j + c, self.values[k][(r, c)]));
                    }
                }
            }
        }
        out
    }

    /// The dense `3n × 3n` matrix (for tests and small problems).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let n = 3 * self.block_rows();
        let mut d = nalgebra::DMatrix::zeros(n, n);
        for (r, c, v) in self.triplets() {
            d[(r, c)] += v;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_holds_stencil_pairs_and_diagonal() {
        let mut b = PatternBuilder::new(5);
        b.add(&[0, 1, 2]);
        b.add(&[1, 2, 3]);
        let m = b.build();
        assert_eq!(m.block_rows(), 5);
        assert!(m.block(0, 2).is_some() && m.block(3, 1).is_some() && m.block(4, 4).is_some());
        assert!(m.block(0, 3).is_none() && m.block(4, 0).is_none());
        // 5 diagonal + 3*2 + 3*2 - 2 shared (1,2),(2,1) off-diagonal.
        assert_eq!(m.stored_blocks(), 5 + 10);
    }

    #[test]
    fn scatter_matvec_and_pin_match_dense() {
        let mut b = PatternBuilder::new(3);
        b.add(&[0, 2]);
        let mut m = b.build();
        let el =
            SMatrix::<f64, 6, 6>::from_fn(|r, c| 1.0 + (r * 6 + c) as f64 + (c * 6 + r) as f64);
        m.add_element(&[2, 0], &el, 2.0).unwrap();
        assert!(m.add_block(0, 1, &Matrix3::identity()).is_err());
        let x = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [-1.0, 0.5, 2.0]];
        let mut y = [[0.0; 3]; 3];
        m.mul_vec(&x, &mut y).unwrap();
        let d = m.to_dense();
        let xf = nalgebra::DVector::from_iterator(9, x.iter().flatten().copied());
        let yd = &d * xf;
        for i in 0..9 {
            assert!((yd[i] - y[i / 3][i % 3]).abs() < 1e-12);
        }
        // Block (2,0) of the matrix is rows 0..3, cols 3..6 of the element (vertex 2 first).
        assert_eq!(d[(6, 0)], 2.0 * el[(0, 3)]);
        m.pin(0);
        let d = m.to_dense();
        assert_eq!(d[(0, 0)], 1.0);
        assert_eq!(d[(0, 6)], 0.0);
        assert_eq!(d[(6, 0)], 0.0);
        assert_eq!(m.diagonal_blocks()[0], Matrix3::identity());
        assert!(m.mul_vec(&x[..2], &mut y).is_err());
    }
}
