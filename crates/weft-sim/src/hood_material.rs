//! HOOD's training materials (seed 004; hood-reference §1.9, their
//! `runners/utils/material.py`): one material sampled per training sample, the same on
//! every vertex, and the network's view of a material as three numbers in `[0, 1]`.
//!
//! Distributions (HOOD's config): Lamé `μ` log-uniform in [`HOOD_MU_RANGE`], `λ`
//! uniform in [`HOOD_LAMBDA_RANGE`], the bending stiffness `k_b` log-uniform in
//! [`HOOD_BENDING_RANGE`], the area density uniform in [`HOOD_DENSITY_RANGE`];
//! thickness and friction are [`Material::hood`]'s. Draws come from weft's one seeded
//! generator ([`SplitMix64`]), four numbers per material in the order `μ, λ, k_b, ρ`, so
//! a seed gives the same materials on every platform.

use weft_mesh::rng::SplitMix64;

use crate::material::Material;

/// HOOD's range of the Lamé `μ`, Pa (sampled log-uniform).
pub const HOOD_MU_RANGE: [f64; 2] = [15_909.0, 63_636.0];
/// HOOD's range of the Lamé `λ`, Pa (sampled uniform).
pub const HOOD_LAMBDA_RANGE: [f64; 2] = [3_535.41, 93_333.74];
/// HOOD's range of the bending stiffness `k_b`, N·m (sampled log-uniform).
pub const HOOD_BENDING_RANGE: [f64; 2] = [6.3708e-8, 1.31397e-3];
/// HOOD's range of the area density, kg/m² (sampled uniform).
pub const HOOD_DENSITY_RANGE: [f64; 2] = [0.0434, 0.7];

/// A seeded stream of HOOD training materials ([`sample_hood_material`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaterialSampler {
    rng: SplitMix64,
}

impl MaterialSampler {
    /// A sampler whose stream is fixed by `seed`.
    pub fn new(seed: u64) -> Self {
        MaterialSampler {
            rng: SplitMix64::new(seed),
        }
    }

    /// The next material.
    pub fn sample(&mut self) -> Material {
        sample_hood_material(&mut self.rng)
    }
}

/// One HOOD training material (module docs), named `custom`: `μ`, `λ`, `k_b`, density
/// drawn in that order from `rng`, thickness and friction of [`Material::hood`]. Every
/// value lies in its closed range.
pub fn sample_hood_material(rng: &mut SplitMix64) -> Material {
    let mu = log_uniform(rng, HOOD_MU_RANGE);
    let lambda = uniform(rng, HOOD_LAMBDA_RANGE);
    let bending = log_uniform(rng, HOOD_BENDING_RANGE);
    let density = uniform(rng, HOOD_DENSITY_RANGE);
    let hood = Material::hood();
    Material::from_lame(
        "custom",
        density,
        mu,
        lambda,
        hood.thickness,
        bending,
        hood.friction,
    )
}

/// The network's material inputs, HOOD's raw features in HOOD's order
/// `[k_b, μ, λ]` (their node and edge features end with "bending, μ, λ"): each value's
/// position in its training range, `(ln v − ln lo)/(ln hi − ln lo)` for `k_b` and `μ`,
/// `(v − lo)/(hi − lo)` for `λ`. `μ`, `λ` are the material's plane-stress Lamé
/// parameters ([`Material::lame`]). Range ends map to 0 and 1; values outside the
/// training range map outside `[0, 1]` on the same line (extrapolation, which the
/// network never saw); `k_b = 0` maps to `−∞`. Density is not an input (it enters
/// through the vertex masses).
pub fn hood_inputs(material: &Material) -> [f64; 3] {
    let (mu, lambda) = material.lame();
    [
        log_position(material.bending_stiffness, HOOD_BENDING_RANGE),
        log_position(mu, HOOD_MU_RANGE),
        (lambda - HOOD_LAMBDA_RANGE[0]) / (HOOD_LAMBDA_RANGE[1] - HOOD_LAMBDA_RANGE[0]),
    ]
}

fn uniform(rng: &mut SplitMix64, [lo, hi]: [f64; 2]) -> f64 {
    rng.uniform(lo, hi).clamp(lo, hi)
}

/// `exp` of a uniform draw in `[ln lo, ln hi)`, clamped to `[lo, hi]` against rounding.
fn log_uniform(rng: &mut SplitMix64, [lo, hi]: [f64; 2]) -> f64 {
    rng.uniform(lo.ln(), hi.ln()).exp().clamp(lo, hi)
}

