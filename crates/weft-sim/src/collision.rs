//! Cubic collision penalty against the body (`L_collision` of seed 004 eq. 5, after SNUG
//! [43] eq. 12).
//!
//! For each garment vertex with a body contact (closest point `p`, outward normal `n`):
//! `d = (x − p)·n` and `E = k_c · max(ε − d, 0)³`, zero once the vertex is more than `ε`
//! outside the body. The contact is held fixed while the energy is minimised (HOOD picks
//! the closest body face from the garment's previous positions and uses its point and
//! normal at the current body state), so `d` is linear in `x`:
//! `∇E = −3k_c s² n`, `∇²E = 6k_c s n nᵀ` with `s = max(ε − d, 0)`: C², convex, PSD.
//!
//! HOOD's defaults: `ε = 2 mm`, `k_c` ramped from 5·10³ to 5·10⁵ during training.

use nalgebra::Matrix3;

use crate::contact::{validate_contacts, VertexContact};
use crate::energy::{Energy, HessianKind};
use crate::error::{check_eval, check_nonneg, Output, SimError};
use crate::math::{axpy3, v3};
use crate::sparse::BlockCsr;

/// HOOD's collision threshold ε, m.
pub const HOOD_COLLISION_EPS: f64 = 2e-3;
/// HOOD's final collision stiffness (after the training ramp-up).
pub const HOOD_COLLISION_STIFFNESS: f64 = 5e5;

/// The cubic penalty of vertices closer to the body than ε.
#[derive(Clone, Debug)]
pub struct CubicCollision {
    vertex_count: usize,
    stiffness: f64,
    eps: f64,
    contacts: Vec<VertexContact>,
}

impl CubicCollision {
    /// A penalty with stiffness `k_c >= 0` and threshold `ε >= 0` over `contacts`.
    pub fn new(
        vertex_count: usize,
        stiffness: f64,
        eps: f64,
        contacts: Vec<VertexContact>,
    ) -> Result<Self, SimError> {
        check_nonneg(|| "collision stiffness".into(), stiffness, false)?;
        check_nonneg(|| "collision threshold".into(), eps, false)?;
        Ok(CubicCollision {
            vertex_count,
            stiffness,
            eps,
            contacts: validate_contacts(contacts, vertex_count)?,
        })
    }

    /// Replaces the contacts (each step).
    pub fn set_contacts(&mut self, contacts: Vec<VertexContact>) -> Result<(), SimError> {
        self.contacts = validate_contacts(contacts, self.vertex_count)?;
        Ok(())
    }

    /// The contacts.
    pub fn contacts(&self) -> &[VertexContact] {
        &self.contacts
    }

    /// The threshold ε.
    pub fn eps(&self) -> f64 {
        self.eps
    }

    /// The stiffness `k_c`.
    pub fn stiffness(&self) -> f64 {
        self.stiffness
    }

    /// Changes the stiffness (e.g. HOOD's ramp-up).
    pub fn set_stiffness(&mut self, stiffness: f64) -> Result<(), SimError> {
        check_nonneg(|| "collision stiffness".into(), stiffness, false)?;
        self.stiffness = stiffness;
        Ok(())
    }

    /// `max(ε − d, 0)` of each contact at `x` (the penetration depth below the threshold).
    fn depth(&self, c: &VertexContact, x: &[[f64; 3]]) -> f64 {
        (self.eps - c.contact.signed_distance(x[c.vertex as usize])).max(0.0)
    }

    /// The force magnitude `3 k_c max(ε − d, 0)²` of each contact at `x`, in contact
    /// order: the lagged normal force friction can use.
    pub fn normal_forces(&self, x: &[[f64; 3]]) -> Result<Vec<f64>, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok(self
            .contacts
            .iter()
            .map(|c| 3.0 * self.stiffness * self.depth(c, x).powi(2))
            .collect())
    }
}

impl Energy for CubicCollision {
    fn name(&self) -> &'static str {
        "collision"
    }
    fn vertex_count(&self) -> usize {
        self.vertex_count
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok(self
            .contacts
            .iter()
            .map(|c| self.stiffness * self.depth(c, x).powi(3))
            .sum())
    }
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Gradient(grad.len()))?;
        let mut e = 0.0;
        for c in &self.contacts {
            let s = self.depth(c, x);
            e += self.stiffness * s.powi(3);
            let f = -3.0 * self.stiffness * s * s * scale;
            axpy3(&mut grad[c.vertex as usize], f, c.contact.normal);
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
        check_eval(self.vertex_count, x, Output::Hessian(hess.block_rows()))?;
        for c in &self.contacts {
            let s = self.depth(c, x);
            if s > 0.0 {
                let n = v3(c.contact.normal);
                let b: Matrix3<f64> = n * n.transpose() * (6.0 * self.stiffness * s * scale);
                hess.add_block(c.vertex as usize, c.vertex as usize, &b)?;
            }
        }
        Ok(())
    }
    fn for_each_stencil(&self, _kind: HessianKind, _f: &mut dyn FnMut(&[u32])) {}
}
