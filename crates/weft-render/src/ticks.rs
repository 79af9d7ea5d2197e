//! Axis and colour-bar ticks: "nice" round values (1, 2, 5 × 10^k steps) and labels with
//! just enough digits to tell neighbouring ticks apart.

/// A step of 1, 2 or 5 × 10^k close to `span / target`.
pub(crate) fn nice_step(span: f64, target: usize) -> f64 {
    let raw = span / target.max(1) as f64;
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f < 1.5 {
        1.0
    } else if f < 3.0 {
        2.0
    } else if f < 7.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Multiples of a nice step inside `[lo, hi]` (about `target` of them), and the step.
pub(crate) fn linear(lo: f64, hi: f64, target: usize) -> (Vec<f64>, f64) {
    let step = nice_step(hi - lo, target);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    let ticks = (first..=last.min(first + 1000))
        .map(|k| {
            let v = k as f64 * step;
            // Multiples of 0.1 carry rounding noise; zero must print as 0, not -0.
            if v == 0.0 {
                0.0
            } else {
                v
            }
        })
        .collect();
    (ticks, step)
}

/// Powers of ten inside `[lo, hi]` (both > 0), thinned to at most about 8 labels.
pub(crate) fn decades(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return Vec::new();
    }
    let a = (lo.log10() - 1e-9).ceil() as i32;
    let b = (hi.log10() + 1e-9).floor() as i32;
    let every = ((b - a) / 8 + 1).max(1);
    (a..=b)
        .filter(|e| (e - a) % every == 0)
        .map(|e| 10f64.powi(e))
        .collect()
}

/// A label for a power of ten on a log axis: `0.01`, `0.1`, `1`, `10`, `100`, else `1e-5`.
pub(crate) fn decade(v: f64) -> String {
    let e = v.log10().round() as i32;
    match e {
        -2..=-1 => format!("{:.*}", (-e) as usize, v),
        0..=2 => format!("{}", 10i32.pow(e as u32)),
        _ => format!("1e{e}"),
    }
}

/// A tick label for `v` on an axis with tick spacing `step`: fixed-point with as many
/// decimals as the step needs, scientific for very large or very small magnitudes.
pub(crate) fn label(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-4..1e6).contains(&a) || !(step.abs() >= 1e-4 || step == 0.0) {
        return sci(v);
    }
    let decimals = if step > 0.0 && step.is_finite() {
        (-(step.log10() + 1e-9).floor()).clamp(0.0, 6.0) as usize
    } else {
        2
    };
    format!("{v:.decimals$}")
}

/// Scientific notation with up to 3 significant digits: `1.5e-5`, `2e3`.
pub(crate) fn sci(v: f64) -> String {
    let s = format!("{v:.2e}");
    // Trim trailing zeros of the mantissa: 1.50e-5 -> 1.5e-5, 2.00e3 -> 2e3.
    match s.split_once('e') {
        Some((m, e)) => {
            let m = if m.contains('.') {
                m.trim_end_matches('0').trim_end_matches('.')
            } else {
                m
            };
            format!("{m}e{e}")
        }
        None => s,
    }
}

/// A short label for a value on its own (legend ends, means): 3 significant digits.
pub(crate) fn value(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        sci(v)
    } else {
        let decimals = (2 - a.log10().floor() as i32).clamp(0, 6) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_linear_ticks() {
        let (t, s) = linear(0.0, 10.0, 5);
        assert_eq!(s, 2.0);
        assert_eq!(t, vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        let (t, s) = linear(-0.013, 0.027, 4);
        assert_eq!(s, 0.01);
        let labels: Vec<_> = t.iter().map(|&v| label(v, s)).collect();
        assert_eq!(labels, ["-0.01", "0", "0.01", "0.02"]);
        assert_eq!(linear(0.0, 0.0, 5).0, vec![0.0]);
    }

    #[test]
    fn log_decades() {
        assert_eq!(decades(0.003, 20.0), vec![0.01, 0.1, 1.0, 10.0]);
        assert!(decades(0.0, 1.0).is_empty());
        assert!(decades(1e-30, 1e30).len() <= 9);
        let l: Vec<_> = [1e-3, 0.01, 0.1, 1.0, 10.0, 100.0, 1e3].map(decade).into();
        assert_eq!(l, ["1e-3", "0.01", "0.1", "1", "10", "100", "1e3"]);
    }

    #[test]
    fn labels() {
        assert_eq!(label(2500.0, 500.0), "2500");
        assert_eq!(label(0.25, 0.05), "0.25");
        assert_eq!(label(1e-5, 1e-5), "1e-5");
        assert_eq!(label(2e7, 1e7), "2e7");
        assert_eq!(sci(1.5e-5), "1.5e-5");
        assert_eq!(value(12.3456), "12.3");
        assert_eq!(value(0.012345), "0.0123");
        assert_eq!(value(4.0), "4");
        assert_eq!(value(123456.0), "1.23e5");
    }
}
