//! Buttons: pairs of garment vertices held together (seed 004 §4, Fig. 4: "we manually
//! choose pairs of vertices to connect graph segments"). HOOD's paper toggles them as
//! graph edges and its public code never implemented them (hood-reference §1.14); weft
//! gives each pair a zero-length spring in the potential, so the simulator holds a
//! buttoned garment closed and a network trained on the potential is told to.
//!
//! `E = Σ_p k_p |x_a − x_b|² / 2`: gradient `k_p (x_a − x_b)` at `a` and its negative at
//! `b`; Hessian `k_p [I −I; −I I]` per pair, constant and positive semi-definite, so
//! it is its own projection.

use nalgebra::Matrix3;

use crate::energy::{Energy, HessianKind};
use crate::error::{check_eval, check_len, check_nonneg, Output, SimError};
use crate::math::axpy3;
use crate::sparse::BlockCsr;

/// Checks button `pairs` against a garment of `vertex_count` vertices: every vertex in
/// range, none paired with itself. The one check of every place that takes pairs (the
/// simulator, HOOD's graph, the commands), so they refuse the same pairs alike.
pub fn check_pairs(pairs: &[[u32; 2]], vertex_count: usize) -> Result<(), SimError> {
    match pairs
        .iter()
        .enumerate()
        .find(|(_, &[a, b])| a == b || a as usize >= vertex_count || b as usize >= vertex_count)
    {
        Some((index, &[a, b])) => Err(SimError::ButtonPair {
            index,
            a,
            b,
            vertex_count,
        }),
        None => Ok(()),
    }
}

/// Zero-length springs between button vertex pairs.
#[derive(Clone, Debug)]
pub struct Buttons {
    vertex_count: usize,
    pairs: Vec<[u32; 2]>,
    stiffness: Vec<f64>,
}

impl Buttons {
    /// Springs of stiffness `stiffness[p]` (N/m, `> 0`) between the two vertices of
    /// `pairs[p]`; errors on an index `≥ vertex_count`, a vertex paired with itself or a
    /// stiffness that is not finite and positive.
    pub fn new(
        vertex_count: usize,
        pairs: Vec<[u32; 2]>,
        stiffness: Vec<f64>,
    ) -> Result<Self, SimError> {
        check_len("button stiffnesses", pairs.len(), stiffness.len())?;
        check_pairs(&pairs, vertex_count)?;
        for (p, &k) in stiffness.iter().enumerate() {
            check_nonneg(|| format!("stiffness of button pair {p}"), k, true)?;
        }
        Ok(Buttons {
            vertex_count,
            pairs,
            stiffness,
        })
    }

    /// The vertex pairs.
    pub fn pairs(&self) -> &[[u32; 2]] {
        &self.pairs
    }

    /// The stiffness of each pair, N/m.
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }

    /// `x_a − x_b` of pair `[a, b]`.
    fn gap(x: &[[f64; 3]], [a, b]: [u32; 2]) -> [f64; 3] {
        let (pa, pb) = (x[a as usize], x[b as usize]);
        std::array::from_fn(|k| pa[k] - pb[k])
    }
}

impl Energy for Buttons {
    fn name(&self) -> &'static str {
        "buttons"
    }

    fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok(self
            .pairs
            .iter()
            .zip(&self.stiffness)
            .map(|(&pair, k)| {
                let d = Self::gap(x, pair);
                0.5 * k * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
            })
            .sum())
    }

    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Gradient(grad.len()))?;
        let e = self.value(x)?;
        for (&pair, k) in self.pairs.iter().zip(&self.stiffness) {
            let d = Self::gap(x, pair);
            axpy3(&mut grad[pair[0] as usize], scale * k, d);
            axpy3(&mut grad[pair[1] as usize], -scale * k, d);
        }
        Ok(e)
    }

    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        _kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError> {
        check_eval(self.vertex_count, x, Output::Hessian(hess.block_rows()))?;
        for (&[a, b], k) in self.pairs.iter().zip(&self.stiffness) {
            let block = Matrix3::identity() * (scale * k);
            let (a, b) = (a as usize, b as usize);
            hess.add_block(a, a, &block)?;
            hess.add_block(b, b, &block)?;
            hess.add_block(a, b, &-block)?;
            hess.add_block(b, a, &-block)?;
        }
        Ok(())
    }

    fn for_each_stencil(&self, _kind: HessianKind, f: &mut dyn FnMut(&[u32])) {
        for pair in &self.pairs {
            f(pair);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pair_pulls_its_two_vertices_together() {
        let x = [[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.0, 0.4, 0.0]];
        let b = Buttons::new(3, vec![[0, 2]], vec![10.0]).unwrap();
        // ½ · 10 · 0.4² = 0.8 J.
        assert!((b.value(&x).unwrap() - 0.8).abs() < 1e-12);
        let mut g = vec![[0.0; 3]; 3];
        b.add_gradient(&x, 1.0, &mut g).unwrap();
        // Vertex 0 is pulled up (towards 2): the gradient points down at it.
        assert_eq!(g, vec![[0.0, -4.0, 0.0], [0.0; 3], [0.0, 4.0, 0.0]]);
        for bad in [
            Buttons::new(3, vec![[0, 3]], vec![1.0]),
            Buttons::new(3, vec![[1, 1]], vec![1.0]),
            Buttons::new(3, vec![[0, 1]], vec![0.0]),
            Buttons::new(3, vec![[0, 1]], vec![]),
        ] {
            assert!(bad.is_err());
        }
    }
}
