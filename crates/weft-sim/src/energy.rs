//! The common shape of every energy: a pure function of the garment's vertex positions
//! with its value, exact gradient, and Hessian (exact or projected).
//!
//! Everything an energy depends on besides the positions (rest shape, materials, masses,
//! the inertial target, body contacts) is data it owns and that its owner refreshes
//! between evaluations, so each energy is testable on its own against finite
//! differences, and the same code serves the simulator (value, gradient, Hessian of the
//! incremental potential, seed 004 eq. 5) and the networks' unsupervised losses (value
//! and gradient on `f64` copies of predicted positions).

use crate::error::SimError;
use crate::sparse::BlockCsr;

/// Which Hessian to assemble (in TOML: `exact`, `projected`, `surrogate`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HessianKind {
    /// The exact second derivative (may be indefinite: StVK under compression, bending
    /// away from the rest angle, the seed 000 stretch term under compression).
    Exact,
    /// Per element, the exact element Hessian with its negative eigenvalues clamped to
    /// zero, so the assembled matrix is positive semi-definite and Newton's direction is
    /// a descent direction. Terms whose exact Hessian is already PSD return it unchanged.
    #[default]
    Projected,
    /// A cheaper positive semi-definite stand-in for Newton's matrix, built without
    /// eigen-decompositions of element blocks: membranes keep their (PSD) material part
    /// and use the positive part of the 2×2 stress in the geometric part (exact under
    /// tension, StVK), bending keeps the Gauss–Newton part `2kw ∇θ∇θᵀ`, and other terms
    /// project their small F-space (6×6) Hessian or are already PSD. Not a derivative:
    /// Newton with it still minimises the exact energy (the line search uses the exact
    /// value and gradient), only its convergence rate differs. Measured in
    /// `docs/physics.md`.
    Surrogate,
}

/// An energy over the positions of a garment with `vertex_count()` vertices.
///
/// Positions are `&[[f64; 3]]` in metres. Gradients are accumulated (`+=`) with a
/// `scale`, so a weighted sum of terms needs no temporary buffers.
pub trait Energy {
    /// A short name for logs and per-term breakdowns.
    fn name(&self) -> &'static str;

    /// The number of vertices the energy is defined over.
    fn vertex_count(&self) -> usize;

    /// The energy at `x`.
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError>;

    /// Adds `scale · ∇E(x)` to `grad` and returns `E(x)` (unscaled).
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError>;

    /// Adds `scale · ∇²E(x)` (of the given kind) into `hess`, whose pattern must hold
    /// this energy's stencils of that kind (see [`Energy::for_each_stencil`]).
    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError>;

    /// Calls `f` with the vertex set of every element that couples vertices in the
    /// Hessian of `kind` (faces, hinges). Per-vertex terms need not report anything:
    /// the diagonal is always in the pattern. The kind matters where a surrogate
    /// couples fewer vertices than the exact Hessian (bending).
    fn for_each_stencil(&self, kind: HessianKind, f: &mut dyn FnMut(&[u32]));
}

/// A convenience: the gradient of `energy` at `x` in a fresh buffer, with the value.
pub fn gradient_of<E: Energy + ?Sized>(
    energy: &E,
    x: &[[f64; 3]],
) -> Result<(f64, Vec<[f64; 3]>), SimError> {
    let mut g = vec![[0.0; 3]; energy.vertex_count()];
    let v = energy.add_gradient(x, 1.0, &mut g)?;
    Ok((v, g))
}

/// A convenience: the sparsity pattern of `energy`'s Hessian of `kind`, all values zero.
pub fn hessian_pattern_of<E: Energy + ?Sized>(energy: &E, kind: HessianKind) -> BlockCsr {
    let mut b = crate::sparse::PatternBuilder::new(energy.vertex_count());
    energy.for_each_stencil(kind, &mut |s| b.add(s));
    b.build()
}

/// A convenience: the Hessian of `energy` at `x` in a fresh matrix.
pub fn hessian_of<E: Energy + ?Sized>(
    energy: &E,
    x: &[[f64; 3]],
    kind: HessianKind,
) -> Result<BlockCsr, SimError> {
    let mut h = hessian_pattern_of(energy, kind);
    energy.add_hessian(x, 1.0, kind, &mut h)?;
    Ok(h)
}
