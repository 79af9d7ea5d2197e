//! Datasets for weft: garments simulated on bodies performing motions, stored as one
//! safetensors shard per sequence plus a JSON manifest, split into train / validation /
//! test sets that share no garment, no body shape and no motion (seed 000 §4).
//!
//! * [`config`]: what to generate (TOML; presets `tiny` and `paper`).
//! * [`plan`]: the config resolved into ids, seeds, shapes and sequences, and the
//!   no-overlap check.
//! * [`generate()`]: parallel, resumable, shardable generation through weft-sim.
//! * [`import()`]: a user's own simulation caches as a dataset.
//! * [`manifest`] and [`shard`]: the files on disk.
//! * [`Dataset`]: the loader the training code uses.
//! * [`info`]: the summary of `weft data info`.
//! * [`characters`]: seed 001's case-1 datasets (dressed characters, poses and a
//!   ground-truth deformation of each), built by `weft data characters`.
//!
//! See docs/datasets.md for the layout, the presets and how cluster jobs merge.

pub mod characters;
pub mod config;
pub mod dataset;
pub mod error;
pub mod generate;
pub mod import;
pub mod info;
pub mod manifest;
pub mod plan;
pub mod progress;
pub mod shard;
pub mod split;
mod tensors;

pub use config::{DataConfig, GarmentSpec, MotionSpec, SplitConfig};
pub use dataset::{Dataset, Sequence};
pub use error::DataError;
pub use generate::{
    generate, GenerateOptions, GenerateReport, Physics, Progress, SequenceSimulator, Silent,
    SimInput, SimOutcome,
};
pub use import::{import, ImportReport, ImportSpec};
pub use info::DatasetInfo;
pub use manifest::{merge_directory, Job, Manifest, SequenceRecord, Status};
pub use split::Split;
