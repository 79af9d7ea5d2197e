//! Gravity (`L_gravity` of seed 004 eq. 5; seed 000 supplement eq. 5 is the same term
//! with weight `k_g`) and the lumped vertex masses every dynamic term uses.
//!
//! `E = −Σ_i m_i g·x_i`: linear in the positions, so the gradient is the constant
//! `−m_i g` and the Hessian is zero. weft is Y-up, so the default `g` is
//! `(0, −9.81, 0)` m/s² (seed 000 writes `g = [0, 0, −9.8]` in its Z-up frame; HOOD
//! uses 9.81 on its up axis).

use weft_mesh::TriMesh;

use crate::energy::{Energy, HessianKind};
use crate::error::{check_count, check_eval, check_nonneg, check_vertex, Output, SimError};
use crate::math::{axpy3, finite3};
use crate::sparse::BlockCsr;

/// Standard gravity, Y-up, m/s².
pub const STANDARD_GRAVITY: [f64; 3] = [0.0, -9.81, 0.0];

/// Lumped vertex masses: each face gives a third of `density_f × area_f` (rest areas,
/// density in kg/m²) to each of its vertices (HOOD's `get_vertex_mass`).
pub fn lumped_masses(rest: &TriMesh, face_density: &[f64]) -> Result<Vec<f64>, SimError> {
    check_count("density", "face", rest.faces.len(), face_density.len())?;
    let n = rest.vertex_count();
    for (fi, f) in rest.faces.iter().enumerate() {
        for &v in f {
            check_vertex("face", fi, v, n)?;
        }
        check_nonneg(|| format!("face {fi} density"), face_density[fi], true)?;
    }
    let mut m = vec![0.0; n];
    for ((f, a), rho) in rest.faces.iter().zip(rest.face_areas()).zip(face_density) {
        for &v in f {
            m[v as usize] += rho * a / 3.0;
        }
    }
    Ok(m)
}

/// Checks masses: finite and `>= 0`.
pub(crate) fn check_masses(m: &[f64]) -> Result<(), SimError> {
    for (i, &mi) in m.iter().enumerate() {
        check_nonneg(|| format!("vertex {i} mass"), mi, false)?;
    }
    Ok(())
}

/// The gravitational potential energy of the garment.
#[derive(Clone, Debug)]
pub struct Gravity {
    masses: Vec<f64>,
    g: [f64; 3],
}

impl Gravity {
    /// Gravity with acceleration `g` (m/s²) on vertices of mass `masses` (kg).
    pub fn new(masses: Vec<f64>, g: [f64; 3]) -> Result<Self, SimError> {
        check_masses(&masses)?;
        if !finite3(g) {
            return Err(SimError::InvalidVector {
                what: "gravity".into(),
                message: "not finite",
            });
        }
        Ok(Gravity { masses, g })
    }

    /// The masses.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The acceleration.
    pub fn acceleration(&self) -> [f64; 3] {
        self.g
    }
}

impl Energy for Gravity {
    fn name(&self) -> &'static str {
        "gravity"
    }
    fn vertex_count(&self) -> usize {
        self.masses.len()
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.masses.len(), x, Output::Value)?;
        let g = self.g;
        Ok(-x
            .iter()
            .zip(&self.masses)
            .map(|(p, m)| m * (g[0] * p[0] + g[1] * p[1] + g[2] * p[2]))
            .sum::<f64>())
    }
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_eval(self.masses.len(), x, Output::Gradient(grad.len()))?;
        let e = self.value(x)?;
        for (gr, m) in grad.iter_mut().zip(&self.masses) {
            axpy3(gr, -scale * m, self.g);
        }
        Ok(e)
    }
    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        _scale: f64,
        _kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError> {
        check_eval(self.masses.len(), x, Output::Hessian(hess.block_rows()))
    }
    fn for_each_stencil(&self, _kind: HessianKind, _f: &mut dyn FnMut(&[u32])) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::grid;

    #[test]
    fn lumped_masses_sum_to_total_mass() {
        let m = grid(4, 3, 0.5);
        let masses = lumped_masses(&m, &vec![0.2; m.face_count()]).unwrap();
        let total: f64 = masses.iter().sum();
        assert!((total - 0.2 * 1.5 * 1.0).abs() < 1e-12);
        assert!(lumped_masses(&m, &[0.2]).is_err());
        let mut bad = vec![0.2; m.face_count()];
        bad[3] = -1.0;
        assert!(lumped_masses(&m, &bad).is_err());
    }

    #[test]
    fn gravity_energy_is_weight_times_height() {
        let g = Gravity::new(vec![2.0, 1.0], STANDARD_GRAVITY).unwrap();
        let e = g.value(&[[0.0, 1.0, 0.0], [5.0, -2.0, 1.0]]).unwrap();
        assert!((e - 9.81 * (2.0 - 2.0)).abs() < 1e-12);
        let mut gr = vec![[0.0; 3]; 2];
        g.add_gradient(&[[0.0; 3]; 2], 1.0, &mut gr).unwrap();
        assert_eq!(gr[0], [0.0, 2.0 * 9.81, 0.0]);
        assert!(g.value(&[[0.0; 3]]).is_err());
        assert!(Gravity::new(vec![f64::NAN], STANDARD_GRAVITY).is_err());
    }
}
