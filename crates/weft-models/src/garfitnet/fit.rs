//! The fit parameter α (seed 001 §4.2.1, eq. 4.3–4.4): factor analysis of garment–body
//! distances over training pairs, and α of any pair as the posterior mean of its
//! factors.
//!
//! Each sample is one garment–body pair's distance vector `d` in the rest pose; the model
//! is `d = μ + L a + ε`, `a ~ N(0, I)`, `ε ~ N(0, Ψ)` with `Ψ` diagonal. The thesis fits
//! it by "SVD-based likelihood optimisation" (Barber, *Bayesian Reasoning and Machine
//! Learning*, alg. 21.1, as scikit-learn's `FactorAnalysis` implements it), not by EM:
//! per iteration one SVD of the noise-whitened data gives the loadings, then the noise
//! variances, until the log-likelihood gains less than `tol`. Written here on nalgebra's
//! SVD: the algorithm is twenty lines, and no well-kept Rust crate implements it.
//!
//! Signs: a factor's sign is free in the likelihood; each is turned so that its loadings
//! sum to a positive value, so a larger `α_k` means larger garment–body distances (the
//! thesis's Fig. 4.3: the first factor orders tight → loose).
//!
//! The samples ([`garment_body_distances`]): eq. 4.3 indexes distances by garment
//! vertex, which gives every garment template its own length of `d`, so one factor
//! model could not cover garments of different meshes, nor give α to an unseen one
//! (thesis-reference G1). Here they are indexed by **body** vertex, whose topology every
//! body shares: each body vertex's distance to the garment surface in the rest pose,
//! capped, so a body vertex the garment does not cover reads the cap. A looser garment
//! raises the covered distances, a shorter one turns more of them into the cap; both
//! are fit, and the factors sort them out.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use weft_body::query::BodySurface;
use weft_mesh::TriMesh;

use crate::error::ModelError;

/// One garment–body pair's sample: the distance from each of `body`'s vertices (rest
/// pose, the body the garment was made for) to `garment`'s surface, at most `cap`
/// metres (see the module documentation).
pub fn garment_body_distances(
    body: &[[f64; 3]],
    garment: &TriMesh,
    cap: f64,
) -> Result<Vec<f64>, ModelError> {
    if !(cap.is_finite() && cap > 0.0) {
        return Err(ModelError::Config(format!(
            "distance cap {cap}: expected a positive number of metres"
        )));
    }
    let surface =
        BodySurface::from_mesh(garment).map_err(|e| ModelError::Garment(e.to_string()))?;
    body.iter()
        .map(|&p| {
            surface
                .closest_point_within(p, cap)
                .map(|c| c.map_or(cap, |c| c.distance))
                .map_err(|e| ModelError::Body(e.to_string()))
        })
        .collect()
}

/// One garment–body pair's sample for the factor model: [`garment_body_distances`] from
/// the body of `model` at shape `betas` (rest pose), averaged over the body's regions
/// (each body vertex in the region of the joint that weighs most in its skinning): one
/// value per joint.
///
/// Why regions: with per-vertex samples (13 380 values for a few dozen training pairs)
/// the factor model explains single pairs exactly (a noise variance near zero on the
/// vertices where one pair differs) and gave most of garfit-tiny's pairs the same α; 24
/// region means keep what fit is (how far the garment stands off the hips, the thighs,
/// the shins, and which regions it covers) in a dimension the pairs can estimate.
pub fn fit_sample(
    model: &weft_body::BodyModel,
    betas: &[f64],
    garment: &TriMesh,
    cap: f64,
) -> Result<Vec<f64>, ModelError> {
    let body = model
        .shape(betas)
        .map_err(|e| ModelError::Body(e.to_string()))?;
    let distances = garment_body_distances(&body.positions, garment, cap)?;
    let weights = model.weights();
    let regions = weights.joint_count();
    let (mut sum, mut count) = (vec![0.0; regions], vec![0usize; regions]);
    for (v, d) in distances.iter().enumerate() {
        let region = weights
            .influences(v)
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(j, _)| j);
        sum[region] += d;
        count[region] += 1;
    }
    Ok(sum
        .iter()
        .zip(&count)
        .map(|(s, &c)| if c == 0 { cap } else { s / c as f64 })
        .collect())
}

/// Settings of [`FactorAnalysis::fit`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FactorAnalysisConfig {
    /// Factors (the length of α). Default 3, the thesis's.
    pub factors: usize,
    /// Stop when the log-likelihood gains less than this. Default 1e-2 (scikit-learn's).
    pub tol: f64,
    /// At most this many iterations. Default 1 000.
    pub max_iterations: usize,
}

impl Default for FactorAnalysisConfig {
    fn default() -> Self {
        FactorAnalysisConfig {
            factors: 3,
            tol: 1e-2,
            max_iterations: 1000,
        }
    }
}

