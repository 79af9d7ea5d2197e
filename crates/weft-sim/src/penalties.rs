//! Physics penalties over a garment's positions that are not simulator energies but
//! losses on a prediction (seed 000 supplement §2, eq. 4, 6–8), written as [`Energy`]s so
//! they share the code path (and the finite-difference checks) of the simulator's terms:
//!
//! * eq. 4, collision: `k_c Σ_i |min(h(x_i) − ε, 0)|` = `k_c Σ_i max(ε − d_i, 0)` with the
//!   signed distance `h` taken, as for the cubic penalty, along the contact normal:
//!   [`LinearCollision`]. Its gradient is `−k_c n` below the threshold and its Hessian is
//!   zero wherever it exists (the kink at `d = ε` has none).
//! * eq. 5, gravity, is [`crate::Gravity`] itself.
//! * eq. 6, UV stretch: `k_s Σ_f a_f [(‖W^u_f‖ − 1)² + (‖W^v_f‖ − 1)²]`: [`UvStretch`].
//! * eq. 7, UV shear: `k_h Σ_f a_f (W^u_f · W^v_f)²`: [`UvShear`].
//! * eq. 8: `(W^u W^v) = (Δx₁ Δx₂)(Δu₁ Δu₂; Δv₁ Δv₂)⁻¹`, which is the deformation gradient
//!   `F` of a [`RestFrames`] built from UVs (`from_corner_uvs` / `from_vertex_uvs`); `a_f`
//!   is the UV area. Without UVs, `from_rest_mesh` gives the same with the rest triangle
//!   laid flat.
//!
//! The weights `k_*` are not inside the energies: they are term weights, chosen by whoever
//! sums the terms (the trainer's loss weights, or an [`crate::IncrementalPotential`]).
//!
//! Eq. 6 is the Baraff–Witkin stretch condition squared: its exact Hessian,
//! `2a[ŵŵᵀ + (1 − 1/‖w‖)(I − ŵŵᵀ)]` per column, is indefinite when a direction is
//! compressed (`‖w‖ < 1`); the projected Hessian clamps each face's 9×9 block.

use nalgebra::{Matrix3, Matrix3x2};

use crate::contact::{validate_contacts, VertexContact};
use crate::energy::{Energy, HessianKind};
use crate::error::{check_len, check_nonneg, SimError};
use crate::math::axpy3;
use crate::membrane::{FHessian, MembraneDensity, RestFrames};
use crate::sparse::BlockCsr;

/// Seed 000 eq. 4: the linear (hinge) collision loss `Σ max(ε − d, 0)`.
#[derive(Clone, Debug)]
pub struct LinearCollision {
    vertex_count: usize,
    eps: f64,
    contacts: Vec<VertexContact>,
}

impl LinearCollision {
    /// The loss with threshold `ε >= 0` over `contacts`.
    pub fn new(
        vertex_count: usize,
        eps: f64,
        contacts: Vec<VertexContact>,
    ) -> Result<Self, SimError> {
        check_nonneg(|| "collision threshold".into(), eps, false)?;
        Ok(LinearCollision {
            vertex_count,
            eps,
            contacts: validate_contacts(contacts, vertex_count)?,
        })
    }

    /// Replaces the contacts.
    pub fn set_contacts(&mut self, contacts: Vec<VertexContact>) -> Result<(), SimError> {
        self.contacts = validate_contacts(contacts, self.vertex_count)?;
        Ok(())
    }
}

impl Energy for LinearCollision {
    fn name(&self) -> &'static str {
        "linear collision"
    }
    fn vertex_count(&self) -> usize {
        self.vertex_count
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_len("positions", self.vertex_count, x.len())?;
        Ok(self
            .contacts
            .iter()
            .map(|c| (self.eps - c.contact.signed_distance(x[c.vertex as usize])).max(0.0))
            .sum())
    }
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_len("positions", self.vertex_count, x.len())?;
        check_len("gradient", self.vertex_count, grad.len())?;
        let mut e = 0.0;
        for c in &self.contacts {
            let s = self.eps - c.contact.signed_distance(x[c.vertex as usize]);
            if s > 0.0 {
                e += s;
                axpy3(&mut grad[c.vertex as usize], -scale, c.contact.normal);
            }
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
        check_len("positions", self.vertex_count, x.len())?;
        check_len("hessian", self.vertex_count, hess.block_rows())
    }
    fn for_each_stencil(&self, _kind: HessianKind, _f: &mut dyn FnMut(&[u32])) {}
}

