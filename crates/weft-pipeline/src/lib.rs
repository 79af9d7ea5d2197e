//! weft's pipelines: the steps a user runs, as library calls that the `weft` binary and
//! the demo share, so both take the same path and a test can run it in-process.
//!
//! - [`train`]: resolve a model kind's configuration and train it into a run directory;
//! - [`evaluate`]: any run directory (whatever its model kind) against the LBS and DQS
//!   baselines on a dataset split, with its report;
//! - [`characters`]: refinement runs and the skinning baselines on a character dataset
//!   (seed 001's tables, in cm);
//! - [`demo`]: data → training → evaluation → animation → attribution → report;
//! - [`stand_in`]: a cheap simulator for dry runs of the pipeline.
//!
//! This crate sits above weft-train and weft-eval so that neither depends on the other.

pub mod characters;
pub mod demo;
pub mod error;
pub mod evaluate;
pub mod stand_in;
pub mod train;

pub use error::PipelineError;