/// A fitted factor model; see the module documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FactorAnalysis {
    /// The mean sample `μ`, `[D]`.
    pub mean: Vec<f64>,
    /// Loadings `L`, one row of `D` per factor.
    pub loadings: Vec<Vec<f64>>,
    /// Noise variances `Ψ`, `[D]`.
    pub noise: Vec<f64>,
    /// Log-likelihood of the training samples after each iteration.
    pub log_likelihood: Vec<f64>,
}

/// Noise variances never fall below this (scikit-learn's floor), so `Ψ^{-1/2}` exists.
const MIN_NOISE: f64 = 1e-12;

impl FactorAnalysis {
    /// Fits `cfg.factors` factors to `samples` (one distance vector per pair, all of one
    /// length). Errors: fewer than two samples, ragged or non-finite samples, or more
    /// factors than samples or features.
    pub fn fit(samples: &[Vec<f64>], cfg: &FactorAnalysisConfig) -> Result<Self, ModelError> {
        let x = matrix(samples, None)?;
        let (n, d) = x.shape();
        if n < 2 {
            return Err(ModelError::mismatch(
                "factor analysis samples",
                "at least 2".to_string(),
                n,
            ));
        }
        if cfg.factors == 0 || cfg.factors > n.min(d) {
            return Err(ModelError::Config(format!(
                "factors = {}: expected 1 to {} (the fewer of {n} samples and {d} features)",
                cfg.factors,
                n.min(d)
            )));
        }
        if !(cfg.tol.is_finite() && cfg.tol > 0.0) {
            return Err(ModelError::Config(format!(
                "tol = {}: expected a positive number",
                cfg.tol
            )));
        }
        let k = cfg.factors;
        let mean = x.row_mean().transpose();
        let centred = DMatrix::from_fn(n, d, |i, j| x[(i, j)] - mean[j]);
        let var: Vec<f64> = (0..d)
            .map(|j| centred.column(j).norm_squared() / n as f64)
            .collect();
        let ll_const = d as f64 * (2.0 * std::f64::consts::PI).ln() + k as f64;
        let mut noise = vec![1.0f64; d];
        let mut loadings = DMatrix::zeros(k, d);
        let mut log_likelihood = Vec::new();
        let sqrt_n = (n as f64).sqrt();
        for _ in 0..cfg.max_iterations {
            let sqrt_noise: Vec<f64> = noise.iter().map(|p| p.sqrt() + MIN_NOISE).collect();
            let whitened =
                DMatrix::from_fn(n, d, |i, j| centred[(i, j)] / (sqrt_noise[j] * sqrt_n));
            let total = whitened.norm_squared();
            let svd = whitened.svd(false, true);
            let v_t = svd
                .v_t
                .ok_or_else(|| ModelError::Config("factor analysis: SVD failed".into()))?;
            // Singular values, largest first, with their right vectors.
            let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
            order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
            let s2: Vec<f64> = order[..k]
                .iter()
                .map(|&r| svd.singular_values[r].powi(2))
                .collect();
            let unexplained = total - s2.iter().sum::<f64>();
            for (f, &r) in order[..k].iter().enumerate() {
                let scale = (s2[f] - 1.0).max(0.0).sqrt();
                for j in 0..d {
                    loadings[(f, j)] = scale * v_t[(r, j)] * sqrt_noise[j];
                }
            }
            let ll = -(n as f64) / 2.0
                * (ll_const
                    + s2.iter().map(|s| s.max(MIN_NOISE).ln()).sum::<f64>()
                    + unexplained
                    + noise.iter().map(|p| p.ln()).sum::<f64>());
            let gain = ll - log_likelihood.last().copied().unwrap_or(f64::NEG_INFINITY);
            log_likelihood.push(ll);
            if gain < cfg.tol {
                break;
            }
            for (j, p) in noise.iter_mut().enumerate() {
                *p = (var[j] - loadings.column(j).norm_squared()).max(MIN_NOISE);
            }
        }
        for mut row in loadings.row_iter_mut() {
            if row.sum() < 0.0 {
                row.neg_mut();
            }
        }
        Ok(FactorAnalysis {
            mean: mean.iter().copied().collect(),
            loadings: loadings
                .row_iter()
                .map(|r| r.iter().copied().collect())
                .collect(),
            noise,
            log_likelihood,
        })
    }

    /// Factors (the length of α).
    pub fn factors(&self) -> usize {
        self.loadings.len()
    }

