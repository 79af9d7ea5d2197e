//! Cloth physics for weft: materials, the energies of the incremental potential with
//! exact gradients and Hessians, and the implicit-Euler simulator built on them.
//!
//! Seed 004 (HOOD) eq. 5 sums StVK stretching ([`Stretch`]), dihedral bending
//! ([`Bending`]), gravity ([`Gravity`]), friction ([`Friction`]), a cubic collision
//! penalty ([`CubicCollision`]) and implicit-Euler inertia ([`Inertia`]) into the
//! incremental potential ([`IncrementalPotential`]); minimising it over the end-of-step
//! positions is one implicit-Euler step, and its value is HOOD's self-supervised loss.
//! Seed 000's unsupervised losses (supplement eq. 4–8) are in [`penalties`].
//!
//! A garment's physics (rest shape, per-face, per-hinge and per-vertex materials,
//! masses, options) is a [`ClothModel`]; its [`ClothModel::step_potential`] is the one
//! builder of a step's potential, used by the simulator ([`ClothSimulator`]) and by
//! HOOD's loss alike. HOOD's training materials: [`hood_material`].
//!
//! Every energy implements [`Energy`]: value, gradient, and a Hessian, exact or
//! projected to positive semi-definite per element ([`HessianKind`]), scattered into a
//! 3×3-block sparse matrix ([`BlockCsr`]) whose product and diagonal blocks feed
//! preconditioned conjugate gradients. Positions are plain `&[[f64; 3]]` so the networks
//! can evaluate losses on `f64` copies of their predictions. Body contacts are plain data
//! ([`BodyContact`]); the posed body ([`PosedBody`], on weft-body's closest-point
//! queries) provides them, and [`simulate_sequence`] runs a garment on a body that follows
//! a motion, with sub-steps and the body moving continuously between frames.
//!
//! Physics is `f64`, metres, seconds, kilograms, Y up. Derivations, equation numbers and
//! material sources: `docs/physics.md`.

pub mod attachment;
pub mod bending;
pub mod body;
pub mod buttons;
pub mod cloth;
pub mod collision;
pub mod contact;
pub mod elastic_skin;
pub mod energy;
pub mod error;
pub mod face_contact;
pub mod friction;
pub mod gravity;
pub mod hood_material;
pub mod inertia;
pub mod material;
mod math;
pub mod membrane;
pub mod penalties;
pub mod potential;
pub mod sequence;
pub mod solver;
pub mod sparse;
pub mod strain_limit;
pub mod stretch;
pub mod swept;

#[cfg(test)]
mod fd_tests;

pub use attachment::{Attachment, SkinAnchors};
pub use bending::{Bending, BendingScale, RestAngle};
pub use body::{check_garment_gap, Penetration, PosedBody, MAX_GARMENT_GAP};
pub use buttons::Buttons;
pub use cloth::{ClothModel, StepContacts, StepInputs};
pub use collision::CubicCollision;
pub use contact::{
    project_contacts, BodyContact, BodyProximity, Clearance, Grip, Plane, Proximity, Sphere,
    VertexContact,
};
pub use elastic_skin::{ConeVolume, ElasticSkin, ElasticSkinParams, ElasticSkinReport};
pub use energy::{gradient_of, hessian_of, hessian_pattern_of, Energy, HessianKind};
pub use error::SimError;
pub use face_contact::FaceContact;
pub use friction::{Friction, FrictionContact};
pub use gravity::{lumped_masses, Gravity, STANDARD_GRAVITY};
pub use hood_material::{
    MaterialRanges, MaterialSampler, HOOD_BENDING_RANGE, HOOD_DENSITY_RANGE, HOOD_LAMBDA_RANGE,
    HOOD_MU_RANGE,
};
pub use inertia::{inertial_target, Inertia};
pub use material::Material;
pub use membrane::RestFrames;
pub use penalties::{LinearCollision, UvShear, UvStretch};
pub use potential::{IncrementalPotential, Term, WeightedTerm};
pub use sequence::{
    simulate_sequence, FrameStats, SequenceError, SequenceOptions, SequenceProgress,
    SimulatedSequence, MAX_SUBSTEPS, MAX_WARMUP_FRAMES,
};
pub use solver::{ClothSimulator, NewtonOptions, PreconditionerKind, SimOptions};
pub use sparse::{BlockCsr, ElementGather, GatherCache, PatternBuilder};
pub use strain_limit::{StrainBounds, StrainLimit, StrainLimited};
pub use stretch::{Stretch, StretchParams};
pub use swept::SweptBody;