/// Seed 000 eq. 6: `Σ_f a_f [(‖W^u‖ − 1)² + (‖W^v‖ − 1)²]`.
#[derive(Clone, Debug)]
pub struct UvStretch {
    frames: RestFrames,
}

impl UvStretch {
    /// The stretch loss over `frames` (from UVs, or from the rest mesh).
    pub fn new(frames: RestFrames) -> Self {
        UvStretch { frames }
    }
}

/// Returns `(‖w‖, ŵ)`, `ŵ = 0` for `w = 0`.
fn length_dir(
    w: nalgebra::VectorView3<f64, nalgebra::U1, nalgebra::U3>,
) -> (f64, nalgebra::Vector3<f64>) {
    let l = w.norm();
    if l > 0.0 {
        (l, w / l)
    } else {
        (0.0, nalgebra::Vector3::zeros())
    }
}

impl MembraneDensity for UvStretch {
    fn psi(&self, _f: usize, fg: &Matrix3x2<f64>) -> f64 {
        (fg.column(0).norm() - 1.0).powi(2) + (fg.column(1).norm() - 1.0).powi(2)
    }
    fn psi_and_stress(&self, f: usize, fg: &Matrix3x2<f64>) -> (f64, Matrix3x2<f64>) {
        let mut p = Matrix3x2::zeros();
        for j in 0..2 {
            let (l, d) = length_dir(fg.column(j));
            p.set_column(j, &(d * (2.0 * (l - 1.0))));
        }
        (self.psi(f, fg), p)
    }
    fn stiffness(&self, _f: usize, fg: &Matrix3x2<f64>) -> FHessian {
        let mut k = FHessian::zeros();
        for j in 0..2 {
            let (l, d) = length_dir(fg.column(j));
            if l == 0.0 {
                continue;
            }
            let dd = d * d.transpose();
            let b: Matrix3<f64> = (dd + (Matrix3::identity() - dd) * ((l - 1.0) / l)) * 2.0;
            k.fixed_view_mut::<3, 3>(3 * j, 3 * j).copy_from(&b);
        }
        k
    }
}

/// Seed 000 eq. 7: `Σ_f a_f (W^u · W^v)²`.
#[derive(Clone, Debug)]
pub struct UvShear {
    frames: RestFrames,
}

impl UvShear {
    /// The shear loss over `frames` (from UVs, or from the rest mesh).
    pub fn new(frames: RestFrames) -> Self {
        UvShear { frames }
    }
}

impl MembraneDensity for UvShear {
    fn psi(&self, _f: usize, fg: &Matrix3x2<f64>) -> f64 {
        fg.column(0).dot(&fg.column(1)).powi(2)
    }
    fn psi_and_stress(&self, _f: usize, fg: &Matrix3x2<f64>) -> (f64, Matrix3x2<f64>) {
        let (wu, wv) = (fg.column(0).into_owned(), fg.column(1).into_owned());
        let s = wu.dot(&wv);
        (
            s * s,
            Matrix3x2::from_columns(&[wv * (2.0 * s), wu * (2.0 * s)]),
        )
    }
    fn stiffness(&self, _f: usize, fg: &Matrix3x2<f64>) -> FHessian {
        let (wu, wv) = (fg.column(0).into_owned(), fg.column(1).into_owned());
        let s = wu.dot(&wv);
        let mut k = FHessian::zeros();
        k.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(wv * wv.transpose() * 2.0));
        k.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(wu * wu.transpose() * 2.0));
        let off: Matrix3<f64> = (wv * wu.transpose() + Matrix3::identity() * s) * 2.0;
        k.fixed_view_mut::<3, 3>(0, 3).copy_from(&off);
        k.fixed_view_mut::<3, 3>(3, 0).copy_from(&off.transpose());
        k
    }
}

crate::membrane::membrane_energy!(UvStretch, "uv stretch");
crate::membrane::membrane_energy!(UvShear, "uv shear");
