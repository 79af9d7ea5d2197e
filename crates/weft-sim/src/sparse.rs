//! Block-sparse symmetric matrices with 3×3 blocks (one block per vertex pair), the
//! shape of every Hessian here.
//!
//! The sparsity pattern is fixed by the energies' stencils (faces, hinges, the diagonal)
//! and built once per garment; Newton iterations only zero the values and add
//! per-element blocks into them. Both triangles of the symmetric matrix are stored
//! so that the product `H v` (what conjugate gradients needs) is one pass over the rows,
//! and the diagonal blocks (a block-Jacobi preconditioner) are one lookup per row.
//!
//! Element energies add their blocks through an [`ElementGather`]: built once per
//! pattern, it lists for every stored block the element blocks that sum into it, so
//! assembly is a parallel pass in which each stored block is written by one thread.

use std::sync::{Arc, Mutex};

use nalgebra::{Matrix3, SMatrix};
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
            pattern: Arc::new(Pattern { row_offsets, cols }),
            values,
        }
    }
}

/// Where the blocks are stored. Shared by the clones of a matrix, so that an
/// [`ElementGather`] made for one pattern is recognised (by pointer) and reused.
#[derive(Debug, PartialEq)]
struct Pattern {
    /// `row_offsets[i]..row_offsets[i + 1]` indexes `cols` and the values of block row `i`.
    row_offsets: Vec<usize>,
    /// Block column of each stored block, ascending within a row.
    cols: Vec<u32>,
}

/// A square block-sparse matrix of `n × n` blocks of size 3×3 (compressed rows).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockCsr {
    pattern: Arc<Pattern>,
    /// The blocks, in the pattern's order.
    values: Vec<Matrix3<f64>>,
}

impl BlockCsr {
    /// Number of block rows (vertices).
    pub fn block_rows(&self) -> usize {
        self.pattern.row_offsets.len() - 1
    }

    /// Number of stored blocks.
    pub fn stored_blocks(&self) -> usize {
        self.pattern.cols.len()
    }

