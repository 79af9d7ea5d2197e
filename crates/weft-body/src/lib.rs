//! Bodies for weft: the SMPL-format body model (v_template, shapedirs, posedirs,
//! J_regressor, weights, kintree_table, f), rotations (Rodrigues, dual quaternions),
//! forward kinematics over the kinematic tree, linear blend and dual quaternion
//! skinning. Motions (the poses that drive a body over time) live in `weft-motion`.
//!
//! A geometry crate: no learning dependency, so it builds and tests in seconds.

pub mod default_body;
pub mod error;
pub mod features;
pub mod joints;
pub mod kinematics;
pub mod model;
pub mod mpfb;
pub mod posed;
pub mod query;
pub mod rotation;
pub mod skinning;

pub use default_body::default_body;
pub use error::BodyError;
pub use joints::Pose;
pub use model::{BodyModel, BodyParts, ShapedBody, BETA_LIMIT};
pub use posed::PosedSequence;
pub use skinning::Skinning;
