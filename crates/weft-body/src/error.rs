//! Typed errors of body models: every variant names the model's file (or "the default
//! body") and, for bad content, the array (`key`) and what was expected.

use weft_mesh::io::npz::NpzError;
use weft_mesh::MeshError;

use crate::kinematics::KinematicsError;

/// What went wrong loading, checking, shaping, posing or writing a body model.
#[derive(Debug, thiserror::Error)]
pub enum BodyError {
    /// Reading or writing the `.npz` failed, or an array has the wrong dtype or shape.
    #[error(transparent)]
    Npz(#[from] NpzError),
    /// Writing a mesh failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// An array has the right shape but content the model cannot use.
    #[error("{source_name}: `{key}`: {message}")]
    Invalid {
        /// The model's file, or `default body`.
        source_name: String,
        /// The array.
        key: &'static str,
        /// What is wrong and what was expected.
        message: String,
    },
    /// More shape coefficients than the model has.
    #[error("{source_name}: {given} shape coefficients (betas) given but the model has {available}; expected at most {available}")]
    Betas {
        /// The model's file, or `default body`.
        source_name: String,
        /// How many were given.
        given: usize,
        /// How many the model has.
        available: usize,
    },
    /// A non-finite shape coefficient, pose angle or translation.
    #[error("{what} {index} is {value}; expected a finite number")]
    NonFinite {
        /// Which input (`beta`, `pose angle`, `translation`).
        what: &'static str,
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A pose that does not fit the skeleton.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// A posed surface could not be built for queries.
    #[error(transparent)]
    Query(#[from] crate::query::QueryError),
}
