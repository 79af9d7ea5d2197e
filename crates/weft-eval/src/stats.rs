//! Mean ± standard deviation over many samples, accumulated in one pass.
//!
//! Table 1 of seed 000 reports every error as "mean (± std)" over all vertices of all test
//! frames: millions of samples for a real test split. Welford's update keeps the running
//! mean and the sum of squared deviations, so the accumulator is O(1) memory and stays
//! accurate where the naive `E[x²] − E[x]²` loses every digit (errors of a few mm on
//! values that are all about the same). Two accumulators merge exactly (Chan et al.), so
//! per-garment-kind summaries can be combined into the overall one.

use serde::{Deserialize, Serialize};

/// Running statistics of a stream of finite `f64` samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Accumulator {
    count: u64,
    mean: f64,
    m2: f64,
    min: f64,
    max: f64,
}

impl Accumulator {
    /// No samples yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one sample. Non-finite samples are not added (a caller that can produce
    /// them counts them separately, see [`crate::metrics`]).
    pub fn push(&mut self, x: f64) {
        if !x.is_finite() {
            return;
        }
        if self.count == 0 {
            self.min = x;
            self.max = x;
        } else {
            self.min = self.min.min(x);
            self.max = self.max.max(x);
        }
        self.count += 1;
        let d = x - self.mean;
        self.mean += d / self.count as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Adds every sample of `xs`.
    pub fn extend(&mut self, xs: impl IntoIterator<Item = f64>) {
        for x in xs {
            self.push(x);
        }
    }

    /// Adds all samples of `other` (exact pairwise merge).
    pub fn merge(&mut self, other: &Accumulator) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 {
            *self = *other;
            return;
        }
        let n = (self.count + other.count) as f64;
        let d = other.mean - self.mean;
        self.mean += d * other.count as f64 / n;
        self.m2 += other.m2 + d * d * self.count as f64 * other.count as f64 / n;
        self.count += other.count;
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    /// Number of samples.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The summary so far (all zeros without samples).
    pub fn summary(&self) -> Summary {
        Summary {
            mean: self.mean,
            // Population standard deviation: the spread of the errors themselves, as the
            // paper's "± std" over all vertices, not an estimate of a wider population.
            std: if self.count > 0 {
                (self.m2 / self.count as f64).max(0.0).sqrt()
            } else {
                0.0
            },
            min: self.min,
            max: self.max,
            count: self.count,
        }
    }
}

/// Mean, standard deviation (population), extremes and sample count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Arithmetic mean.
    pub mean: f64,
    /// Population standard deviation.
    pub std: f64,
    /// Smallest sample.
    pub min: f64,
    /// Largest sample.
    pub max: f64,
    /// Number of samples.
    pub count: u64,
}

impl Summary {
    /// `mean (± std)` with `digits` decimals, the paper's Table 1 format; `–` without
    /// samples.
    pub fn mean_std(&self, digits: usize) -> String {
        if self.count == 0 {
            return "–".to_owned();
        }
        format!("{:.*} (± {:.*})", digits, self.mean, digits, self.std)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn naive(xs: &[f64]) -> (f64, f64) {
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        (mean, var.sqrt())
    }

    #[test]
    fn matches_two_pass_formula() {
        let xs = [1.0, 2.0, 4.0, 8.0, 16.0];
        let mut a = Accumulator::new();
        a.extend(xs);
        let s = a.summary();
        let (m, sd) = naive(&xs);
        assert!((s.mean - m).abs() < 1e-12);
        assert!((s.std - sd).abs() < 1e-12);
        assert_eq!((s.min, s.max, s.count), (1.0, 16.0, 5));
    }

    #[test]
    fn stays_accurate_on_large_offsets() {
        // Errors of ±1 around 1e9: E[x²] − E[x]² would cancel to garbage.
        let mut a = Accumulator::new();
        for k in 0..1000 {
            a.push(1e9 + if k % 2 == 0 { 1.0 } else { -1.0 });
        }
        assert!((a.summary().std - 1.0).abs() < 1e-6);
    }

    #[test]
    fn skips_non_finite_and_empty_is_zero() {
        let mut a = Accumulator::new();
        assert_eq!(a.summary().mean_std(2), "–");
        a.extend([f64::NAN, 3.0, f64::INFINITY]);
        assert_eq!(a.count(), 1);
        assert_eq!(a.summary().mean_std(2), "3.00 (± 0.00)");
    }

    proptest! {
        #[test]
        fn merge_equals_one_stream(xs in prop::collection::vec(-1e3f64..1e3, 1..60), split in 0usize..60) {
            let split = split.min(xs.len());
            let mut whole = Accumulator::new();
            whole.extend(xs.iter().copied());
            let (mut a, mut b) = (Accumulator::new(), Accumulator::new());
            a.extend(xs[..split].iter().copied());
            b.extend(xs[split..].iter().copied());
            a.merge(&b);
            let (w, m) = (whole.summary(), a.summary());
            prop_assert_eq!(w.count, m.count);
            prop_assert!((w.mean - m.mean).abs() < 1e-9);
            prop_assert!((w.std - m.std).abs() < 1e-7);
            prop_assert_eq!((w.min, w.max), (m.min, m.max));
        }
    }
}
