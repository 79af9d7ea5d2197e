//! HOOD's training materials (seed 004; hood-reference §1.9, their
//! `runners/utils/material.py`): the space a network is trained over, one material
//! sampled from it per training sample (or per region), and the network's view of a
//! material as three numbers, its position in that space.
//!
//! Distributions (HOOD's config): Lamé `μ` log-uniform, `λ` uniform, the bending
//! stiffness `k_b` log-uniform, the area density uniform, each in its range of
//! [`MaterialRanges`]; every sample has the ranges' thickness and [`Material::hood`]'s
//! friction. HOOD's own ranges are [`MaterialRanges::hood`]; a run may train over
//! others (`[model.materials]`), which are then also the scale its inputs are read on.
//! Draws come from weft's one seeded generator ([`SplitMix64`]), four numbers per
//! material in the order `μ, λ, k_b, ρ`, so a seed gives the same materials on every
//! platform.

use serde::{Deserialize, Serialize};
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

/// The material space of a HOOD network: where its training materials are drawn and
/// the scale its material inputs are read on ([`MaterialRanges::inputs`]).
///
/// `μ` and `λ` are those of a membrane of [`MaterialRanges::thickness`]: the stretching
/// energy is thickness × area × StVK density, so a material of another thickness is
/// placed by its `μ·h` and `λ·h` (silk, 769 kPa at 0.15 mm, sits where 245 kPa does at
/// HOOD's 0.47 mm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
// A field left out of a run's `[model.materials]` keeps HOOD's range.
#[serde(default, deny_unknown_fields)]
pub struct MaterialRanges {
    /// Lamé `μ`, Pa, `[lo, hi]` (sampled log-uniform).
    pub mu: [f64; 2],
    /// Lamé `λ`, Pa, `[lo, hi]` (sampled uniform).
    pub lambda: [f64; 2],
    /// Bending stiffness `k_b`, N·m, `[lo, hi]` (sampled log-uniform).
    pub bending: [f64; 2],
    /// Area density, kg/m², `[lo, hi]` (sampled uniform).
    pub density: [f64; 2],
    /// Thickness of every sampled material, m.
    pub thickness: f64,
}

impl Default for MaterialRanges {
    fn default() -> Self {
        Self::hood()
    }
}

impl MaterialRanges {
    /// HOOD's ranges (its config), at [`Material::hood`]'s thickness.
    pub fn hood() -> Self {
        MaterialRanges {
            mu: HOOD_MU_RANGE,
            lambda: HOOD_LAMBDA_RANGE,
            bending: HOOD_BENDING_RANGE,
            density: HOOD_DENSITY_RANGE,
            thickness: Material::hood().thickness,
        }
    }

