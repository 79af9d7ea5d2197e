//! The implicit-Euler simulator: each step minimises the incremental potential
//! (seed 004 eq. 5) over the end-of-step positions with Newton's method.
//!
//! * [`pcg`]: preconditioned conjugate gradients on the 3×3-block Hessian (block
//!   Jacobi, or [`two_level`]'s block Jacobi plus a coarse solve on aggregates).
//! * [`newton`]: projected Newton (per-element PSD Hessians), PCG for the direction,
//!   backtracking (Armijo) line search, pinned vertices held at their targets.
//! * [`simulator`]: the time loop: inertial target, body contacts, friction anchors,
//!   pinning, divergence detection.
//!
//! Why Newton–PCG rather than projective dynamics: the energies here (StVK, the seed 000
//! terms, the cubic penalty, friction) are not all quadratic-plus-projection, and the
//! same potential is the networks' loss, so the simulator minimises exactly that
//! potential; projective dynamics would minimise a different one.

pub mod newton;
pub mod pcg;
pub mod simulator;
pub mod two_level;

pub use newton::{minimize, NewtonOptions, NewtonReport, PreconditionerKind};
pub use pcg::{pcg, pcg_with, BlockJacobi, PcgReport, Preconditioner};
pub use simulator::{ClothSimulator, SimOptions, StepReport};
pub use two_level::{Aggregates, TwoLevel};
