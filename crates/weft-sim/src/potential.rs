//! The incremental potential (seed 004 eq. 5): a weighted sum of energies whose minimum
//! over the end-of-step positions is one implicit-Euler step, and whose value and
//! gradient are the networks' unsupervised losses (HOOD's loss is eq. 5 itself; the
//! Multilevel system's are seed 000 supplement eq. 4–7).
//!
//! Terms are a closed set ([`Term`]) plus [`Term::Custom`], so that the simulator can
//! reach in and refresh the per-step data (inertial target, contacts, friction anchors)
//! without downcasting.

use crate::bending::Bending;
use crate::buttons::Buttons;
use crate::collision::CubicCollision;
use crate::energy::{Energy, HessianKind};
use crate::error::{check_eval, check_len, Output, SimError};
use crate::friction::Friction;
use crate::gravity::Gravity;
use crate::inertia::Inertia;
use crate::penalties::{LinearCollision, UvShear, UvStretch};
use crate::sparse::{BlockCsr, PatternBuilder};
use crate::stretch::Stretch;

/// One term of the potential.
pub enum Term {
    /// StVK stretching.
    Stretch(Stretch),
    /// Dihedral bending.
    Bending(Bending),
    /// Gravity.
    Gravity(Gravity),
    /// Implicit-Euler inertia.
    Inertia(Inertia),
    /// Cubic collision penalty.
    Collision(CubicCollision),
    /// Friction.
    Friction(Friction),
    /// Button pairs held together.
    Buttons(Buttons),
    /// Seed 000 eq. 4.
    LinearCollision(LinearCollision),
    /// Seed 000 eq. 6.
    UvStretch(UvStretch),
    /// Seed 000 eq. 7.
    UvShear(UvShear),
    /// Anything else.
    Custom(Box<dyn Energy + Send + Sync>),
}

impl std::fmt::Debug for Term {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Term({})", self.energy().name())
    }
}

impl Term {
    /// The term as an energy.
    pub fn energy(&self) -> &dyn Energy {
        match self {
            Term::Stretch(e) => e,
            Term::Bending(e) => e,
            Term::Gravity(e) => e,
            Term::Inertia(e) => e,
            Term::Collision(e) => e,
            Term::Friction(e) => e,
            Term::Buttons(e) => e,
            Term::LinearCollision(e) => e,
            Term::UvStretch(e) => e,
            Term::UvShear(e) => e,
            Term::Custom(e) => e.as_ref(),
        }
    }
}

/// A term with its weight.
#[derive(Debug)]
pub struct WeightedTerm {
    /// The weight (`>= 0`).
    pub weight: f64,
    /// The term.
    pub term: Term,
}

/// `Σ_k w_k E_k(x)` over the positions of one garment.
#[derive(Debug)]
pub struct IncrementalPotential {
    vertex_count: usize,
    terms: Vec<WeightedTerm>,
}

macro_rules! term_access {
    ($get:ident, $get_mut:ident, $variant:ident, $t:ty) => {
        /// The first term of this kind.
        pub fn $get(&self) -> Option<&$t> {
            self.terms.iter().find_map(|t| match &t.term {
                Term::$variant(e) => Some(e),
                _ => None,
            })
        }
        /// The first term of this kind, mutable (to refresh per-step data).
        pub fn $get_mut(&mut self) -> Option<&mut $t> {
            self.terms.iter_mut().find_map(|t| match &mut t.term {
                Term::$variant(e) => Some(e),
                _ => None,
            })
        }
    };
}

impl IncrementalPotential {
    /// An empty potential over `vertex_count` vertices.
    pub fn new(vertex_count: usize) -> Self {
        IncrementalPotential {
            vertex_count,
            terms: Vec::new(),
        }
    }

    /// Adds a term with weight `weight >= 0`.
    pub fn push(&mut self, weight: f64, term: Term) -> Result<(), SimError> {
        crate::error::check_nonneg(
            || format!("weight of {}", term.energy().name()),
            weight,
            false,
        )?;
        check_len(
            term.energy().name(),
            self.vertex_count,
            term.energy().vertex_count(),
        )?;
        self.terms.push(WeightedTerm { weight, term });
        Ok(())
    }

