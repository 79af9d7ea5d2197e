//! Learned garment deformation models for weft.
//!
//! - [`multilevel`]: the Multilevel model of seed 000 (multi-source garment graph,
//!   structure-preserving pooling, temporal skinning weights and blend shapes, LBS).

pub mod error;
pub mod multilevel;

pub use error::ModelError;
