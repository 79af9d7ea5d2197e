//! Projected Newton on the incremental potential.
//!
//! Each iteration: gradient `g` (zero on pinned vertices), the Hessian with each
//! element block projected to PSD (so with the mass term `M/h²` the matrix is positive
//! definite on the free vertices and the direction is a descent direction), the
//! direction `d` from PCG (`H d = −g`, pinned rows replaced by the identity), then a
//! backtracking line search from `α = 1` halving until the Armijo condition
//! `E(x + αd) <= E(x) + c α gᵀd` holds. The energy therefore decreases monotonically;
//! the report records it per iteration. Convergence: the accepted step's largest vertex
//! displacement falls below `tolerance` (IPC's criterion `‖Δx‖∞ / h < ε_v` written as a
//! length).

use crate::energy::{Energy, HessianKind};
use crate::error::{check_len, SimError};
use crate::potential::IncrementalPotential;
use crate::solver::pcg::{pcg_with, BlockJacobi, Preconditioner};
use crate::solver::two_level::{Aggregates, TwoLevel};
use crate::sparse::BlockCsr;

/// Newton's stopping and inner-solve parameters. A TOML table sets any of them; the
/// others keep the defaults stated on each field.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NewtonOptions {
    /// At most this many Newton iterations. Default: 50.
    pub max_iterations: usize,
    /// Converged when the largest vertex displacement of a step is below this, m.
    /// Default: 1e-5 m.
    pub tolerance: f64,
    /// Relative residual of the PCG solve (unitless). Default: 1e-3.
    pub cg_rtol: f64,
    /// At most this many PCG iterations per Newton iteration. Default: 1000.
    pub cg_max_iterations: usize,
    /// Armijo constant `c` (unitless). Default: 1e-4.
    pub armijo: f64,
    /// At most this many step halvings. Default: 30.
    pub max_halvings: usize,
    /// Newton's matrix: [`HessianKind::Surrogate`] (default: no element eigen-
    /// decompositions, measured fastest per step) or [`HessianKind::Projected`].
    pub hessian: HessianKind,
    /// Loosest PCG relative residual of the forcing sequence: iteration `k` solves to
    /// `max(cg_rtol, min(cg_rtol_loose, ‖g_k‖∞/‖g_0‖∞))`, so early iterations, far
    /// from the minimum, take a rough direction cheaply (inexact Newton,
    /// Eisenstat–Walker). Set it equal to `cg_rtol` for a fixed tolerance. Default: 1e-2.
    pub cg_rtol_loose: f64,
    /// PCG's preconditioner. Default: [`PreconditionerKind::TwoLevel`].
    pub preconditioner: PreconditionerKind,
}

/// Which preconditioner PCG uses (in TOML: `block_jacobi`, `two_level`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PreconditionerKind {
    /// The inverses of the 3×3 diagonal blocks.
    BlockJacobi,
    /// Block Jacobi plus an exact solve on aggregates of about 60 vertices
    /// ([`TwoLevel`]): fewer PCG iterations for a small factorisation per Newton
    /// iteration (measured in docs/physics.md).
    #[default]
    TwoLevel,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            max_iterations: 50,
            tolerance: 1e-5,
            cg_rtol: 1e-3,
            cg_max_iterations: 1000,
            armijo: 1e-4,
            max_halvings: 30,
            hessian: HessianKind::Surrogate,
            cg_rtol_loose: 1e-2,
            preconditioner: PreconditionerKind::TwoLevel,
        }
    }
}

/// What a minimisation did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NewtonReport {
    /// Newton iterations run.
    pub iterations: usize,
    /// Whether the step criterion was met.
    pub converged: bool,
    /// The energy before the first iteration and after each accepted step.
    pub energies: Vec<f64>,
    /// PCG iterations over all Newton iterations.
    pub cg_iterations: usize,
    /// Largest vertex displacement of the last step, m.
    pub last_step: f64,
    /// Largest gradient component on free vertices at the end, N.
    pub gradient_max: f64,
}

fn free_gradient(
    p: &IncrementalPotential,
    x: &[[f64; 3]],
    pinned: &[bool],
) -> Result<(f64, Vec<[f64; 3]>), SimError> {
    let (e, mut g) = p.gradient(x)?;
    for (gi, &pin) in g.iter_mut().zip(pinned) {
        if pin {
            *gi = [0.0; 3];
        }
    }
    Ok((e, g))
}

fn max_abs(v: &[[f64; 3]]) -> f64 {
    v.iter().flatten().fold(0.0, |m, c| m.max(c.abs()))
}

