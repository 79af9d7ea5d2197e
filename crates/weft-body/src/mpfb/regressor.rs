//! Joint regressors: each joint as a convex combination (non-negative weights summing
//! to 1) of body vertices, fitted to the joint positions of many shapes.
//!
//! MPFB places most joints at the centres of helper cubes that are not part of the
//! body mesh, so `J_regressor` cannot simply average the rig's own vertices. Instead,
//! for each joint we take the body vertices near it and solve
//! `min_w Σ_s ‖Σ_i w_i v_i^s − J^s‖²` over the probability simplex (projected gradient
//! with Nesterov momentum), across all sampled shapes `s`. Convexity keeps the joint
//! inside the body and makes it follow translations exactly, as SMPL's regressor does.

use nalgebra::{DMatrix, DVector};

/// Candidate vertices for a joint at `p`: the nearest vertices, taken in order of
/// distance until they **surround** the joint (for each of 26 directions — the axes,
/// the face and the corner diagonals of a cube — some candidate lies within about 45°
/// of it) and number at least `min`; at most `max`. A joint near the back surface (the
/// spine) then also gets belly vertices, so a convex combination can reach it.
pub fn candidates(p: [f64; 3], vertices: &[[f64; 3]], min: usize, max: usize) -> Vec<u32> {
    let mut d: Vec<(f64, u32)> = vertices
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let s: f64 = (0..3).map(|k| (v[k] - p[k]).powi(2)).sum();
            (s.sqrt(), i as u32)
        })
        .collect();
    d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut dirs = Vec::new();
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) != (0, 0, 0) {
                    let n = f64::from(x * x + y * y + z * z).sqrt();
                    dirs.push([f64::from(x) / n, f64::from(y) / n, f64::from(z) / n]);
                }
            }
        }
    }
    let mut covered = vec![false; dirs.len()];
    let mut n = 0;
    for &(dist, i) in &d {
        if n >= max || (n >= min && covered.iter().all(|&c| c)) {
            break;
        }
        n += 1;
        if dist > 0.0 {
            let v = vertices[i as usize];
            let u = [0, 1, 2].map(|k| (v[k] - p[k]) / dist);
            for (c, dir) in covered.iter_mut().zip(&dirs) {
                *c |=
                    u[0] * dir[0] + u[1] * dir[1] + u[2] * dir[2] > std::f64::consts::FRAC_1_SQRT_2;
            }
        }
    }
    d[..n].iter().map(|x| x.1).collect()
}

/// Fits simplex weights over `cand` so that, for every sample `s`, the weighted mean of
/// `samples[s][cand]` is as close as possible to `targets[s]`. Returns the weights
/// and the RMS residual (same units as the positions).
pub fn fit(
    cand: &[u32],
    samples: &[Vec<[f64; 3]>],
    targets: &[[f64; 3]],
    iterations: usize,
) -> (Vec<f64>, f64) {
    let k = cand.len();
    // Normal equations of the least-squares objective: G = AᵀA, c = Aᵀb.
    let mut g = DMatrix::<f64>::zeros(k, k);
    let mut c = DVector::<f64>::zeros(k);
    let mut bb = 0.0;
    for (vs, t) in samples.iter().zip(targets) {
        for dim in 0..3 {
            let a: Vec<f64> = cand.iter().map(|&i| vs[i as usize][dim]).collect();
            for i in 0..k {
                c[i] += a[i] * t[dim];
                for j in 0..k {
                    g[(i, j)] += a[i] * a[j];
                }
            }
            bb += t[dim] * t[dim];
        }
    }
    // Step 1/L with L the largest eigenvalue of G (power iteration, then a margin).
    let mut x = DVector::from_element(k, 1.0 / (k as f64).sqrt());
    let mut l = 0.0;
    for _ in 0..100 {
        let y = &g * &x;
        l = y.norm();
        if l == 0.0 {
            break;
        }
        x = y / l;
    }
    let step = 1.0 / (l * 1.01).max(1e-300);
    let mut w = DVector::from_element(k, 1.0 / k as f64);
    let mut y = w.clone();
    let mut t = 1.0f64;
    for _ in 0..iterations {
        let grad = &g * &y - &c;
        let w_next = project_simplex(&(&y - grad * step));
        let t_next = (1.0 + (1.0 + 4.0 * t * t).sqrt()) / 2.0;
        y = &w_next + (&w_next - &w) * ((t - 1.0) / t_next);
        w = w_next;
        t = t_next;
    }
    // Residual: wᵀGw − 2cᵀw + bᵀb over 3S coordinates... as RMS per joint position.
    let r2 = (w.dot(&(&g * &w)) - 2.0 * c.dot(&w) + bb).max(0.0);
    let rms = (r2 / samples.len().max(1) as f64).sqrt();
    (w.iter().copied().collect(), rms)
}

/// Euclidean projection onto `{w ≥ 0, Σ w = 1}` (sort-based, Held et al.).
pub fn project_simplex(v: &DVector<f64>) -> DVector<f64> {
    let mut u: Vec<f64> = v.iter().copied().collect();
    u.sort_by(|a, b| b.total_cmp(a));
    let mut cum = 0.0;
    let mut theta = 0.0;
    for (i, &ui) in u.iter().enumerate() {
        cum += ui;
        let t = (cum - 1.0) / (i + 1) as f64;
        if ui - t > 0.0 {
            theta = t;
        }
    }
    v.map(|x| (x - theta).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_lands_on_the_simplex() {
        let p = project_simplex(&DVector::from_vec(vec![0.5, 2.0, -1.0]));
        assert!((p.sum() - 1.0).abs() < 1e-12 && p.iter().all(|&x| x >= 0.0));
        assert_eq!(p, DVector::from_vec(vec![0.0, 1.0, 0.0]));
        let q = project_simplex(&DVector::from_vec(vec![0.2, 0.3, 0.5]));
        assert!((q - DVector::from_vec(vec![0.2, 0.3, 0.5])).norm() < 1e-12);
    }

    #[test]
    fn recovers_the_centre_of_a_ring_across_shapes() {
        // A ring of 8 points around a centre that moves and scales with the "shape".
        let mut samples = Vec::new();
        let mut targets = Vec::new();
        for s in 0..5 {
            let c = [0.1 * f64::from(s), 1.0, -0.2 * f64::from(s)];
            let r = 0.1 + 0.02 * f64::from(s);
            let ring: Vec<[f64; 3]> = (0..8)
                .map(|i| {
                    let a = std::f64::consts::TAU * f64::from(i) / 8.0;
                    [c[0] + r * a.cos(), c[1] + r * a.sin(), c[2]]
                })
                .collect();
            samples.push(ring);
            targets.push(c);
        }
        let cand = candidates(targets[0], &samples[0], 4, 16);
        assert_eq!(cand.len(), 8);
        let (w, rms) = fit(&cand, &samples, &targets, 3000);
        assert!(rms < 1e-6, "{rms}");
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    }
}