    /// α of each sample: the posterior mean `(I + L Ψ⁻¹ Lᵀ)⁻¹ L Ψ⁻¹ (d − μ)` (eq. 4.4's
    /// `A`, for training pairs and unseen ones alike).
    pub fn alpha(&self, samples: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, ModelError> {
        let d = self.mean.len();
        let x = matrix(samples, Some(d))?;
        let k = self.factors();
        let l = DMatrix::from_fn(k, d, |f, j| self.loadings[f][j]);
        let l_psi = DMatrix::from_fn(k, d, |f, j| l[(f, j)] / self.noise[j]);
        let cov = (DMatrix::identity(k, k) + &l_psi * l.transpose())
            .try_inverse()
            .ok_or_else(|| {
                ModelError::Config("factor analysis: posterior covariance not invertible".into())
            })?;
        let mean = DVector::from_column_slice(&self.mean);
        Ok(x.row_iter()
            .map(|row| {
                let centred = row.transpose() - &mean;
                (&cov * (&l_psi * centred)).iter().copied().collect()
            })
            .collect())
    }
}

/// `samples` as an `n × d` matrix; every row of length `width` (or of the first row's).
fn matrix(samples: &[Vec<f64>], width: Option<usize>) -> Result<DMatrix<f64>, ModelError> {
    let d = width.unwrap_or_else(|| samples.first().map_or(0, Vec::len));
    if d == 0 {
        return Err(ModelError::mismatch(
            "factor analysis features",
            "at least 1".to_string(),
            0,
        ));
    }
    for (i, s) in samples.iter().enumerate() {
        if s.len() != d {
            return Err(ModelError::mismatch(
                "factor analysis sample length",
                format!("{d} (sample {i})"),
                s.len(),
            ));
        }
        if let Some(j) = s.iter().position(|v| !v.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "factor analysis sample",
                index: i * d + j,
            });
        }
    }
    Ok(DMatrix::from_fn(samples.len(), d, |i, j| samples[i][j]))
}

#[cfg(test)]
mod tests {
    use weft_mesh::rng::SplitMix64;

    use super::*;

    /// `n` samples of `d = L a + μ + ε` with two planted factors: a "looseness" that
    /// raises every distance, and one that trades the first half against the second.
    fn planted(n: usize, d: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<[f64; 2]>) {
        let mut rng = SplitMix64::new(seed);
        let mut gauss = move || {
            // Box–Muller from two uniforms.
            let (u, v) = (rng.unit().max(1e-300), rng.unit());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        };
        let mut samples = Vec::new();
        let mut factors = Vec::new();
        for _ in 0..n {
            let a = [gauss(), gauss()];
            samples.push(
                (0..d)
                    .map(|j| {
                        let half = if j < d / 2 { 1.0 } else { -1.0 };
                        0.02 + 0.01 * a[0] + 0.004 * half * a[1] + 0.0005 * gauss()
                    })
                    .collect(),
            );
            factors.push(a);
        }
        (samples, factors)
    }

    fn correlation(x: &[f64], y: &[f64]) -> f64 {
        let n = x.len() as f64;
        let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
        let cov: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
        let vx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
        let vy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
        cov / (vx * vy).sqrt()
    }

    #[test]
    fn recovers_planted_factors_and_orders_tight_to_loose() {
        let (samples, truth) = planted(60, 40, 7);
        let cfg = FactorAnalysisConfig {
            factors: 2,
            ..FactorAnalysisConfig::default()
        };
        let fa = FactorAnalysis::fit(&samples, &cfg).unwrap();
        // The likelihood never falls, and the fit stops well before the budget.
        assert!(fa.log_likelihood.windows(2).all(|w| w[1] >= w[0] - 1e-9));
        assert!(fa.log_likelihood.len() < 200, "{}", fa.log_likelihood.len());
        // The noise variances come back near the planted 0.0005².
        let noise = fa.noise.iter().sum::<f64>() / fa.noise.len() as f64;
        assert!((noise / 0.0005f64.powi(2) - 1.0).abs() < 0.3, "{noise}");
        let alpha = fa.alpha(&samples).unwrap();
        let first: Vec<f64> = alpha.iter().map(|a| a[0]).collect();
        let loose: Vec<f64> = truth.iter().map(|a| a[0]).collect();
        // The first factor is the looseness, with its sign: larger α, looser fit.
        assert!(
            correlation(&first, &loose) > 0.99,
            "{}",
            correlation(&first, &loose)
        );
        let second: Vec<f64> = alpha.iter().map(|a| a[1]).collect();
        let trade: Vec<f64> = truth.iter().map(|a| a[1]).collect();
        assert!(correlation(&second, &trade).abs() > 0.95);
        // An unseen pair: a uniformly looser garment gets a larger first α.
        let tight: Vec<f64> = vec![0.01; 40];
        let loose_pair: Vec<f64> = vec![0.03; 40];
        let a = fa.alpha(&[tight, loose_pair]).unwrap();
        assert!(a[1][0] > a[0][0] + 1.0, "{a:?}");
    }

