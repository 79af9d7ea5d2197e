//! Gauss–Legendre quadrature: the nodes and weights eq. 9 of seed 000 integrates the
//! attribution path with.
//!
//! `N` nodes integrate polynomials up to degree `2N − 1` exactly on `[−1, 1]`. The nodes
//! `ξ_k` are the roots of the Legendre polynomial `P_N`, found by Newton's method from
//! Tricomi's asymptotic guess `cos(π (k − 1/4) / (N + 1/2))`, with `P_N` and `P_N'` from
//! the three-term recurrence; the weights are `w_k = 2 / ((1 − ξ_k²) P_N'(ξ_k)²)`, the
//! factor written out in eq. 9. Computed rather than tabulated so that `N_s` is free
//! (the paper uses 50).

use crate::error::EvalError;

/// The largest supported number of nodes. Newton from Tricomi's guess converges for every
/// `N` in range; beyond it, f64 weights lose digits and nobody needs them for a path
/// integral.
pub const MAX_NODES: usize = 1000;

/// Nodes and weights of an `N`-point rule.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    /// Nodes `ξ_k` in `(−1, 1)`, ascending.
    pub nodes: Vec<f64>,
    /// Weights `w_k > 0`, summing to 2.
    pub weights: Vec<f64>,
}

/// `P_n(x)` and `P_n'(x)` by the recurrence `(k+1) P_{k+1} = (2k+1) x P_k − k P_{k−1}`.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 1..n {
        let k = k as f64;
        let p2 = ((2.0 * k + 1.0) * x * p1 - k * p0) / (k + 1.0);
        p0 = p1;
        p1 = p2;
    }
    // P_n' = n (x P_n − P_{n−1}) / (x² − 1), valid strictly inside (−1, 1).
    let dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, dp)
}

impl GaussLegendre {
    /// The `n`-point rule on `[−1, 1]`; `n` from 1 to [`MAX_NODES`].
    pub fn new(n: usize) -> Result<Self, EvalError> {
        if n == 0 || n > MAX_NODES {
            return Err(EvalError::Invalid(format!(
                "{n} quadrature nodes; expected 1 to {MAX_NODES}"
            )));
        }
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        // Roots are symmetric: compute the upper half and mirror.
        for k in 0..n.div_ceil(2) {
            let mut x = (std::f64::consts::PI * (k as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let step = p / d;
                x -= step;
                if step.abs() <= 1e-16 * x.abs().max(1.0) {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            if d.is_finite() {
                dp = d;
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[n - 1 - k] = x;
            weights[n - 1 - k] = w;
            nodes[k] = -x;
            weights[k] = w;
        }
        if n % 2 == 1 {
            // The middle root is exactly 0.
            nodes[n / 2] = 0.0;
        }
        Ok(GaussLegendre { nodes, weights })
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the rule has no nodes (never, for a rule from [`Self::new`]).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// `∫_{−1}^{1} f(ξ) dξ ≈ Σ w_k f(ξ_k)`.
    pub fn integrate(&self, mut f: impl FnMut(f64) -> f64) -> f64 {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(x))
            .sum()
    }

    /// The rule mapped to `[0, 1]` by `α = (1 + ξ) / 2`: points `α_k` and weights
    /// `w_k / 2` (summing to 1). Eq. 9 samples the path `α X` at these points; its factor
    /// `1 / ((1 − ξ_k²) P'(ξ_k)²)` is exactly `w_k / 2`.
    pub fn unit_interval(&self) -> Vec<(f64, f64)> {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| (0.5 * (1.0 + x), 0.5 * w))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_small_rules() {
        let g = GaussLegendre::new(1).unwrap();
        assert_eq!((g.nodes[0], g.weights[0]), (0.0, 2.0));
        let g = GaussLegendre::new(2).unwrap();
        let r = 1.0 / 3f64.sqrt();
        assert!((g.nodes[0] + r).abs() < 1e-15 && (g.nodes[1] - r).abs() < 1e-15);
        assert!((g.weights[0] - 1.0).abs() < 1e-14);
        let g = GaussLegendre::new(3).unwrap();
        assert!((g.nodes[2] - 0.6f64.sqrt()).abs() < 1e-15);
        assert!((g.weights[1] - 8.0 / 9.0).abs() < 1e-14);
        assert!((g.weights[0] - 5.0 / 9.0).abs() < 1e-14);
    }

    #[test]
    fn exact_for_polynomials_up_to_degree_2n_minus_1() {
        for n in [1, 2, 3, 5, 8, 13, 50] {
            let g = GaussLegendre::new(n).unwrap();
            assert!(
                (g.weights.iter().sum::<f64>() - 2.0).abs() < 1e-13,
                "n = {n}"
            );
            assert!(g.nodes.windows(2).all(|w| w[0] < w[1]), "n = {n}");
            for d in 0..2 * n {
                // ∫_{−1}^{1} ξ^d = 2/(d+1) for even d, 0 for odd d.
                let exact = if d % 2 == 0 {
                    2.0 / (d as f64 + 1.0)
                } else {
                    0.0
                };
                let got = g.integrate(|x| x.powi(d as i32));
                assert!(
                    (got - exact).abs() < 1e-12,
                    "n = {n}, degree {d}: {got} vs {exact}"
                );
            }
            // Degree 2n is no longer exact (the rule is not better than it should be);
            // visible in f64 for small rules only.
            if n <= 8 {
                let d = 2 * n as i32;
                let got = g.integrate(|x| x.powi(d));
                assert!((got - 2.0 / (f64::from(d) + 1.0)).abs() > 1e-10, "n = {n}");
            }
        }
    }

    #[test]
    fn unit_interval_integrates_on_zero_one() {
        let g = GaussLegendre::new(50).unwrap();
        let s: f64 = g
            .unit_interval()
            .iter()
            .map(|&(a, w)| w * (3.0 * a * a + (5.0 * a).cos()))
            .sum();
        assert!((s - (1.0 + 5f64.sin() / 5.0)).abs() < 1e-14, "{s}");
    }

    #[test]
    fn refuses_zero_and_huge_rules() {
        assert!(GaussLegendre::new(0).is_err());
        assert!(GaussLegendre::new(MAX_NODES + 1).is_err());
        assert_eq!(GaussLegendre::new(MAX_NODES).unwrap().len(), MAX_NODES);
    }
}
