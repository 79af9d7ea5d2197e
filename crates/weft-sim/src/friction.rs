//! Friction against the body (`L_friction` of seed 004 eq. 5; HOOD cites Bridson et al.
//! 2002 [8] and Geilinger et al. 2020 [18]).
//!
//! HOOD's term (their `friction_energy.py`, supplementary §1.4): for a garment vertex in
//! contact, the displacement over the step relative to the body,
//! `Δ = x_{t+1} − (x_t + Δp_body)` with `Δp_body` the motion of the body point the
//! vertex touched at the start of the step, is projected onto the body's tangent plane
//! (normal `n` = mean of the start and end normals), and
//! `E = μ · λ_n · ‖Δ_T‖` with the normal force magnitude lagged at `λ_n = m g` (the
//! vertex's weight). This is dissipation of a Coulomb friction force of magnitude
//! `μ λ_n` opposing the relative tangential motion (the lagged dissipative potential of
//! Geilinger et al. and of IPC, Li et al. 2020).
//!
//! `‖Δ_T‖` has no derivative at zero (static friction), which Newton cannot handle; we
//! use IPC's C² mollifier `f₀` with a small slip length `ε` (m):
//! `f₀(y) = −y³/(3ε²) + y²/ε + ε/3` for `y < ε`, `f₀(y) = y` beyond. So
//! `E = Σ μ λ_n f₀(‖T(x − a)‖)` with the anchor `a = x_t + Δp_body` and
//! `T = I − nnᵀ`, and with `u = T(x − a)`, `y = |u|`:
//!
//! * `∇E = μλ_n f₀'(y)/y · u` (`f₀'(y)/y → 2/ε` as `y → 0`, so no division by zero),
//! * `∇²E = μλ_n [(2/ε − y/ε²) T − (y/ε²) ûûᵀ]` for `y < ε`, `μλ_n (T − ûûᵀ)/y` beyond:
//!   exact, PSD, C⁰ at `y = ε` (f₀ is C² there).
//!
//! Differences from HOOD, on purpose: the mollifier (HOOD differentiates `‖Δ_T‖` with
//! autograd, which is fine for a loss but not for Newton), and HOOD's extra factor
//! `sqrt(1 − cos²(Δ_T, z) + 10⁻⁴)` (the angle to a fixed world axis) is left out: it
//! depends on the world frame, not on the contact. The normal force can also be lagged
//! from the collision penalty (`CubicCollision::normal_forces`) instead of `m g`.

use nalgebra::Matrix3;

use crate::contact::unit;
use crate::energy::{Energy, HessianKind};
use crate::error::{check_eval, check_nonneg, check_vertex, Output, SimError};
use crate::math::{axpy3, finite3, v3};
use crate::sparse::BlockCsr;

/// HOOD's friction coefficient.
pub const HOOD_FRICTION_MU: f64 = 0.5;
/// HOOD's contact radius for friction (m): vertices within it at the start and the end
/// of the step are in frictional contact.
pub const HOOD_FRICTION_RADIUS: f64 = 3e-3;
/// Default slip length of the mollifier, m (IPC's `ε_v h` for `ε_v = 3 mm/s` at 30 fps).
pub const DEFAULT_FRICTION_EPS: f64 = 1e-4;

/// One vertex in frictional contact with the body during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionContact {
    /// The garment vertex.
    pub vertex: u32,
    /// Where the vertex would be if it stuck to the body: `x_t + Δp_body`.
    pub anchor: [f64; 3],
    /// The body normal (normalised on construction of [`Friction`]).
    pub normal: [f64; 3],
    /// Lagged normal force magnitude `λ_n`, N.
    pub normal_force: f64,
    /// Friction coefficient μ.
    pub mu: f64,
}

impl FrictionContact {
    /// HOOD's contact: anchor `x_t + (p_body,t+1 − p_body,t)`, normal the mean of the body
    /// normals at both ends of the step, normal force `mass × g`.
    #[allow(clippy::too_many_arguments)]
    pub fn hood(
        vertex: u32,
        x_start: [f64; 3],
        body_point_start: [f64; 3],
        body_point_end: [f64; 3],
        normal_start: [f64; 3],
        normal_end: [f64; 3],
        mass: f64,
        gravity: f64,
        mu: f64,
    ) -> Self {
        FrictionContact {
            vertex,
            anchor: std::array::from_fn(|k| x_start[k] + body_point_end[k] - body_point_start[k]),
            normal: std::array::from_fn(|k| 0.5 * (normal_start[k] + normal_end[k])),
            normal_force: mass * gravity,
            mu,
        }
    }
}