    #[test]
    fn body_indexed_distances_give_any_garment_an_alpha_that_orders_looseness() {
        // A leg (radius 10 cm, 38 cm long) and tubes of four lengths and six radii, each
        // meshed with its own ring count.
        let leg = weft_mesh::primitives::cylinder(20, 32, 0.1, 0.02);
        let radii = [0.105, 0.11, 0.115, 0.12, 0.125, 0.13];
        let mut samples = Vec::new();
        for rings in [8, 10, 12, 14] {
            for r in radii {
                let tube = weft_mesh::primitives::cylinder(rings, 32, r, 0.02);
                samples.push(garment_body_distances(&leg.positions, &tube, 0.1).unwrap());
            }
        }
        // Covered body vertices read the gap (less the chords), those below the hem more, up
        // to the cap.
        let s = &samples[1];
        assert!((s[0] - 0.01).abs() < 1e-4, "{}", s[0]);
        assert!(s[19 * 32] == 0.1 && s[8 * 32] > 0.01);
        let cfg = FactorAnalysisConfig {
            factors: 2,
            ..FactorAnalysisConfig::default()
        };
        let fa = FactorAnalysis::fit(&samples, &cfg).unwrap();
        let alpha = fa.alpha(&samples).unwrap();
        // One factor grows with the radius at every length.
        assert!(
            (0..2).any(|k| alpha
                .chunks(radii.len())
                .all(|g| g.windows(2).all(|w| w[1][k] > w[0][k]))),
            "{alpha:?}"
        );
        assert!(garment_body_distances(&leg.positions, &leg, 0.0).is_err());
    }

    #[test]
    fn the_same_samples_give_the_same_model() {
        let (samples, _) = planted(20, 12, 3);
        let cfg = FactorAnalysisConfig::default();
        assert_eq!(
            FactorAnalysis::fit(&samples, &cfg).unwrap(),
            FactorAnalysis::fit(&samples, &cfg).unwrap()
        );
    }

    #[test]
    fn bad_samples_are_refused_by_name() {
        let cfg = FactorAnalysisConfig::default();
        let e = |s: &[Vec<f64>], c: &FactorAnalysisConfig| {
            FactorAnalysis::fit(s, c).unwrap_err().to_string()
        };
        assert!(e(&[vec![1.0; 4]], &cfg).contains("at least 2"));
        assert!(e(&[vec![1.0; 4], vec![1.0; 3]], &cfg).contains("sample 1"));
        assert!(e(&[vec![1.0; 4], vec![f64::NAN; 4]], &cfg).contains("non-finite"));
        let many = FactorAnalysisConfig { factors: 5, ..cfg };
        assert!(e(&[vec![1.0; 4], vec![2.0; 4]], &many).contains("factors = 5"));
        let (samples, _) = planted(10, 6, 1);
        let fa = FactorAnalysis::fit(&samples, &cfg).unwrap();
        assert!(fa.alpha(&[vec![0.0; 5]]).is_err());
    }

    #[test]
    fn region_samples_read_a_looser_garment_as_farther() {
        use weft_garment::{FitBody, GarmentKind, Style};
        let body = weft_body::default_body().unwrap();
        let fit = FitBody::new(&body, &[]).unwrap();
        let skirt = fit
            .generate(
                GarmentKind::Skirt,
                &Style::from_seed(GarmentKind::Skirt, 5),
                400,
            )
            .unwrap()
            .mesh;
        let tight = fit_sample(&body, &[], &skirt, 0.1).unwrap();
        assert_eq!(tight.len(), body.joint_count());
        assert!(
            tight.iter().all(|&d| (0.0..=0.1 + 1e-9).contains(&d)),
            "{tight:?}"
        );
        // The same skirt 1.5 cm farther out, horizontally from its axis.
        let c: [f64; 3] = [0, 1, 2].map(|k| {
            skirt.positions.iter().map(|p| p[k]).sum::<f64>() / skirt.positions.len() as f64
        });
        let mut loose = skirt.clone();
        for p in &mut loose.positions {
            let (dx, dz) = (p[0] - c[0], p[2] - c[2]);
            let r = (dx * dx + dz * dz).sqrt().max(1e-9);
            p[0] += 0.015 * dx / r;
            p[2] += 0.015 * dz / r;
        }
        let looser = fit_sample(&body, &[], &loose, 0.1).unwrap();
        let covered: Vec<usize> = (0..tight.len()).filter(|&j| tight[j] < 0.095).collect();
        assert!(!covered.is_empty());
        for &j in &covered {
            assert!(
                looser[j] > tight[j],
                "region {j}: {} vs {}",
                looser[j],
                tight[j]
            );
        }
    }
}
