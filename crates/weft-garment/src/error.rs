//! Errors of garment generation: everything a user can get wrong is a typed error here,
//! so the CLI can print one line and exit non-zero instead of panicking.

use thiserror::Error;

/// Why a garment could not be generated or written.
#[derive(Debug, Error)]
pub enum GarmentError {
    /// The kind name is not one of the known kinds.
    #[error("unknown garment kind `{0}` (expected one of: {kinds})", kinds = crate::GarmentKind::NAMES.join(", "))]
    UnknownKind(String),
    /// The requested vertex count is outside the supported range.
    #[error("--vertices {got} is out of range: choose {min} to {max}")]
    VertexCount {
        /// What was asked for.
        got: usize,
        /// Smallest supported count.
        min: usize,
        /// Largest supported count.
        max: usize,
    },
    /// A style parameter is out of its range or not finite.
    #[error("style parameter {name} = {value} is out of range {range}")]
    Style {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
    /// Measurements taken from a body are unusable (non-finite or non-positive).
    #[error("body measurements unusable: {0}")]
    Measurements(String),
    /// The body model failed (bad β count, …).
    #[error(transparent)]
    Body(#[from] weft_body::BodyError),
    /// The garment cannot be opened down the front.
    #[error("cannot open the garment down the front: {0}")]
    OpenFront(String),
    /// Writing the garment failed.
    #[error("cannot write {path}")]
    Io {
        /// The destination.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
}
