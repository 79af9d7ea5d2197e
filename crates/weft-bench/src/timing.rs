//! The timer of every bench: one warm-up run, then the median of `reps` runs. The median,
//! not the mean, because this machine is shared: a neighbour's build lengthens a few runs
//! and the median ignores them.

use std::time::Instant;

/// Median wall time of `reps` (at least 1) runs of `f` after one warm-up run, in ms.
pub fn median_ms(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut times: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Median of `reps` fallible runs, as [`median_ms`]; the first error stops it.
pub fn try_median_ms<E>(reps: usize, mut f: impl FnMut() -> Result<(), E>) -> Result<f64, E> {
    let mut error = None;
    let ms = median_ms(reps, || {
        if error.is_none() {
            if let Err(e) = f() {
                error = Some(e);
            }
        }
    });
    match error {
        Some(e) => Err(e),
        None => Ok(ms),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_ignores_one_slow_run() {
        let mut n = 0;
        let ms = median_ms(5, || {
            n += 1;
            // Run 3 (the second timed one) sleeps 50 ms; the others return at once.
            if n == 3 {
                std::thread::sleep(std::time::Duration::from_millis(50));
            }
        });
        assert_eq!(n, 6, "one warm-up and five timed runs");
        assert!(ms < 25.0, "{ms} ms");
    }

    #[test]
    fn an_error_stops_the_timing() {
        let mut n = 0;
        let r = try_median_ms(5, || {
            n += 1;
            if n == 2 {
                Err("second run")
            } else {
                Ok(())
            }
        });
        assert_eq!(r, Err("second run"));
    }
}