fn log_position(v: f64, [lo, hi]: [f64; 2]) -> f64 {
    (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn within(v: f64, [lo, hi]: [f64; 2]) -> bool {
        (lo..=hi).contains(&v)
    }

    /// Draws lie in HOOD's ranges (μ, λ through the E, ν round trip, to rounding), are
    /// valid materials, and the same seed gives the same stream.
    #[test]
    fn draws_lie_in_the_ranges_and_repeat_with_the_seed() {
        let mut s = MaterialSampler::new(7);
        let draws: Vec<Material> = (0..2000).map(|_| s.sample()).collect();
        let tol = |[lo, hi]: [f64; 2]| [lo * (1.0 - 1e-12), hi * (1.0 + 1e-12)];
        for m in &draws {
            m.validate().unwrap();
            let (mu, lambda) = m.lame();
            assert!(within(mu, tol(HOOD_MU_RANGE)), "{m:?}");
            assert!(within(lambda, tol(HOOD_LAMBDA_RANGE)), "{m:?}");
            assert!(within(m.bending_stiffness, HOOD_BENDING_RANGE), "{m:?}");
            assert!(within(m.density, HOOD_DENSITY_RANGE), "{m:?}");
            assert_eq!(m.thickness, Material::hood().thickness);
            assert_eq!(m.friction, Material::hood().friction);
            for x in hood_inputs(m) {
                assert!((-1e-9..=1.0 + 1e-9).contains(&x), "{m:?}");
            }
        }
        let mut again = MaterialSampler::new(7);
        assert!(draws.iter().all(|m| *m == again.sample()));
        let other = MaterialSampler::new(8).sample();
        assert_ne!(other, draws[0]);
        // The free function on the same generator is the same stream.
        let mut rng = SplitMix64::new(7);
        assert_eq!(sample_hood_material(&mut rng), draws[0]);
    }

    /// The distributions: log-uniform μ and k_b have their median at the geometric mean
    /// of the range, uniform λ and density at the arithmetic mean; every input spreads
    /// over [0, 1] uniformly (mean ½).
    #[test]
    fn distributions_are_hoods() {
        let mut s = MaterialSampler::new(1);
        let n = 20_000;
        let draws: Vec<Material> = (0..n).map(|_| s.sample()).collect();
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let geo = |[lo, hi]: [f64; 2]| (lo * hi).sqrt();
        let mid = |[lo, hi]: [f64; 2]| 0.5 * (lo + hi);
        let close = |got: f64, want: f64, range: f64| (got - want).abs() < 0.03 * range;
        let mu = median(draws.iter().map(|m| m.lame().0).collect());
        let kb = median(draws.iter().map(|m| m.bending_stiffness).collect());
        let lambda = median(draws.iter().map(|m| m.lame().1).collect());
        let rho = median(draws.iter().map(|m| m.density).collect());
        // Log-uniform: compare on the log scale.
        let log_range = |[lo, hi]: [f64; 2]| (hi / lo).ln();
        assert!(close(
            mu.ln(),
            geo(HOOD_MU_RANGE).ln(),
            log_range(HOOD_MU_RANGE)
        ));
        assert!(close(
            kb.ln(),
            geo(HOOD_BENDING_RANGE).ln(),
            log_range(HOOD_BENDING_RANGE)
        ));
        let width = |[lo, hi]: [f64; 2]| hi - lo;
        assert!(close(
            lambda,
            mid(HOOD_LAMBDA_RANGE),
            width(HOOD_LAMBDA_RANGE)
        ));
        assert!(close(
            rho,
            mid(HOOD_DENSITY_RANGE),
            width(HOOD_DENSITY_RANGE)
        ));
        for k in 0..3 {
            let mean = draws.iter().map(|m| hood_inputs(m)[k]).sum::<f64>() / n as f64;
            assert!((mean - 0.5).abs() < 0.01, "input {k}: mean {mean}");
        }
    }

    /// The range ends map to 0 and 1, HOOD's default material inside, values beyond the
    /// range outside [0, 1].
    #[test]
    fn inputs_map_the_range_ends_to_0_and_1() {
        let at = |mu: f64, lambda: f64, kb: f64| {
            hood_inputs(&Material::from_lame(
                "custom", 0.2, mu, lambda, 4.7e-4, kb, 0.5,
            ))
        };
        let [lo, hi] = [0, 1].map(|k| {
            at(
                HOOD_MU_RANGE[k],
                HOOD_LAMBDA_RANGE[k],
                HOOD_BENDING_RANGE[k],
            )
        });
        for k in 0..3 {
            assert!(lo[k].abs() < 1e-12, "{lo:?}");
            assert!((hi[k] - 1.0).abs() < 1e-12, "{hi:?}");
        }
        let hood = hood_inputs(&Material::hood());
        assert!(hood.iter().all(|x| (0.0..1.0).contains(x)), "{hood:?}");
        // λ = 44 400 is (44 400 − 3 535.41)/(93 333.74 − 3 535.41) along its range.
        assert!((hood[2] - 0.455_070_712_3).abs() < 1e-9, "{hood:?}");
        let beyond = at(2.0 * HOOD_MU_RANGE[1], 0.0, 0.5 * HOOD_BENDING_RANGE[0]);
        assert!(
            beyond[0] < 0.0 && beyond[1] > 1.0 && beyond[2] < 0.0,
            "{beyond:?}"
        );
    }
}