/// Minimises `potential` over `x` (pinned vertices stay where they are), reusing
/// `hess` (from [`IncrementalPotential::hessian_pattern`]).
pub fn minimize(
    potential: &IncrementalPotential,
    x: &mut [[f64; 3]],
    pinned: &[bool],
    hess: &mut BlockCsr,
    opts: &NewtonOptions,
) -> Result<NewtonReport, SimError> {
    let n = potential.vertex_count();
    check_len("positions", n, x.len())?;
    check_len("pinned flags", n, pinned.len())?;
    check_len("hessian", n, hess.block_rows())?;
    let mut report = NewtonReport::default();
    let (mut e, mut g) = free_gradient(potential, x, pinned)?;
    if !e.is_finite() {
        return Err(SimError::Diverged {
            message: format!("the incremental potential is {e} at the start of the step"),
        });
    }
    report.energies.push(e);
    let mut trial = x.to_vec();
    let g0 = max_abs(&g).max(f64::MIN_POSITIVE);
    // The aggregates depend on the pattern and the pins only: once per minimisation.
    let aggregates = (opts.preconditioner == PreconditionerKind::TwoLevel)
        .then(|| Aggregates::new(hess, pinned, 2));
    for _ in 0..opts.max_iterations {
        report.iterations += 1;
        potential.hessian_into(x, opts.hessian, hess)?;
        for (i, &pin) in pinned.iter().enumerate() {
            if pin {
                hess.pin(i);
            }
        }
        let rhs: Vec<[f64; 3]> = g.iter().map(|v| v.map(|c| -c)).collect();
        let rtol = (max_abs(&g) / g0).min(opts.cg_rtol_loose).max(opts.cg_rtol);
        let pre: Box<dyn Preconditioner> = match &aggregates {
            Some(a) => Box::new(TwoLevel::new(hess, a)),
            None => Box::new(BlockJacobi::new(hess)),
        };
        let (mut d, cg) = pcg_with(hess, &rhs, pre.as_ref(), rtol, opts.cg_max_iterations)?;
        report.cg_iterations += cg.iterations;
        let mut slope: f64 = d
            .iter()
            .flatten()
            .zip(g.iter().flatten())
            .map(|(a, b)| a * b)
            .sum();
        if slope >= 0.0 || slope.is_nan() {
            // Not a descent direction (should not happen with PSD blocks): use −g.
            d = rhs;
            slope = -d.iter().flatten().map(|c| c * c).sum::<f64>();
        }
        if slope == 0.0 {
            report.converged = true;
            break;
        }
        // The full step first, with its gradient: most Newton steps are accepted at
        // α = 1 (84 % on the walking skirt), and then the next iteration's gradient comes
        // with the value the line search needs instead of a second pass over the
        // elements. Halvings evaluate the value only.
        let mut alpha = 1.0;
        let mut accepted = None;
        for halving in 0..=opts.max_halvings {
            for ((t, xi), di) in trial.iter_mut().zip(x.iter()).zip(&d) {
                *t = std::array::from_fn(|k| xi[k] + alpha * di[k]);
            }
            let (et, gt) = if halving == 0 {
                let (et, gt) = free_gradient(potential, &trial, pinned)?;
                (et, Some(gt))
            } else {
                (potential.value(&trial)?, None)
            };
            if et.is_finite() && et <= e + opts.armijo * alpha * slope {
                accepted = Some((et, gt));
                break;
            }
            alpha *= 0.5;
        }
        let step = alpha * max_abs(&d);
        let Some((et, gt)) = accepted else {
            // No decrease possible at this resolution: we are at the minimum to rounding.
            report.last_step = 0.0;
            report.converged = max_abs(&d) < 10.0 * opts.tolerance;
            break;
        };
        if std::env::var_os("WEFT_NEWTON_TRACE").is_some() {
            eprintln!(
                "  it {} E {:.6e} alpha {alpha} |d| {:.2e} cg {} res {:.1e} |g| {:.2e}",
                report.iterations,
                e,
                max_abs(&d),
                cg.iterations,
                cg.relative_residual,
                max_abs(&g)
            );
        }
        x.copy_from_slice(&trial);
        report.last_step = step;
        (e, g) = match gt {
            Some(gt) => (et, gt),
            None => free_gradient(potential, x, pinned)?,
        };
        report.energies.push(e);
        if step < opts.tolerance {
            report.converged = true;
            break;
        }
    }
    report.gradient_max = max_abs(&g);
    Ok(report)
}