    /// The stored blocks of block row `row`, with their block columns (ascending).
    pub fn row(&self, row: usize) -> impl Iterator<Item = (usize, &Matrix3<f64>)> + '_ {
        let p = &self.pattern;
        let (a, b) = (p.row_offsets[row], p.row_offsets[row + 1]);
        p.cols[a..b]
            .iter()
            .map(|&j| j as usize)
            .zip(&self.values[a..b])
    }

    /// Sets every stored value to zero, keeping the pattern.
    pub fn set_zero(&mut self) {
        self.values.iter_mut().for_each(|b| *b = Matrix3::zeros());
    }

    fn position(&self, row: usize, col: usize) -> Option<usize> {
        let p = &self.pattern;
        let start = *p.row_offsets.get(row)?;
        let end = *p.row_offsets.get(row + 1)?;
        let k = p.cols[start..end].binary_search(&(col as u32)).ok()?;
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

    /// Adds `scale · block(e, a, b)` for every element block `(a, b)` of element `e` that
    /// `gather` routes here (block `(a, b)`: rows of the element's vertex `a`, columns
    /// of its vertex `b`). Parallel over the stored blocks; `gather` must have been made
    /// for this matrix's pattern ([`GatherCache::get`] makes sure of it).
    pub fn add_gathered<const K: usize>(
        &mut self,
        gather: &ElementGather<K>,
        scale: f64,
        block: impl Fn(usize, usize, usize) -> Matrix3<f64> + Sync,
    ) -> Result<(), SimError> {
        if !Arc::ptr_eq(&gather.pattern, &self.pattern) {
            return Err(SimError::InvalidParameter {
                what: "element gather".into(),
                value: gather.offsets.len() as f64 - 1.0,
                expected: "expected one made for this matrix's pattern",
            });
        }
        let (offsets, sources) = (&gather.offsets, &gather.sources);
        self.values
            .par_iter_mut()
            .with_min_len(1024)
            .enumerate()
            .for_each(|(k, v)| {
                let mut acc = Matrix3::zeros();
                for &s in &sources[offsets[k] as usize..offsets[k + 1] as usize] {
                    let (e, ab) = (s as usize / (K * K), s as usize % (K * K));
                    acc += block(e, ab / K, ab % K);
                }
                *v += acc * scale;
            });
        Ok(())
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[[f64; 3]], y: &mut [[f64; 3]]) -> Result<(), SimError> {
        let n = self.block_rows();
        check_len("matrix-vector input", n, x.len())?;
        check_len("matrix-vector output", n, y.len())?;
        // Rows are independent: split them over threads in chunks big enough to pay
        // for the scheduling.
        let (p, values) = (&*self.pattern, &self.values[..]);
        #[cfg(target_arch = "x86_64")]
        let avx2 = std::is_x86_feature_detected!("avx2");
        y.par_chunks_mut(1024).enumerate().for_each(|(c, ys)| {
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                // SAFETY: the CPU supports AVX2, checked above.
                unsafe { mul_rows_avx2(values, p, x, c * 1024, ys) };
                return;
            }
            mul_rows(values, p, x, c * 1024, ys);
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
        let p = Arc::clone(&self.pattern);
        for k in p.row_offsets[i]..p.row_offsets[i + 1] {
            let j = p.cols[k] as usize;
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
        let p = &self.pattern;
        let mut out = Vec::with_capacity(9 * p.cols.len());
        for i in 0..self.block_rows() {
            for k in p.row_offsets[i]..p.row_offsets[i + 1] {
                let j = p.cols[k] as usize;
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

/// For a fixed list of `K`-vertex elements and one matrix pattern: which element blocks
/// sum into each stored block. Building it does the binary searches once per garment;
/// assembling through it ([`BlockCsr::add_gathered`]) is then a parallel pass over the
/// stored blocks, each written by one thread (the serial scatter it replaced was a
/// third of a simulator step).
#[derive(Debug)]
pub struct ElementGather<const K: usize> {
    pattern: Arc<Pattern>,
    /// `offsets[k]..offsets[k + 1]` indexes `sources` for stored block `k`.
    offsets: Vec<u32>,
    /// `e · K² + a · K + b`: block `(a, b)` of element `e`.
    sources: Vec<u32>,
}

impl<const K: usize> ElementGather<K> {
    /// The gather of `count` elements, element `e` on vertices `verts(e)`, into the
    /// pattern of `h`. A block outside the pattern is [`SimError::NotInPattern`].
    pub fn new(
        h: &BlockCsr,
        count: usize,
        verts: impl Fn(usize) -> [u32; K],
    ) -> Result<Self, SimError> {
        if count.saturating_mul(K * K) > u32::MAX as usize {
            return Err(SimError::InvalidParameter {
                what: "element count of a Hessian gather".into(),
                value: count as f64,
                expected: "expected at most 2^32 element blocks",
            });
        }
        let mut target = Vec::with_capacity(count * K * K);
        for e in 0..count {
            let v = verts(e);
            for &va in &v {
                for &vb in &v {
                    let k = h
                        .position(va as usize, vb as usize)
                        .ok_or(SimError::NotInPattern {
                            row: va as usize,
                            col: vb as usize,
                        })?;
                    target.push(k as u32);
                }
            }
        }
        // Counting sort of the sources by their stored block.
        let mut offsets = vec![0u32; h.stored_blocks() + 1];
        for &k in &target {
            offsets[k as usize + 1] += 1;
        }
        for k in 1..offsets.len() {
            offsets[k] += offsets[k - 1];
        }
        let mut next = offsets.clone();
        let mut sources = vec![0u32; target.len()];
        for (s, &k) in target.iter().enumerate() {
            sources[next[k as usize] as usize] = s as u32;
            next[k as usize] += 1;
        }
        Ok(ElementGather {
            pattern: Arc::clone(&h.pattern),
            offsets,
            sources,
        })
    }
}

/// The [`ElementGather`] of an energy's elements for the last pattern it assembled
/// into, kept across the steps of a simulation (energies share it through their
/// `Arc`s). A cache, not part of an energy's value: a clone starts empty and
/// comparisons ignore it.
#[derive(Default)]
pub struct GatherCache<const K: usize>(Mutex<Option<Arc<ElementGather<K>>>>);

impl<const K: usize> GatherCache<K> {
    /// The gather for `h`'s pattern: the cached one, or a new one (see
    /// [`ElementGather::new`]) that replaces it.
    pub fn get(
        &self,
        h: &BlockCsr,
        count: usize,
        verts: impl Fn(usize) -> [u32; K],
    ) -> Result<Arc<ElementGather<K>>, SimError> {
        let mut cached = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(g) = cached.as_ref() {
            if Arc::ptr_eq(&g.pattern, &h.pattern) {
                return Ok(Arc::clone(g));
            }
        }
        let g = Arc::new(ElementGather::new(h, count, verts)?);
        *cached = Some(Arc::clone(&g));
        Ok(g)
    }
}

impl<const K: usize> Clone for GatherCache<K> {
    fn clone(&self) -> Self {
        GatherCache::default()
    }
}

impl<const K: usize> PartialEq for GatherCache<K> {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl<const K: usize> std::fmt::Debug for GatherCache<K> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("GatherCache")
    }
}

/// Rows `first..first + ys.len()` of `A x`: each block adds `c₀x₀ + c₁x₁ + c₂x₂` (its
/// columns times `x_j`'s coordinates, summed in that order), the order the AVX2 form
/// computes, so both give the same bits.
fn mul_rows(
    values: &[Matrix3<f64>],
    p: &Pattern,
    x: &[[f64; 3]],
    first: usize,
    ys: &mut [[f64; 3]],
) {
    for (o, yi) in ys.iter_mut().enumerate() {
        let (a, b) = (p.row_offsets[first + o], p.row_offsets[first + o + 1]);
        let mut acc = [0.0; 3];
        for (m, &j) in values[a..b].iter().zip(&p.cols[a..b]) {
            let xj = x[j as usize];
            for (r, out) in acc.iter_mut().enumerate() {
                *out += m[(r, 0)] * xj[0] + m[(r, 1)] * xj[1] + m[(r, 2)] * xj[2];
            }
        }
        *yi = acc;
    }
}

/// [`mul_rows`] with each block column in one four-lane register. Built for the baseline
/// x86-64 target, the product of a 3×3 block compiled to about thirty scalar and
/// two-lane instructions, and PCG's products were most of a simulated frame; here a block
/// is three loads, three broadcasts, three products and three sums. No fused
/// multiply-add, so the bits are [`mul_rows`]'s.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn mul_rows_avx2(
    values: &[Matrix3<f64>],
    p: &Pattern,
    x: &[[f64; 3]],
    first: usize,
    ys: &mut [[f64; 3]],
) {
    use std::arch::x86_64::*;
    for (o, yi) in ys.iter_mut().enumerate() {
        let (a, b) = (p.row_offsets[first + o], p.row_offsets[first + o + 1]);
        let mut acc = _mm256_setzero_pd();
        for (m, &j) in values[a..b].iter().zip(&p.cols[a..b]) {
            let xj = &x[j as usize];
            // A block is nine numbers, column-major. Columns 0 and 1 are read as entries
            // 0..4 and 3..7, column 2 as entries 5..9 rotated to 8, 5, 6, 7 → lanes
            // 6, 7, 8, 5: every load stays inside the block, and the fourth lane, never
            // stored, holds a neighbouring entry.
            let v = m.as_slice().as_ptr();
            // SAFETY: `v` points at nine contiguous f64; each load reads four of them.
            let (c0, c1, c2) = unsafe {
                (
                    _mm256_loadu_pd(v),
                    _mm256_loadu_pd(v.add(3)),
                    _mm256_permute4x64_pd::<0b00_11_10_01>(_mm256_loadu_pd(v.add(5))),
                )
            };
            let mut t = _mm256_mul_pd(c0, _mm256_set1_pd(xj[0]));
            t = _mm256_add_pd(t, _mm256_mul_pd(c1, _mm256_set1_pd(xj[1])));
            t = _mm256_add_pd(t, _mm256_mul_pd(c2, _mm256_set1_pd(xj[2])));
            acc = _mm256_add_pd(acc, t);
        }
        let mut out = [0.0; 4];
        // SAFETY: `out` holds four f64.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), acc) };
        *yi = [out[0], out[1], out[2]];
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

    /// Assembly through a gather equals the element-by-element dense scatter, for
    /// elements that overlap and repeat; a gather is refused by a matrix of another
    /// pattern, and the cache keeps one per pattern.
    #[test]
    fn gathered_assembly_matches_the_dense_scatter() {
        let elements: [[u32; 4]; 4] = [[0, 1, 2, 3], [2, 3, 4, 5], [5, 4, 6, 0], [0, 1, 2, 3]];
        let mut b = PatternBuilder::new(7);
        for e in &elements {
            b.add(e);
        }
        let pattern = b.build();
        let matrix = |e: usize| {
            SMatrix::<f64, 12, 12>::from_fn(|r, c| ((7 * e + 3 * r + 5 * c) % 11) as f64 - 4.5)
        };
        let mut dense = pattern.clone();
        for (e, v) in elements.iter().enumerate() {
            dense.add_element(v, &matrix(e), 0.5).unwrap();
        }
        let cache = GatherCache::<4>::default();
        let mut gathered = pattern.clone();
        let g = cache
            .get(&gathered, elements.len(), |e| elements[e])
            .unwrap();
        gathered
            .add_gathered(&g, 0.5, |e, a, bb| {
                matrix(e).fixed_view::<3, 3>(3 * a, 3 * bb).into_owned()
            })
            .unwrap();
        assert_eq!(gathered.to_dense(), dense.to_dense());
        assert!(Arc::ptr_eq(
            &g,
            &cache
                .get(&pattern, elements.len(), |e| elements[e])
                .unwrap()
        ));
        let mut other = PatternBuilder::new(7).build();
        assert!(other
            .add_gathered(&g, 1.0, |_, _, _| Matrix3::zeros())
            .is_err());
        assert!(matches!(
            cache.get(&other, elements.len(), |e| elements[e]),
            Err(SimError::NotInPattern { .. })
        ));
    }

    #[test]
    fn avx2_product_is_the_scalar_product_to_the_bit() {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            let n = 50;
            let mut b = PatternBuilder::new(n);
            for i in 0..n as u32 - 2 {
                b.add(&[i, i + 1, i + 2]);
            }
            let mut h = b.build();
            let mut s = 3u64;
            let mut next = || {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            for i in 0..n {
                let cols: Vec<usize> = h.row(i).map(|(j, _)| j).collect();
                for j in cols {
                    h.add_block(i, j, &Matrix3::from_fn(|_, _| next())).unwrap();
                }
            }
            let x: Vec<[f64; 3]> = (0..n).map(|_| [next(), next(), next()]).collect();
            let (mut scalar, mut wide) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
            mul_rows(&h.values, &h.pattern, &x, 0, &mut scalar);
            // SAFETY: AVX2 was detected above.
            unsafe { mul_rows_avx2(&h.values, &h.pattern, &x, 0, &mut wide) };
            assert_eq!(scalar, wide);
            // And both are the product.
            for (i, yi) in scalar.iter().enumerate() {
                let mut want = nalgebra::Vector3::zeros();
                for (j, m) in h.row(i) {
                    want += m * nalgebra::Vector3::from(x[j]);
                }
                for k in 0..3 {
                    assert!((yi[k] - want[k]).abs() < 1e-14);
                }
            }
        }
    }
}
