//! Learned garment deformation models for weft.
//!
//! - [`multilevel`]: the Multilevel model of seed 000 (multi-source garment graph,
//!   structure-preserving pooling, temporal skinning weights and blend shapes, LBS).
//! - [`kind`]: [`ModelKind`], the systems by name.
//! - [`run`]: the one owner of the run directory (layout, header, `latest`).

pub mod error;
pub mod kind;
pub mod multilevel;
pub mod run;

pub use error::ModelError;
pub use kind::{ModelKind, UnknownModelKind};
pub use run::{RunHeader, RunLayout};
