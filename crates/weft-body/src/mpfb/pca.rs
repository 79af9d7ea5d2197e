//! Principal components of a set of meshes, the way SMPL's shape space was built.
//!
//! With `S` samples of dimension `D = 3V` and `S ≪ D`, the components come from the
//! `S × S` Gram matrix of the centred samples: if `X Xᵀ = E Λ Eᵀ`, the unit principal
//! directions are `u_k = Xᵀ e_k / √λ_k` and the standard deviation along `u_k` is
//! `√(λ_k / (S − 1))`. That is exact (not an approximation) and costs `S² D` instead of
//! an SVD of the `S × D` matrix.

use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

/// The principal components of some samples.
#[derive(Clone, Debug)]
pub struct Pca {
    /// The mean sample (length D).
    pub mean: Vec<f64>,
    /// Unit principal directions, largest variance first (each of length D).
    pub directions: Vec<Vec<f64>>,
    /// Standard deviation of the samples along each direction.
    pub std_devs: Vec<f64>,
    /// Total variance of the samples (sum over all directions).
    pub total_variance: f64,
}

/// The first `k` principal components of `samples` (each of the same length D).
///
/// Deterministic: the signs of the directions are fixed by `orient`, which should
/// return a value whose sign says whether a direction points the preferred way.
pub fn pca(samples: &[Vec<f64>], k: usize, orient: impl Fn(&[f64]) -> f64) -> Pca {
    let s = samples.len();
    let d = samples.first().map_or(0, Vec::len);
    let mut mean = vec![0.0; d];
    for x in samples {
        for (m, v) in mean.iter_mut().zip(x) {
            *m += v;
        }
    }
    mean.iter_mut().for_each(|m| *m /= s.max(1) as f64);
    let centred: Vec<Vec<f64>> = samples
        .par_iter()
        .map(|x| x.iter().zip(&mean).map(|(a, b)| a - b).collect())
        .collect();
    let rows: Vec<Vec<f64>> = (0..s)
        .into_par_iter()
        .map(|i| (0..s).map(|j| dot(&centred[i], &centred[j])).collect())
        .collect();
    let gram = DMatrix::from_fn(s, s, |i, j| rows[i][j]);
    let eig = SymmetricEigen::new(gram);
    let mut order: Vec<usize> = (0..s).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let total_variance =
        eig.eigenvalues.iter().map(|l| l.max(0.0)).sum::<f64>() / (s.max(2) - 1) as f64;
    let mut directions = Vec::new();
    let mut std_devs = Vec::new();
    for &c in order.iter().take(k) {
        let lambda = eig.eigenvalues[c].max(0.0);
        let e = eig.eigenvectors.column(c);
        let mut u = vec![0.0; d];
        for (i, x) in centred.iter().enumerate() {
            let w = e[i];
            for (a, b) in u.iter_mut().zip(x) {
                *a += w * b;
            }
        }
        let n = dot(&u, &u).sqrt();
        if n > 0.0 {
            u.iter_mut().for_each(|a| *a /= n);
        }
        if orient(&u) < 0.0 {
            u.iter_mut().for_each(|a| *a = -*a);
        }
        directions.push(u);
        std_devs.push((lambda / (s.max(2) - 1) as f64).sqrt());
    }
    Pca {
        mean,
        directions,
        std_devs,
        total_variance,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_known_axes_and_spreads() {
        // Samples spread 3 along (1,1,0)/√2 and 1 along (0,0,1) around (5, 5, 5).
        let mut samples = Vec::new();
        let r = std::f64::consts::FRAC_1_SQRT_2;
        for &a in &[-3.0, 3.0] {
            for &b in &[-1.0, 1.0] {
                samples.push(vec![5.0 + a * r, 5.0 + a * r, 5.0 + b]);
            }
        }
        let p = pca(&samples, 2, |u| u.iter().sum());
        assert!(p.mean.iter().all(|m| (m - 5.0).abs() < 1e-12));
        // Sample std over 4 points of ±3: sqrt(4·9/3) = sqrt(12).
        assert!((p.std_devs[0] - 12f64.sqrt()).abs() < 1e-12);
        assert!((p.std_devs[1] - (4.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!((p.directions[0][0] - r).abs() < 1e-12 && (p.directions[0][1] - r).abs() < 1e-12);
        assert!((p.directions[1][2] - 1.0).abs() < 1e-12);
        assert!((p.total_variance - (12.0 + 4.0 / 3.0)).abs() < 1e-9);
    }
}
