//! Macro settings ("phenotypes") and how they weight MakeHuman's macro targets, by the
//! rules of MakeHuman itself (`targets/macrodetails/macro.json` in the data, and
//! MakeHuman's `human.py`):
//!
//! - each setting is a number in [0, 1] interpolated piecewise linearly between
//!   **anchors**, giving one weight per variation: gender (female 0, male 1), age
//!   (baby 0, child 0.1875, young 0.5 = 25 years, old 1 = 90 years), muscle and weight
//!   (min 0, average 0.5, max 1), height (min 0, *none* 0.5, max 1), proportions
//!   (uncommon 0, *none* 0.5, ideal 1); *none* is a variation without a target, so a
//!   setting of 0.5 leaves the body's height and proportions as the other macros make
//!   them;
//! - race weights are 1/3 each (MakeHuman's default);
//! - a target named by variations (e.g. `universal-female-young-maxmuscle-averageweight`)
//!   is applied with the **product** of their weights.
//!
//! The families are `universal-G-A-M-W`, `RACE-G-A`, `height/G-A-M-W-H` and
//! `proportions/G-A-M-W-P` (not for babies), the ones `anny` loads too. anny
//! (anny/models/phenotype.py) differs in its anchors: it puts height and proportions on
//! two anchors (min 0, max 1), so 0.5 applies half of each target, which makes average
//! adults about 1.9 m tall, and it adds a scaled-down "newborn" age. weft follows
//! MakeHuman's rules, whose 0.5 settings give a 1.59 m woman and a 1.73 m man. Breast size
//! and firmness stay at their defaults (0.5), where the breast targets add nothing.

use std::path::PathBuf;

/// The variations of each setting, in anchor order.
pub const GENDERS: [&str; 2] = ["female", "male"];
/// Age variations.
pub const AGES: [&str; 4] = ["baby", "child", "young", "old"];
/// Muscle variations.
pub const MUSCLES: [&str; 3] = ["minmuscle", "averagemuscle", "maxmuscle"];
/// Weight variations.
pub const WEIGHTS: [&str; 3] = ["minweight", "averageweight", "maxweight"];
/// Height variations.
pub const HEIGHTS: [&str; 2] = ["minheight", "maxheight"];
/// Proportion variations (low, high).
pub const PROPORTIONS: [&str; 2] = ["uncommonproportions", "idealproportions"];
/// Race variations.
pub const RACES: [&str; 3] = ["african", "asian", "caucasian"];

/// One macro setting of the body, each in `[0, 1]` (age: see the anchors above).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phenotype {
    /// 0 female … 1 male.
    pub gender: f64,
    /// 0 baby, 0.1875 child, 0.5 young adult (25 years), 1 old (90 years).
    pub age: f64,
    /// 0 minimal … 1 maximal muscle.
    pub muscle: f64,
    /// 0 minimal … 1 maximal weight.
    pub weight: f64,
    /// 0 minimal, 0.5 no height target, 1 maximal height.
    pub height: f64,
    /// 0 uncommon, 0.5 no proportions target, 1 ideal proportions.
    pub proportions: f64,
}

impl Default for Phenotype {
    /// MakeHuman's defaults: every setting 0.5 (a 25-year-old of average build).
    fn default() -> Self {
        Phenotype {
            gender: 0.5,
            age: 0.5,
            muscle: 0.5,
            weight: 0.5,
            height: 0.5,
            proportions: 0.5,
        }
    }
}

/// Weights of the variations for `value` interpolated piecewise linearly between
/// `anchors` (increasing positions; clamped at the ends). Returns one weight per
/// anchor; callers ignore the anchors that have no target.
pub fn interpolate(value: f64, anchors: &[f64]) -> Vec<f64> {
    let n = anchors.len();
    let mut w = vec![0.0; n];
    if n == 1 {
        w[0] = 1.0;
        return w;
    }
    let x = value.clamp(anchors[0], anchors[n - 1]);
    let i = (0..n - 1).find(|&i| x <= anchors[i + 1]).unwrap_or(n - 2);
    let alpha = (x - anchors[i]) / (anchors[i + 1] - anchors[i]);
    w[i] = 1.0 - alpha;
    w[i + 1] = alpha;
    w
}

/// Anchors of the settings (see the module docs).
const TWO: [f64; 2] = [0.0, 1.0];
const THREE: [f64; 3] = [0.0, 0.5, 1.0];
const AGE_ANCHORS: [f64; 4] = [0.0, 0.1875, 0.5, 1.0];

