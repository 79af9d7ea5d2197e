//! Preconditioned conjugate gradients for `H d = b` with a symmetric positive
//! (semi-)definite block-sparse `H`, preconditioned by any [`Preconditioner`]; the
//! simplest is the inverses of its 3×3 diagonal blocks (block Jacobi: exact for the
//! per-vertex terms — inertia, collision, friction — and cheap to apply).

use nalgebra::Matrix3;

use crate::error::{check_len, SimError};
use crate::sparse::BlockCsr;

/// How a PCG solve ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcgReport {
    /// Iterations run.
    pub iterations: usize,
    /// `‖r‖ / ‖b‖` at the end.
    pub relative_residual: f64,
    /// Stopped because `pᵀHp <= 0` (a direction of non-positive curvature).
    pub hit_nonpositive_curvature: bool,
}

fn dot(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x[0] * y[0] + x[1] * y[1] + x[2] * y[2])
        .sum()
}

/// An approximation `B ≈ H⁻¹`, symmetric positive definite, applied as `z = B r`.
pub trait Preconditioner {
    /// `z = B r` (overwrites `z`).
    fn apply(&self, r: &[[f64; 3]], z: &mut [[f64; 3]]);
}

/// Inverses of the diagonal blocks; a singular block falls back to the inverse of its
/// diagonal, then to the identity.
#[derive(Clone, Debug)]
pub struct BlockJacobi(Vec<Matrix3<f64>>);

impl BlockJacobi {
    /// Block Jacobi of `h`.
    pub fn new(h: &BlockCsr) -> Self {
        BlockJacobi(
            h.diagonal_blocks()
                .into_iter()
                .map(|b| {
                    let sym = (b + b.transpose()) * 0.5;
                    sym.try_inverse()
                        .filter(|inv| inv.iter().all(|c| c.is_finite()))
                        .unwrap_or_else(|| {
                            Matrix3::from_diagonal(&sym.diagonal().map(|d| {
                                if d > 0.0 {
                                    1.0 / d
                                } else {
                                    1.0
                                }
                            }))
                        })
                })
                .collect(),
        )
    }
}

impl Preconditioner for BlockJacobi {
    fn apply(&self, r: &[[f64; 3]], z: &mut [[f64; 3]]) {
        for ((zi, ri), pi) in z.iter_mut().zip(r).zip(&self.0) {
            let v = pi * nalgebra::Vector3::new(ri[0], ri[1], ri[2]);
            *zi = [v.x, v.y, v.z];
        }
    }
}

/// [`pcg_with`] preconditioned by block Jacobi.
pub fn pcg(
    h: &BlockCsr,
    b: &[[f64; 3]],
    rtol: f64,
    max_iter: usize,
) -> Result<(Vec<[f64; 3]>, PcgReport), SimError> {
    pcg_with(h, b, &BlockJacobi::new(h), rtol, max_iter)
}

/// Solves `h x = b` from `x = 0` to relative residual `rtol` or `max_iter` iterations.
/// Returns the last iterate (on non-positive curvature, the iterate before it, which is
/// still a descent direction for `b = −∇E`).
pub fn pcg_with(
    h: &BlockCsr,
    b: &[[f64; 3]],
    pre: &dyn Preconditioner,
    rtol: f64,
    max_iter: usize,
) -> Result<(Vec<[f64; 3]>, PcgReport), SimError> {
    let n = h.block_rows();
    check_len("right-hand side", n, b.len())?;
    let mut x = vec![[0.0; 3]; n];
    let mut r = b.to_vec();
    let mut z = vec![[0.0; 3]; n];
    pre.apply(&r, &mut z);
    let mut p = z.clone();
    let mut hp = vec![[0.0; 3]; n];
    let bnorm = dot(b, b).sqrt();
    let mut report = PcgReport {
        iterations: 0,
        relative_residual: 0.0,
        hit_nonpositive_curvature: false,
    };
    if bnorm == 0.0 {
        return Ok((x, report));
    }
    let mut rz = dot(&r, &z);
    for it in 0..max_iter {
        h.mul_vec(&p, &mut hp)?;
        let php = dot(&p, &hp);
        if php <= 0.0 || !php.is_finite() {
            report.hit_nonpositive_curvature = true;
            if it == 0 {
                // Fall back to the preconditioned steepest descent direction.
                x.clone_from(&z);
            }
            break;
        }
        let alpha = rz / php;
        for i in 0..n {
            for k in 0..3 {
                x[i][k] += alpha * p[i][k];
                r[i][k] -= alpha * hp[i][k];
            }
        }
        report.iterations = it + 1;
        let rn = dot(&r, &r).sqrt();
        report.relative_residual = rn / bnorm;
        if report.relative_residual <= rtol {
            break;
        }
        pre.apply(&r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            for k in 0..3 {
                p[i][k] = z[i][k] + beta * p[i][k];
            }
        }
    }
    Ok((x, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::PatternBuilder;
    use nalgebra::SMatrix;

    #[test]
    fn solves_a_spd_system() {
        let mut b = PatternBuilder::new(3);
        b.add(&[0, 1]);
        b.add(&[1, 2]);
        let mut h = b.build();
        let a = SMatrix::<f64, 6, 6>::from_fn(|r, c| {
            if r == c {
                4.0
            } else {
                1.0 / (1.0 + (r + c) as f64)
            }
        });
        h.add_element(&[0, 1], &a, 1.0).unwrap();
        h.add_element(&[1, 2], &a, 1.0).unwrap();
        let rhs = [[1.0, 2.0, 3.0], [-1.0, 0.5, 0.0], [0.3, 0.2, 0.1]];
        let (x, rep) = pcg(&h, &rhs, 1e-12, 100).unwrap();
        let mut hx = [[0.0; 3]; 3];
        h.mul_vec(&x, &mut hx).unwrap();
        for i in 0..3 {
            for k in 0..3 {
                assert!((hx[i][k] - rhs[i][k]).abs() < 1e-10);
            }
        }
        assert!(rep.iterations <= 9 && !rep.hit_nonpositive_curvature);
    }
}
