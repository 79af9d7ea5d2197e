//! Inertia of implicit Euler as an energy (`L_inertia` of seed 004 eq. 5, after Martin
//! et al. 2011, "Example-based elastic materials", and SNUG eq. 6).
//!
//! `E = Σ_i m_i |x_i − x̂_i|² / (2h²)` with the inertial target `x̂ = x_t + h v_t`. With
//! `v_t = (x_t − x_{t−1})/h` (HOOD), `x̂ = 2x_t − x_{t−1}`. Minimising this plus the
//! potential energies over `x = x_{t+1}` is exactly one implicit-Euler step:
//! `M(x − x̂)/h² = −∇U(x)`.

use crate::energy::{Energy, HessianKind};
use crate::error::{check_eval, check_len, check_nonneg, Output, SimError};
use crate::gravity::check_masses;
use crate::math::{axpy3, finite3};
use crate::sparse::BlockCsr;
use nalgebra::Matrix3;

/// The inertial term of one implicit-Euler step.
#[derive(Clone, Debug)]
pub struct Inertia {
    masses: Vec<f64>,
    dt: f64,
    target: Vec<[f64; 3]>,
}

impl Inertia {
    /// Inertia towards `target` (`x̂`) with time step `dt > 0` (s).
    pub fn new(masses: Vec<f64>, dt: f64, target: Vec<[f64; 3]>) -> Result<Self, SimError> {
        check_masses(&masses)?;
        check_nonneg(|| "time step".into(), dt, true)?;
        let mut i = Inertia {
            masses,
            dt,
            target: Vec::new(),
        };
        i.set_target(target)?;
        Ok(i)
    }

    /// Inertia from the two previous states (HOOD): `x̂ = x_t + (x_t − x_{t−1})`.
    pub fn from_states(
        masses: Vec<f64>,
        dt: f64,
        previous: &[[f64; 3]],
        current: &[[f64; 3]],
    ) -> Result<Self, SimError> {
        check_len("previous positions", masses.len(), previous.len())?;
        check_len("current positions", masses.len(), current.len())?;
        let target = inertial_target(current, previous, 1.0)?;
        Self::new(masses, dt, target)
    }

    /// Replaces the inertial target (each step).
    pub fn set_target(&mut self, target: Vec<[f64; 3]>) -> Result<(), SimError> {
        check_len("inertial target", self.masses.len(), target.len())?;
        if let Some(i) = target.iter().position(|p| !finite3(*p)) {
            return Err(SimError::InvalidVector {
                what: format!("inertial target of vertex {i}"),
                message: "not finite",
            });
        }
        self.target = target;
        Ok(())
    }

    /// Changes the time step.
    pub fn set_dt(&mut self, dt: f64) -> Result<(), SimError> {
        check_nonneg(|| "time step".into(), dt, true)?;
        self.dt = dt;
        Ok(())
    }

    /// The time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The inertial target `x̂`.
    pub fn target(&self) -> &[[f64; 3]] {
        &self.target
    }

    /// The masses.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }
}

/// `x_t + s · (x_t − x_{t−1})`, the inertial target for velocity `(x_t − x_{t−1})/h` and
/// step `s · h` (`s = 1` for a constant step).
pub fn inertial_target(
    current: &[[f64; 3]],
    previous: &[[f64; 3]],
    s: f64,
) -> Result<Vec<[f64; 3]>, SimError> {
    check_len("previous positions", current.len(), previous.len())?;
    Ok(current
        .iter()
        .zip(previous)
        .map(|(c, p)| std::array::from_fn(|k| c[k] + s * (c[k] - p[k])))
        .collect())
}

impl Energy for Inertia {
    fn name(&self) -> &'static str {
        "inertia"
    }
    fn vertex_count(&self) -> usize {
        self.masses.len()
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.masses.len(), x, Output::Value)?;
        let c = 0.5 / (self.dt * self.dt);
        Ok(x.iter()
            .zip(&self.target)
            .zip(&self.masses)
            .map(|((p, t), m)| {
                c * m * ((p[0] - t[0]).powi(2) + (p[1] - t[1]).powi(2) + (p[2] - t[2]).powi(2))
            })
            .sum())
    }
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_eval(self.masses.len(), x, Output::Gradient(grad.len()))?;
        let e = self.value(x)?;
        let c = scale / (self.dt * self.dt);
        for (((gr, p), t), m) in grad.iter_mut().zip(x).zip(&self.target).zip(&self.masses) {
            axpy3(gr, c * m, std::array::from_fn(|k| p[k] - t[k]));
        }
        Ok(e)
    }
    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        _kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError> {
        check_eval(self.masses.len(), x, Output::Hessian(hess.block_rows()))?;
        let c = scale / (self.dt * self.dt);
        for (i, m) in self.masses.iter().enumerate() {
            hess.add_block(i, i, &(Matrix3::identity() * (c * m)))?;
        }
        Ok(())
    }
    fn for_each_stencil(&self, _kind: HessianKind, _f: &mut dyn FnMut(&[u32])) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_extrapolates_velocity() {
        let i =
            Inertia::from_states(vec![1.0], 0.1, &[[0.0, 1.0, 0.0]], &[[0.0, 2.0, 0.0]]).unwrap();
        assert_eq!(i.target(), &[[0.0, 3.0, 0.0]]);
        assert_eq!(i.value(&[[0.0, 3.0, 0.0]]).unwrap(), 0.0);
        assert!((i.value(&[[0.0, 3.1, 0.0]]).unwrap() - 0.5).abs() < 1e-12);
        assert!(Inertia::new(vec![1.0], 0.0, vec![[0.0; 3]]).is_err());
        assert!(Inertia::new(vec![1.0], 0.1, vec![[f64::INFINITY, 0.0, 0.0]]).is_err());
    }
}
