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
//! negative eigenvalues); [`crate::HessianKind::Projected`] clamps each face's 9×9 block.

use std::sync::Arc;

use nalgebra::{Matrix2, Matrix3, Matrix3x2, SMatrix, Vector2, Vector3};
use weft_mesh::TriMesh;

use crate::error::{check_count, check_nonneg, SimError};
use crate::math::positive_part2;
use crate::membrane::{FHessian, MembraneDensity, RestFrames};

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

/// StVK stretching energy of a garment. The rest frames and parameters are shared
/// (`Arc`), so a clone is cheap: a [`crate::ClothModel`] hands one to every step's
/// potential.
#[derive(Clone, Debug)]
pub struct Stretch {
    frames: Arc<RestFrames>,
    params: Arc<[StretchParams]>,
}

impl Stretch {
    /// One parameter set per face of `frames`. `μ > 0`, `λ >= 0`, thickness `> 0`.
    pub fn new(frames: RestFrames, params: Vec<StretchParams>) -> Result<Self, SimError> {
        Self::on_frames(Arc::new(frames), params)
    }

    /// The same rest frames (shared, not copied) with other per-face parameters, as
    /// [`Stretch::new`] checks them.
    pub fn with_params(&self, params: Vec<StretchParams>) -> Result<Self, SimError> {
        Self::on_frames(Arc::clone(&self.frames), params)
    }

