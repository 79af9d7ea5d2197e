//! The Multilevel model of seed 000 ("Efficient deformation learning of varied garments
//! with a structure-preserving multilevel framework"): design notes in
//! docs/multilevel.md.
//!
//! - [`config`]: every width and depth, presets `paper` and `cpu`;
//! - [`garment`]: [`GarmentInput`], the constant inputs of a garment–body pair;
//! - [`frames`]: [`FrameInputs`], the inputs of a window of frames;
//! - [`contact`]: where the posed body is, seen from each garment vertex (`body_contact`);
//! - [`mp`]: one submodule of M^mp (pooling, GAT blocks, unpooling, skips);
//! - [`model`]: [`Multilevel`], [`PairEncoding`], [`Prediction`];
//! - [`predictor`]: [`Predictor`], a trained run loaded for inference.

pub mod config;
pub mod contact;
pub mod frames;
pub mod garment;
pub mod model;
pub mod mp;
pub mod predictor;

pub use config::{MultilevelConfig, PoolingKind, NO_DRAPE, PRESETS};
pub use frames::FrameInputs;
pub use garment::GarmentInput;
pub use model::{Multilevel, PairEncoding, Prediction};
pub use predictor::{Predictor, RUN_FORMAT_VERSION};