    /// Checks every range: finite, `lo <= hi`, positive (`λ` may start at 0), and a
    /// positive thickness; errors name the field.
    pub fn validate(&self) -> Result<(), String> {
        for (name, [lo, hi], min) in [
            ("mu", self.mu, f64::MIN_POSITIVE),
            ("lambda", self.lambda, 0.0),
            ("bending", self.bending, f64::MIN_POSITIVE),
            ("density", self.density, f64::MIN_POSITIVE),
        ] {
            if !(lo.is_finite() && hi.is_finite() && lo >= min && lo <= hi) {
                return Err(format!(
                    "materials.{name} = [{lo}, {hi}]: expected finite [lo, hi] with lo <= hi and lo {}",
                    if min == 0.0 { ">= 0" } else { "> 0" }
                ));
            }
        }
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(format!(
                "materials.thickness = {}: expected a positive number of metres",
                self.thickness
            ));
        }
        Ok(())
    }

    /// One training material (module docs), named `custom`: `μ`, `λ`, `k_b`, density
    /// drawn in that order from `rng`. Every value lies in its closed range.
    pub fn sample(&self, rng: &mut SplitMix64) -> Material {
        let mu = log_uniform(rng, self.mu);
        let lambda = uniform(rng, self.lambda);
        let bending = log_uniform(rng, self.bending);
        let density = uniform(rng, self.density);
        self.material(density, mu, lambda, bending)
    }

    /// The softest and lightest (`0`) or the stiffest and heaviest (`1`) corner.
    pub fn corner(&self, end: usize) -> Material {
        self.material(
            self.density[end],
            self.mu[end],
            self.lambda[end],
            self.bending[end],
        )
    }

    fn material(&self, density: f64, mu: f64, lambda: f64, bending: f64) -> Material {
        let hood = Material::hood();
        Material::from_lame(
            "custom",
            density,
            mu,
            lambda,
            self.thickness,
            bending,
            hood.friction,
        )
    }

    /// The network's material inputs, HOOD's raw features in HOOD's order
    /// `[k_b, μ, λ]` (their node and edge features end with "bending, μ, λ"): each
    /// value's position in its range, `(ln v − ln lo)/(ln hi − ln lo)` for `k_b` and
    /// `μ`, `(v − lo)/(hi − lo)` for `λ` (0 where a range is one value). `μ`, `λ` are
    /// the plane-stress Lamé parameters ([`Material::lame`]) scaled to the ranges'
    /// thickness (type docs). Range ends map to 0 and 1; values outside map outside
    /// `[0, 1]` on the same line, where the network was never trained
    /// ([`MaterialRanges::outside`]); `k_b = 0` maps to `−∞`. Density is not an input
    /// (it enters through the vertex masses).
    pub fn inputs(&self, material: &Material) -> [f64; 3] {
        let (mu, lambda) = self.membrane(material);
        [
            log_position(material.bending_stiffness, self.bending),
            log_position(mu, self.mu),
            position(lambda, self.lambda),
        ]
    }

    /// `material`'s `μ`, `λ` at the ranges' thickness.
    fn membrane(&self, material: &Material) -> (f64, f64) {
        let (mu, lambda) = material.lame();
        let scale = material.thickness / self.thickness;
        (mu * scale, lambda * scale)
    }

    /// What of `material` lies outside the ranges (the network's inputs or the density
    /// it was trained on), one phrase per value, e.g. `μ 245.499 kPa (trained 15.909
    /// kPa to 63.636 kPa)`; empty when all lie inside (to 0.1 %).
    pub fn outside(&self, material: &Material) -> Vec<String> {
        let (mu, lambda) = self.membrane(material);
        let kpa = |v: f64| format!("{:.3} kPa", v / 1e3);
        let bend = |v: f64| format!("{v:.3e} N·m");
        let per_m2 = |v: f64| format!("{v:.3} kg/m²");
        [
            ("μ", mu, self.mu, &kpa as &dyn Fn(f64) -> String),
            ("λ", lambda, self.lambda, &kpa),
            ("k_b", material.bending_stiffness, self.bending, &bend),
            ("density", material.density, self.density, &per_m2),
        ]
        .into_iter()
        // Slack of 0.1 %: a range end written as a rounded `E`, `ν` is not outside.
        .filter(|(_, v, [lo, hi], _)| *v < lo * (1.0 - 1e-3) || *v > hi * (1.0 + 1e-3))
        .map(|(name, v, [lo, hi], show)| {
            format!("{name} {} (trained {} to {})", show(v), show(lo), show(hi))
        })
        .collect()
    }
}

/// A seeded stream of training materials from one [`MaterialRanges`].
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSampler {
    rng: SplitMix64,
    ranges: MaterialRanges,
}

impl MaterialSampler {
    /// A sampler of `ranges` whose stream is fixed by `seed`.
    pub fn new(seed: u64, ranges: MaterialRanges) -> Self {
        MaterialSampler {
            rng: SplitMix64::new(seed),
            ranges,
        }
    }

    /// The next material.
    pub fn sample(&mut self) -> Material {
        self.ranges.sample(&mut self.rng)
    }
}

fn uniform(rng: &mut SplitMix64, [lo, hi]: [f64; 2]) -> f64 {
    rng.uniform(lo, hi).clamp(lo, hi)
}

/// `exp` of a uniform draw in `[ln lo, ln hi)`, clamped to `[lo, hi]` against rounding.
fn log_uniform(rng: &mut SplitMix64, [lo, hi]: [f64; 2]) -> f64 {
    rng.uniform(lo.ln(), hi.ln()).exp().clamp(lo, hi)
}

fn position(v: f64, [lo, hi]: [f64; 2]) -> f64 {
    if hi > lo {
        (v - lo) / (hi - lo)
    } else {
        0.0
    }
}