    fn on_frames(frames: Arc<RestFrames>, params: Vec<StretchParams>) -> Result<Self, SimError> {
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
        Ok(Stretch {
            frames,
            params: params.into(),
        })
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

/// The Green strain `E` of `F` and the second Piola stress `S = 2μE + λ tr(E) I`.
fn strain_and_stress(p: &StretchParams, f: &Matrix3x2<f64>) -> (Matrix2<f64>, Matrix2<f64>) {
    let e = green(f);
    let s = e * (2.0 * p.mu) + Matrix2::identity() * (p.lambda * e.trace());
    (e, s)
}

impl MembraneDensity for Stretch {
    fn psi(&self, f: usize, fg: &Matrix3x2<f64>) -> f64 {
        let p = self.params[f];
        let e = green(fg);
        p.thickness * (p.mu * e.norm_squared() + 0.5 * p.lambda * e.trace().powi(2))
    }

    fn psi_and_stress(&self, f: usize, fg: &Matrix3x2<f64>) -> (f64, Matrix3x2<f64>) {
        let p = self.params[f];
        let (e, s) = strain_and_stress(&p, fg);
        let tr = e.trace();
        let psi = p.mu * e.norm_squared() + 0.5 * p.lambda * tr * tr;
        (p.thickness * psi, fg * s * p.thickness)
    }

    fn stiffness(&self, f: usize, fg: &Matrix3x2<f64>) -> FHessian {
        let (_, s) = strain_and_stress(&self.params[f], fg);
        self.stiffness_with_stress(f, fg, &s)
    }

    /// `dP = dF S⁺ + F dS`: the material part `F dS` is PSD for `μ, λ >= 0`
    /// (`⟨FᵀdF, dS⟩ = 2μ‖dE‖² + λ tr(dE)²`) and the geometric part `dF S⁺` is PSD with the
    /// positive part `S⁺` of the stress, so no eigen-decomposition of the 6×6 is needed;
    /// under tension (`S ⪰ 0`) this is the exact `K`.
    fn surrogate_stiffness(&self, f: usize, fg: &Matrix3x2<f64>) -> FHessian {
        let (_, s) = strain_and_stress(&self.params[f], fg);
        self.stiffness_with_stress(f, fg, &positive_part2(&s))
    }

    /// `A h [(g_aᵀS⁺g_b) I + μ (g_a·g_b) FFᵀ + μ (Fg_b)(Fg_a)ᵀ + λ (Fg_a)(Fg_b)ᵀ]` for the
    /// block of vertices `a, b`: the second variation of `ψ` along `u g_aᵀ` and `w g_bᵀ`
    /// (`⟨A, B S⟩ + 2μ⟨sym FᵀA, sym FᵀB⟩ + λ tr(FᵀA) tr(FᵀB)`, the geometric term with
    /// `S⁺`). The same matrix as `GᵀK̃G` through the 6×6 `K̃` (test), at a third of the
    /// arithmetic; the faces' Newton blocks were a tenth of a simulated frame.
    fn surrogate_element(
        &self,
        frames: &RestFrames,
        f: usize,
        fg: &Matrix3x2<f64>,
    ) -> SMatrix<f64, 9, 9> {
        let p = self.params[f];
        let s = positive_part2(&strain_and_stress(&p, fg).1);
        let (g, area) = frames.shape(f);
        let g: [Vector2<f64>; 3] = g.map(Vector2::from);
        let fg_a: [Vector3<f64>; 3] = g.map(|ga| fg * ga);
        let fft = fg * fg.transpose();
        let c = area * p.thickness;
        let mut h = SMatrix::<f64, 9, 9>::zeros();
        for a in 0..3 {
            for b in a..3 {
                let block: Matrix3<f64> = (Matrix3::identity() * g[a].dot(&(s * g[b]))
                    + fft * (p.mu * g[a].dot(&g[b]))
                    + fg_a[b] * fg_a[a].transpose() * p.mu
                    + fg_a[a] * fg_a[b].transpose() * p.lambda)
                    * c;
                h.fixed_view_mut::<3, 3>(3 * a, 3 * b).copy_from(&block);
                if a != b {
                    h.fixed_view_mut::<3, 3>(3 * b, 3 * a)
                        .copy_from(&block.transpose());
                }
            }
        }
        h
    }
}

impl Stretch {
    /// `K` with the stress of the geometric term `dF S` given (`S` itself for the exact
    /// Hessian, its positive part for the surrogate).
    fn stiffness_with_stress(&self, f: usize, fg: &Matrix3x2<f64>, s: &Matrix2<f64>) -> FHessian {
        let p = self.params[f];
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

crate::membrane::membrane_energy!(Stretch, "stretching");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::{hessian_of, HessianKind};
    use crate::sparse::BlockCsr;
    use crate::{Bending, RestAngle};
    use weft_mesh::primitives::grid;

    fn min_max_eigen(h: &BlockCsr) -> (f64, f64) {
        let d = h.to_dense();
        let e = d.symmetric_eigen().eigenvalues;
        (e.min(), e.max())
    }

    /// The closed-form face block is the generic `A GᵀK̃G` through the 6×6 `K̃`, under
    /// stretch, compression, shear and bending out of the plane.
    #[test]
    fn closed_form_surrogate_block_is_the_generic_one() {
        let rest = grid(4, 3, 0.1);
        let params = StretchParams {
            mu: 2e5,
            lambda: 7e4,
            thickness: 1e-3,
        };
        let s = Stretch::uniform(&rest, params).unwrap();
        for (a, b, shear) in [
            (1.1, 1.05, 0.0),
            (0.8, 0.9, 0.0),
            (1.2, 0.7, 0.3),
            (0.95, 1.0, -0.2),
        ] {
            let x: Vec<[f64; 3]> = rest
                .positions
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let t = i as f64;
                    [a * p[0] + shear * p[2], 0.03 * (1.3 * t).sin(), b * p[2]]
                })
                .collect();
            for f in 0..rest.faces.len() {
                let fg = s.frames.deformation_gradient(f, &x);
                let generic = s.frames.element_hessian(f, &s.surrogate_stiffness(f, &fg));
                let closed = s.surrogate_element(&s.frames, f, &fg);
                assert!(
                    (closed - generic).norm() <= 1e-12 * generic.norm(),
                    "face {f} at ({a}, {b}, {shear})"
                );
            }
        }
    }

    /// The Newton surrogate is the exact Hessian under tension, and PSD under
    /// compression where the exact one is indefinite; bending's surrogate is PSD and,
    /// at the rest angle, bounds the exact Hessian from above with fewer blocks.
    #[test]
    fn surrogate_is_exact_under_tension_and_psd_always() {
        let rest = grid(4, 4, 0.1);
        let params = StretchParams {
            mu: 1e5,
            lambda: 5e4,
            thickness: 1e-3,
        };
        let s = Stretch::uniform(&rest, params).unwrap();
        let scaled = |a: f64, b: f64| -> Vec<[f64; 3]> {
            rest.positions
                .iter()
                .map(|p| [a * p[0], 0.0, b * p[2]])
                .collect()
        };
        let tense = scaled(1.1, 1.05);
        let exact = hessian_of(&s, &tense, HessianKind::Exact)
            .unwrap()
            .to_dense();
        let surrogate = hessian_of(&s, &tense, HessianKind::Surrogate)
            .unwrap()
            .to_dense();
        assert!((&exact - &surrogate).norm() <= 1e-12 * exact.norm());
        let squashed = scaled(0.8, 0.9);
        let (lo, _) = min_max_eigen(&hessian_of(&s, &squashed, HessianKind::Exact).unwrap());
        assert!(
            lo < 0.0,
            "the exact Hessian is indefinite under compression"
        );
        let (lo, hi) = min_max_eigen(&hessian_of(&s, &squashed, HessianKind::Surrogate).unwrap());
        assert!(lo >= -1e-10 * hi, "surrogate eigenvalue {lo} (max {hi})");
        // Bending, folded away from flat.
        let b = Bending::uniform(&rest, 1e-3, Default::default(), Default::default()).unwrap();
        let mut folded = rest.positions.clone();
        for p in &mut folded {
            p[1] = 0.3 * (p[0] - 0.15).abs() + 0.2 * p[2] * p[2];
        }
        let (lo, hi) = min_max_eigen(&hessian_of(&b, &folded, HessianKind::Surrogate).unwrap());
        assert!(
            lo >= -1e-10 * hi.max(1e-30),
            "bending surrogate eigenvalue {lo}"
        );
        // At the rest angle the exact Hessian is the Gauss–Newton part `2kw∇θ∇θᵀ`; the
        // surrogate bounds it above (surrogate − exact is PSD), at most twice its trace,
        // with no block between a hinge's two wing vertices.
        let bent = weft_mesh::TriMesh::new(folded.clone(), rest.faces.clone());
        let b = Bending::uniform(&bent, 1e-3, Default::default(), RestAngle::FromRest).unwrap();
        let exact = hessian_of(&b, &folded, HessianKind::Exact)
            .unwrap()
            .to_dense();
        let surrogate = hessian_of(&b, &folded, HessianKind::Surrogate).unwrap();
        assert!(
            surrogate.stored_blocks()
                < hessian_of(&b, &folded, HessianKind::Exact)
                    .unwrap()
                    .stored_blocks()
        );
        let surrogate = surrogate.to_dense();
        let gap = (&surrogate - &exact).symmetric_eigen().eigenvalues;
        assert!(exact.norm() > 0.0);
        assert!(
            gap.min() >= -1e-12 * exact.norm(),
            "surrogate below the exact Hessian: {}",
            gap.min()
        );
        assert!(surrogate.trace() <= 2.0 * exact.trace() * (1.0 + 1e-9));
    }
}
