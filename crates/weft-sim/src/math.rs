//! Small linear-algebra helpers: conversions between plain `[f64; 3]` storage and
//! nalgebra types, the skew matrix of a cross product, and the projection of a
//! symmetric element Hessian (or a 2×2 stress) onto the positive semi-definite cone.

use nalgebra::{Matrix2, Matrix3, SMatrix, Vector3};

/// A 3-vector from plain storage.
#[inline]
pub(crate) fn v3(p: [f64; 3]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

/// `[x]×`, the matrix with `[x]× y = x × y`.
#[inline]
pub(crate) fn skew(x: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -x.z, x.y, x.z, 0.0, -x.x, -x.y, x.x, 0.0)
}

/// `true` when every entry is finite.
#[inline]
pub(crate) fn finite3(p: [f64; 3]) -> bool {
    p.iter().all(|c| c.is_finite())
}

/// `out += s · v`.
#[inline]
pub(crate) fn axpy3(out: &mut [f64; 3], s: f64, v: [f64; 3]) {
    for (o, c) in out.iter_mut().zip(v) {
        *o += s * c;
    }
}

macro_rules! project_psd_fn {
    ($name:ident, $n:literal) => {
        /// The nearest (Frobenius) positive semi-definite matrix to the symmetric part of
        /// `m`: eigen-decompose and clamp negative eigenvalues to zero (Teran et al. 2005
        /// apply the same clamp per element so Newton's system stays definite).
        pub(crate) fn $name(m: &SMatrix<f64, $n, $n>) -> SMatrix<f64, $n, $n> {
            let sym = (m + m.transpose()) * 0.5;
            let eig = sym.symmetric_eigen();
            if eig.eigenvalues.iter().all(|&l| l >= 0.0) {
                return sym;
            }
            let mut out = SMatrix::<f64, $n, $n>::zeros();
            for (k, &l) in eig.eigenvalues.iter().enumerate() {
                if l > 0.0 {
                    let q = eig.eigenvectors.column(k);
                    out += q * q.transpose() * l;
                }
            }
            out
        }
    };
}

/// The positive part of a symmetric 2×2 matrix (its negative eigenvalue clamped to
/// zero), in closed form: with eigenvalues `l₁ > 0 > l₂`, `S⁺ = l₁ (S − l₂ I)/(l₁ − l₂)`
/// (that fraction projects onto `l₁`'s eigenvector). Every membrane of every Newton
/// iteration takes one, and nalgebra's iterative eigen-solver was 3 % of a simulated
/// frame.
pub(crate) fn positive_part2(s: &Matrix2<f64>) -> Matrix2<f64> {
    let mean = 0.5 * (s[(0, 0)] + s[(1, 1)]);
    let half_gap = 0.5 * (s[(0, 0)] - s[(1, 1)]);
    let off = 0.5 * (s[(0, 1)] + s[(1, 0)]);
    let r = (half_gap * half_gap + off * off).sqrt();
    let (l1, l2) = (mean + r, mean - r);
    if l2 >= 0.0 {
        Matrix2::new(s[(0, 0)], off, off, s[(1, 1)])
    } else if l1 <= 0.0 {
        Matrix2::zeros()
    } else {
        let mut p = Matrix2::new(s[(0, 0)] - l2, off, off, s[(1, 1)] - l2);
        p *= l1 / (l1 - l2);
        p
    }
}

project_psd_fn!(project_psd6, 6);
project_psd_fn!(project_psd9, 9);
project_psd_fn!(project_psd12, 12);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_clamps_negative_eigenvalues_only() {
        let mut m = SMatrix::<f64, 9, 9>::identity();
        m[(3, 3)] = -2.0;
        m[(0, 1)] = 0.5;
        m[(1, 0)] = 0.5;
        let p = project_psd9(&m);
        assert!(p[(3, 3)].abs() < 1e-14);
        assert!((p[(0, 1)] - 0.5).abs() < 1e-12);
        assert!(p.symmetric_eigen().eigenvalues.iter().all(|&l| l > -1e-12));
        // Already PSD: unchanged.
        let q = SMatrix::<f64, 12, 12>::identity() * 3.0;
        assert_eq!(project_psd12(&q), q);
    }

    #[test]
    fn positive_part2_matches_the_eigen_decomposition() {
        let cases = [
            Matrix2::<f64>::new(2.0, 0.3, 0.3, 1.0), // positive definite: unchanged
            Matrix2::new(-2.0, 0.3, 0.3, -1.0),      // negative definite: zero
            Matrix2::new(1.5, -0.8, -0.8, -0.4),     // indefinite
            Matrix2::new(0.0, 1.0, 1.0, 0.0),        // indefinite, equal diagonal
            Matrix2::new(3.0, 0.0, 0.0, -1e-3),      // diagonal, barely indefinite
        ];
        for s in cases {
            let eig = s.symmetric_eigen();
            let mut want = Matrix2::zeros();
            for k in 0..2 {
                let q = eig.eigenvectors.column(k);
                want += q * q.transpose() * eig.eigenvalues[k].max(0.0);
            }
            let got = positive_part2(&s);
            assert!(
                (got - want).norm() < 1e-14 * (1.0 + s.norm()),
                "{s} -> {got} vs {want}"
            );
        }
    }

    #[test]
    fn skew_is_the_cross_product() {
        let a = Vector3::new(1.0, -2.0, 0.5);
        let b = Vector3::new(0.3, 0.7, -1.1);
        assert!((skew(&a) * b - a.cross(&b)).norm() < 1e-15);
    }
}
