//! The training task of each system, one module per model: its items, loss terms and
//! weights, stages and validation metrics, and its run configuration. A new system adds
//! a module here implementing [`crate::TrainTask`]; the loop, optimisers, checkpoints and
//! metrics log are shared.

pub mod garfit;
pub mod hood;
pub mod multilevel;
pub mod refine;