/// A macro target file (relative to `targets/macrodetails`) and its weight.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightedTarget {
    /// Path relative to the macrodetails directory.
    pub file: PathBuf,
    /// The product of the variation weights.
    pub weight: f64,
}

impl Phenotype {
    /// Every macro target with its weight for this setting (zero weights included, so
    /// the list is the same for every setting).
    pub fn targets(&self) -> Vec<WeightedTarget> {
        let g = interpolate(self.gender, &TWO);
        let a = interpolate(self.age, &AGE_ANCHORS);
        let m = interpolate(self.muscle, &THREE);
        let w = interpolate(self.weight, &THREE);
        // Height and proportions: the middle anchor has no target.
        let h3 = interpolate(self.height, &THREE);
        let h = [h3[0], h3[2]];
        let p3 = interpolate(self.proportions, &THREE);
        let p = [p3[0], p3[2]];
        let race = 1.0 / 3.0;
        let mut out = Vec::new();
        for (gi, gn) in GENDERS.iter().enumerate() {
            for (ai, an) in AGES.iter().enumerate() {
                for (mi, mn) in MUSCLES.iter().enumerate() {
                    for (wi, wn) in WEIGHTS.iter().enumerate() {
                        let base = g[gi] * a[ai] * m[mi] * w[wi];
                        out.push(WeightedTarget {
                            file: format!("universal-{gn}-{an}-{mn}-{wn}.target.gz").into(),
                            weight: base,
                        });
                        for (hi, hn) in HEIGHTS.iter().enumerate() {
                            out.push(WeightedTarget {
                                file: PathBuf::from("height")
                                    .join(format!("{gn}-{an}-{mn}-{wn}-{hn}.target.gz")),
                                weight: base * h[hi],
                            });
                        }
                        if *an != "baby" {
                            for (pi, pn) in PROPORTIONS.iter().enumerate() {
                                out.push(WeightedTarget {
                                    file: PathBuf::from("proportions")
                                        .join(format!("{gn}-{an}-{mn}-{wn}-{pn}.target.gz")),
                                    weight: base * p[pi],
                                });
                            }
                        }
                    }
                }
                for rn in RACES {
                    out.push(WeightedTarget {
                        file: format!("{rn}-{gn}-{an}.target.gz").into(),
                        weight: race * g[gi] * a[ai],
                    });
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_piecewise_linear() {
        assert_eq!(interpolate(0.5, &THREE), vec![0.0, 1.0, 0.0]);
        assert_eq!(interpolate(0.25, &THREE), vec![0.5, 0.5, 0.0]);
        assert_eq!(interpolate(1.0, &THREE), vec![0.0, 0.0, 1.0]);
        assert_eq!(interpolate(1.7, &TWO), vec![0.0, 1.0]);
        assert_eq!(interpolate(-1.0, &TWO), vec![1.0, 0.0]);
        let a = interpolate(0.8, &AGE_ANCHORS);
        assert!((a[2] - 0.4).abs() < 1e-12 && (a[3] - 0.6).abs() < 1e-12);
        let a = interpolate(0.1875, &AGE_ANCHORS);
        assert!((a[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn target_weights_are_products_of_the_settings() {
        let p = Phenotype {
            gender: 0.3,
            age: 0.75,
            muscle: 0.2,
            weight: 0.9,
            height: 0.6,
            proportions: 0.5,
        };
        let t = p.targets();
        // 2 genders × 4 ages × 9 (muscle, weight) × (1 + 2 heights) + proportions for 3
        // ages × 2, + 3 races × 2 × 4.
        assert_eq!(t.len(), 2 * 4 * 9 * 3 + 2 * 3 * 9 * 2 + 3 * 2 * 4);
        let sum = |prefix: &str| -> f64 {
            t.iter()
                .filter(|x| x.file.to_string_lossy().starts_with(prefix))
                .map(|x| x.weight)
                .sum()
        };
        assert!((sum("universal") - 1.0).abs() < 1e-12);
        // Height 0.6 applies 20 % of maxheight; proportions 0.5 nothing.
        assert!((sum("height") - 0.2).abs() < 1e-12);
        assert!(sum("proportions").abs() < 1e-12);
        let f = t
            .iter()
            .find(|x| {
                x.file.to_string_lossy() == "universal-female-young-minmuscle-maxweight.target.gz"
            })
            .unwrap();
        // gender 0.3 → female 0.7; age 0.75 → young 0.5; muscle 0.2 → min 0.6; weight 0.9 → max 0.8.
        assert!((f.weight - 0.7 * 0.5 * 0.6 * 0.8).abs() < 1e-12);
    }
}