/// The mollified friction dissipation of a step.
#[derive(Clone, Debug)]
pub struct Friction {
    vertex_count: usize,
    eps: f64,
    contacts: Vec<FrictionContact>,
}

impl Friction {
    /// Friction with slip length `eps > 0` (m) over `contacts`.
    pub fn new(
        vertex_count: usize,
        eps: f64,
        contacts: Vec<FrictionContact>,
    ) -> Result<Self, SimError> {
        check_nonneg(|| "friction slip length".into(), eps, true)?;
        let mut f = Friction {
            vertex_count,
            eps,
            contacts: Vec::new(),
        };
        f.set_contacts(contacts)?;
        Ok(f)
    }

    /// Replaces the contacts (each step).
    pub fn set_contacts(&mut self, mut contacts: Vec<FrictionContact>) -> Result<(), SimError> {
        for (i, c) in contacts.iter_mut().enumerate() {
            check_vertex("friction contact", i, c.vertex, self.vertex_count)?;
            c.normal = unit(c.normal, || format!("friction contact {i} normal"))?;
            if !finite3(c.anchor) {
                return Err(SimError::InvalidVector {
                    what: format!("friction contact {i} anchor"),
                    message: "not finite",
                });
            }
            check_nonneg(
                || format!("friction contact {i} normal force"),
                c.normal_force,
                false,
            )?;
            check_nonneg(|| format!("friction contact {i} mu"), c.mu, false)?;
        }
        self.contacts = contacts;
        Ok(())
    }

    /// The contacts.
    pub fn contacts(&self) -> &[FrictionContact] {
        &self.contacts
    }

    /// Tangential relative displacement `u = T(x − a)` and its length.
    fn tangential(c: &FrictionContact, x: &[[f64; 3]]) -> (nalgebra::Vector3<f64>, f64) {
        let n = v3(c.normal);
        let d = v3(x[c.vertex as usize]) - v3(c.anchor);
        let u = d - n * n.dot(&d);
        let y = u.norm();
        (u, y)
    }

    /// `f₀(y)`.
    fn f0(&self, y: f64) -> f64 {
        let e = self.eps;
        if y >= e {
            y
        } else {
            -y * y * y / (3.0 * e * e) + y * y / e + e / 3.0
        }
    }

    /// `f₀'(y)/y`.
    fn f1_over_y(&self, y: f64) -> f64 {
        let e = self.eps;
        if y >= e {
            1.0 / y
        } else {
            -y / (e * e) + 2.0 / e
        }
    }
}

impl Energy for Friction {
    fn name(&self) -> &'static str {
        "friction"
    }
    fn vertex_count(&self) -> usize {
        self.vertex_count
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok(self
            .contacts
            .iter()
            .map(|c| c.mu * c.normal_force * self.f0(Self::tangential(c, x).1))
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
            let (u, y) = Self::tangential(c, x);
            let w = c.mu * c.normal_force;
            e += w * self.f0(y);
            let g = u * (w * self.f1_over_y(y) * scale);
            axpy3(&mut grad[c.vertex as usize], 1.0, [g.x, g.y, g.z]);
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
            let (u, y) = Self::tangential(c, x);
            let w = c.mu * c.normal_force * scale;
            if w == 0.0 {
                continue;
            }
            let n = v3(c.normal);
            let t = Matrix3::identity() - n * n.transpose();
            let e = self.eps;
            let b = if y < e {
                // −(y/ε²) ûûᵀ = −uuᵀ/(y ε²), which vanishes with u at y = 0.
                let radial = if y > 0.0 {
                    u * u.transpose() / (y * e * e)
                } else {
                    Matrix3::zeros()
                };
                t * (2.0 / e - y / (e * e)) - radial
            } else {
                (t - u * u.transpose() / (y * y)) / y
            };
            hess.add_block(c.vertex as usize, c.vertex as usize, &(b * w))?;
        }
        Ok(())
    }
    fn for_each_stencil(&self, _kind: HessianKind, _f: &mut dyn FnMut(&[u32])) {}
}
