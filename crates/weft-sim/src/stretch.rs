//! StVK membrane stretching on triangles (seed 004 §3.3, `L_stretching` of eq. 5).
//!
//! Green strain `E = ½(FᵀF − I)` (2×2) and the St. Venant–Kirchhoff density
//! `ψ = μ‖E‖²_F + λ/2 · tr(E)²`, integrated over the rest triangle with the shell
//! thickness `h`: `E_f = A_f · h · ψ(F_f)`, exactly HOOD's stretching energy (their
//! `S = μE + ½λ tr(E) I`, `ψ = tr(SᵀE)`). `μ`, `λ` are per face (heterogeneous garments,
//! HOOD Fig. 10) and in Pa (3D moduli times the thickness give the membrane stiffness
//! in N/m); see `material.rs` for the plane-stress conversion from Young's modulus and
//! Poisson's ratio.
//!
//! Derivatives: `P = ∂ψ/∂F = F S` with the second Piola–Kirchhoff stress
//! `S = 2μE + λ tr(E) I`; `dP = dF S + F dS`, `dS = 2μ dE + λ tr(dE) I`,
//! `dE = ½(dFᵀF + FᵀdF)`. The exact Hessian is indefinite under compression (`E` with
//! negative eigenvalues); [`HessianKind::Projected`] clamps each face's 9×9 block.

use nalgebra::{Matrix2, Matrix3x2};
use weft_mesh::TriMesh;

use crate::energy::{Energy, HessianKind};
use crate::error::{check_count, check_nonneg, SimError};
use crate::membrane::{
    face_stencils, membrane_gradient, membrane_hessian, membrane_value, FHessian, MembraneDensity,
    RestFrames,
};
use crate::sparse::BlockCsr;

/// Lamé parameters and thickness of one face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StretchParams {
    /// Lamé μ (shear modulus), Pa.
    pub mu: f64,
    /// Lamé λ, Pa (the plane-stress value for a membrane).
    pub lambda: f64,
    /// Shell thickness, m.
    pub thickness: f64,
}

/// StVK stretching energy of a garment.
#[derive(Clone, Debug)]
pub struct Stretch {
    frames: RestFrames,
    params: Vec<StretchParams>,
}

impl Stretch {
    /// One parameter set per face of `frames`. `μ > 0`, `λ >= 0`, thickness `> 0`.
    pub fn new(frames: RestFrames, params: Vec<StretchParams>) -> Result<Self, SimError> {
        check_count(
            "stretch parameters",
            "face",
            frames.faces().len(),
            params.len(),
        )?;
        for (f, p) in params.iter().enumerate() {
            check_nonneg(|| format!("face {f} mu"), p.mu, true)?;
            check_nonneg(|| format!("face {f} lambda"), p.lambda, false)?;
            check_nonneg(|| format!("face {f} thickness"), p.thickness, true)?;
        }
        Ok(Stretch { frames, params })
    }

    /// The same parameters on every face, rest frames from the rest mesh.
    pub fn uniform(rest: &TriMesh, params: StretchParams) -> Result<Self, SimError> {
        let frames = RestFrames::from_rest_mesh(rest)?;
        let n = frames.faces().len();
        Self::new(frames, vec![params; n])
    }

    /// The rest frames.
    pub fn frames(&self) -> &RestFrames {
        &self.frames
    }

    /// The per-face parameters.
    pub fn params(&self) -> &[StretchParams] {
        &self.params
    }

    /// Green strain of face `f` at positions `x`.
    pub fn green_strain(&self, f: usize, x: &[[f64; 3]]) -> Result<Matrix2<f64>, SimError> {
        self.frames.check_positions(x)?;
        if f >= self.params.len() {
            return Err(SimError::InvalidParameter {
                what: format!("face index {f}"),
                value: f as f64,
                expected: "expected an index below the face count",
            });
        }
        Ok(green(&self.frames.deformation_gradient(f, x)))
    }
}

fn green(f: &Matrix3x2<f64>) -> Matrix2<f64> {
    (f.transpose() * f - Matrix2::identity()) * 0.5
}

impl MembraneDensity for Stretch {
    fn psi(&self, f: usize, fg: &Matrix3x2<f64>) -> f64 {
        let p = self.params[f];
        let e = green(fg);
        p.thickness * (p.mu * e.norm_squared() + 0.5 * p.lambda * e.trace().powi(2))
    }

    fn psi_and_stress(&self, f: usize, fg: &Matrix3x2<f64>) -> (f64, Matrix3x2<f64>) {
        let p = self.params[f];
        let e = green(fg);
        let tr = e.trace();
        let s = e * (2.0 * p.mu) + Matrix2::identity() * (p.lambda * tr);
        let psi = p.mu * e.norm_squared() + 0.5 * p.lambda * tr * tr;
        (p.thickness * psi, fg * s * p.thickness)
    }

    fn stiffness(&self, f: usize, fg: &Matrix3x2<f64>) -> FHessian {
        let p = self.params[f];
        let e = green(fg);
        let s = e * (2.0 * p.mu) + Matrix2::identity() * (p.lambda * e.trace());
        let mut k = FHessian::zeros();
        for j in 0..2 {
            for kk in 0..3 {
                let mut df = Matrix3x2::zeros();
                df[(kk, j)] = 1.0;
                let ft_df = fg.transpose() * df;
                let de = (ft_df + ft_df.transpose()) * 0.5;
                let ds = de * (2.0 * p.mu) + Matrix2::identity() * (p.lambda * de.trace());
                let dp = (df * s + fg * ds) * p.thickness;
                for m in 0..2 {
                    for l in 0..3 {
                        k[(l + 3 * m, kk + 3 * j)] = dp[(l, m)];
                    }
                }
            }
        }
        k
    }
}

impl Energy for Stretch {
    fn name(&self) -> &'static str {
        "stretching"
    }
    fn vertex_count(&self) -> usize {
        self.frames.vertex_count()
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        membrane_value(&self.frames, self, x)
    }
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        membrane_gradient(&self.frames, self, x, scale, grad)
    }
    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError> {
        membrane_hessian(&self.frames, self, x, scale, kind, hess)
    }
    fn for_each_stencil(&self, f: &mut dyn FnMut(&[u32])) {
        face_stencils(&self.frames, f)
    }
}
