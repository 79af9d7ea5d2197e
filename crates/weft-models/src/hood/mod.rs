//! HOOD (seed 004): a hierarchical graph network that predicts a garment's next state
//! from its current one and the moving body, trained from the physics alone (the
//! incremental potential, weft-sim) instead of simulated ground truth.
//!
//! - [`config`]: widths, levels, the message-passing schedule as data, presets;
//! - [`garment`]: a garment's levels, pins, masses, materials and buttons;
//! - [`features`]: one step's graph (garment and body nodes, mesh edges per level, body
//!   edges both ways) with its input features;
//! - [`stats`]: the four normalisers a run keeps (`hood.json`);
//! - [`model`]: the encode–process–decode network over a batch of step graphs, and its
//!   inference form for rollouts;
//! - [`rollout`]: the output integrated to `x_{t+1}`, and autoregressive rollouts of
//!   several scenes at once;
//! - [`scene`]: a garment on a moving body (posed frames, skinned start, pinned targets);
//! - [`predictor`]: a trained run as a [`crate::Deformer`].

pub mod config;
pub mod features;
pub mod garment;
pub mod model;
pub mod predictor;
pub mod rollout;
pub mod scene;
pub mod stats;
#[cfg(test)]
pub(crate) mod testutil;

pub use config::HoodConfig;
pub use garment::HoodGarment;
pub use model::{Hood, HoodBatch, HoodInput, InferHood};
pub use predictor::{HoodPredictor, OUTSIDE_MATERIAL_SPACE};
pub use rollout::{
    roll_out, Advance, Corrections, Corrector, Rollout, RolloutOptions, CONTACT_ROUNDS,
    ROUND_SWEEPS, STRAIN_LIMIT_SWEEPS,
};
pub use scene::{Materials, Scene, State, StateRef, StepAt, StepBodies};
pub use stats::{HoodStats, HoodStatsFit, STATS_FILE};