    /// Builder form of [`IncrementalPotential::push`].
    pub fn with(mut self, weight: f64, term: Term) -> Result<Self, SimError> {
        self.push(weight, term)?;
        Ok(self)
    }

    /// The terms.
    pub fn terms(&self) -> &[WeightedTerm] {
        &self.terms
    }

    /// The terms, mutable (weights and per-step data).
    pub fn terms_mut(&mut self) -> &mut [WeightedTerm] {
        &mut self.terms
    }

    term_access!(stretch, stretch_mut, Stretch, Stretch);
    term_access!(bending, bending_mut, Bending, Bending);
    term_access!(gravity, gravity_mut, Gravity, Gravity);
    term_access!(inertia, inertia_mut, Inertia, Inertia);
    term_access!(collision, collision_mut, Collision, CubicCollision);
    term_access!(friction, friction_mut, Friction, Friction);
    term_access!(
        linear_collision,
        linear_collision_mut,
        LinearCollision,
        LinearCollision
    );

    /// The value of each term (unweighted) with its name and weight, for logs and
    /// statistics.
    pub fn breakdown(&self, x: &[[f64; 3]]) -> Result<Vec<(&'static str, f64, f64)>, SimError> {
        self.terms
            .iter()
            .map(|t| Ok((t.term.energy().name(), t.weight, t.term.energy().value(x)?)))
            .collect()
    }

    /// The gradient in a fresh buffer, with the value.
    pub fn gradient(&self, x: &[[f64; 3]]) -> Result<(f64, Vec<[f64; 3]>), SimError> {
        let mut g = vec![[0.0; 3]; self.vertex_count];
        let v = self.add_gradient(x, 1.0, &mut g)?;
        Ok((v, g))
    }

    /// The sparsity pattern of the Hessian of `kind` (all values zero); build it once
    /// per garment and reuse it with [`IncrementalPotential::hessian_into`].
    pub fn hessian_pattern(&self, kind: HessianKind) -> BlockCsr {
        let mut b = PatternBuilder::new(self.vertex_count);
        self.for_each_stencil(kind, &mut |s| b.add(s));
        b.build()
    }

    /// Overwrites `hess` (built by [`IncrementalPotential::hessian_pattern`] of the
    /// same `kind`) with the Hessian at `x`.
    pub fn hessian_into(
        &self,
        x: &[[f64; 3]],
        kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError> {
        hess.set_zero();
        self.add_hessian(x, 1.0, kind, hess)
    }

    /// The Hessian at `x` in a fresh matrix.
    pub fn hessian(&self, x: &[[f64; 3]], kind: HessianKind) -> Result<BlockCsr, SimError> {
        let mut h = self.hessian_pattern(kind);
        self.add_hessian(x, 1.0, kind, &mut h)?;
        Ok(h)
    }
}

impl Energy for IncrementalPotential {
    fn name(&self) -> &'static str {
        "incremental potential"
    }
    fn vertex_count(&self) -> usize {
        self.vertex_count
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        let mut e = 0.0;
        for t in &self.terms {
            if t.weight != 0.0 {
                e += t.weight * t.term.energy().value(x)?;
            }
        }
        Ok(e)
    }
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Gradient(grad.len()))?;
        let mut e = 0.0;
        for t in &self.terms {
            if t.weight != 0.0 {
                e += t.weight * t.term.energy().add_gradient(x, scale * t.weight, grad)?;
            }
        }
        Ok(e)
    }
    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError> {
        for t in &self.terms {
            if t.weight != 0.0 {
                t.term
                    .energy()
                    .add_hessian(x, scale * t.weight, kind, hess)?;
            }
        }
        Ok(())
    }
    fn for_each_stencil(&self, kind: HessianKind, f: &mut dyn FnMut(&[u32])) {
        for t in &self.terms {
            t.term.energy().for_each_stencil(kind, f);
        }
    }
}