fn log_position(v: f64, [lo, hi]: [f64; 2]) -> f64 {
    position(v.ln(), [lo.ln(), hi.ln()])
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
        let mut s = MaterialSampler::new(7, MaterialRanges::hood());
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
            for x in MaterialRanges::hood().inputs(m) {
                assert!((-1e-9..=1.0 + 1e-9).contains(&x), "{m:?}");
            }
        }
        let mut again = MaterialSampler::new(7, MaterialRanges::hood());
        assert!(draws.iter().all(|m| *m == again.sample()));
        let other = MaterialSampler::new(8, MaterialRanges::hood()).sample();
        assert_ne!(other, draws[0]);
        // The ranges' own sampling on the same generator is the same stream.
        let mut rng = SplitMix64::new(7);
        assert_eq!(MaterialRanges::hood().sample(&mut rng), draws[0]);
    }

    /// The distributions: log-uniform μ and k_b have their median at the geometric mean
    /// of the range, uniform λ and density at the arithmetic mean; every input spreads
    /// over [0, 1] uniformly (mean ½).
    #[test]
    fn distributions_are_hoods() {
        let mut s = MaterialSampler::new(1, MaterialRanges::hood());
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
            let mean = draws
                .iter()
                .map(|m| MaterialRanges::hood().inputs(m)[k])
                .sum::<f64>()
                / n as f64;
            assert!((mean - 0.5).abs() < 0.01, "input {k}: mean {mean}");
        }
    }

    /// The range ends map to 0 and 1, HOOD's default material inside, values beyond the
    /// range outside [0, 1].
    #[test]
    fn inputs_map_the_range_ends_to_0_and_1() {
        let at = |mu: f64, lambda: f64, kb: f64| {
            MaterialRanges::hood().inputs(&Material::from_lame(
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
        let hood = MaterialRanges::hood().inputs(&Material::hood());
        assert!(hood.iter().all(|x| (0.0..1.0).contains(x)), "{hood:?}");
        // λ = 44 400 is (44 400 − 3 535.41)/(93 333.74 − 3 535.41) along its range.
        assert!((hood[2] - 0.455_070_712_3).abs() < 1e-9, "{hood:?}");
        let beyond = at(2.0 * HOOD_MU_RANGE[1], 0.0, 0.5 * HOOD_BENDING_RANGE[0]);
        assert!(
            beyond[0] < 0.0 && beyond[1] > 1.0 && beyond[2] < 0.0,
            "{beyond:?}"
        );
    }

    /// A material is placed by its membrane stiffness `μ·h`, `λ·h`: the same Lamé
    /// parameters at a third of the thickness sit where a third of them do at the
    /// ranges' thickness. Silk lies above HOOD's ranges and is reported so, HOOD's own
    /// material inside; ranges that reach silk's take it in.
    #[test]
    fn inputs_follow_the_membrane_stiffness_and_outside_names_the_values() {
        let r = MaterialRanges::hood();
        let h = r.thickness;
        let thin = Material::from_lame("custom", 0.2, 45_000.0, 60_000.0, h / 3.0, 1e-5, 0.5);
        let soft = Material::from_lame("custom", 0.2, 15_000.0, 20_000.0, h, 1e-5, 0.5);
        let (a, b) = (r.inputs(&thin), r.inputs(&soft));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-9, "{a:?} {b:?}");
        }
        assert!(r.outside(&Material::hood()).is_empty());
        let silk = r.outside(&Material::silk());
        assert_eq!(silk.len(), 2, "{silk:?}");
        assert!(
            silk[0].starts_with("μ 245.") && silk[0].contains("trained 15.909 kPa to 63.636 kPa"),
            "{silk:?}"
        );
        assert!(silk[1].starts_with("λ 210."), "{silk:?}");
        let wide = MaterialRanges {
            mu: [15_909.0, 300_000.0],
            lambda: [3_535.41, 300_000.0],
            ..r
        };
        wide.validate().unwrap();
        assert!(wide.outside(&Material::silk()).is_empty());
        let x = wide.inputs(&Material::silk());
        assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "{x:?}");
        // Corners are the range ends, and their inputs 0 and 1.
        for end in 0..2 {
            let c = wide.corner(end);
            assert!(wide.outside(&c).is_empty(), "{c:?}");
            for v in wide.inputs(&c) {
                assert!((v - end as f64).abs() < 1e-9, "{c:?}");
            }
        }
    }

    #[test]
    fn bad_ranges_name_the_field() {
        let r = MaterialRanges::hood();
        let cases = [
            (
                MaterialRanges {
                    mu: [2.0, 1.0],
                    ..r
                },
                "materials.mu",
            ),
            (
                MaterialRanges {
                    lambda: [-1.0, 1.0],
                    ..r
                },
                "materials.lambda",
            ),
            (
                MaterialRanges {
                    bending: [0.0, 1.0],
                    ..r
                },
                "materials.bending",
            ),
            (
                MaterialRanges {
                    density: [0.1, f64::NAN],
                    ..r
                },
                "materials.density",
            ),
            (
                MaterialRanges {
                    thickness: 0.0,
                    ..r
                },
                "materials.thickness",
            ),
        ];
        for (bad, field) in cases {
            let e = bad.validate().unwrap_err();
            assert!(e.starts_with(field), "{e}");
        }
        r.validate().unwrap();
        // One-value ranges are allowed: every sample is that value, its input 0.
        let point = MaterialRanges {
            mu: [20_000.0; 2],
            ..r
        };
        point.validate().unwrap();
        let m = point.sample(&mut SplitMix64::new(1));
        assert!((m.lame().0 - 20_000.0).abs() < 1e-6);
        assert_eq!(point.inputs(&m)[1], 0.0);
    }
}
