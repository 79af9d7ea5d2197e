//! Errors of garment preparation, each naming what was wrong and what was expected.

use thiserror::Error;

/// Why a garment could not be resized, draped or rewritten.
#[derive(Debug, Error)]
pub enum PrepareError {
    /// The two shaped bodies of a resize are not the same mesh (vertex count or faces).
    #[error("resize needs one body model at two shapes: the bodies differ ({0})")]
    BodyMismatch(String),
    /// The garment has no vertices or a non-finite coordinate.
    #[error("garment vertex {index} is not finite: {position:?}")]
    NonFinite {
        /// The vertex.
        index: usize,
        /// Its position.
        position: [f64; 3],
    },
    /// The start positions of a drape are not one per pattern vertex.
    #[error("start positions: {given} given for a pattern of {expected} vertices; expected one start position per pattern vertex")]
    StartPositions {
        /// Positions given.
        given: usize,
        /// Pattern vertices.
        expected: usize,
    },
    /// A body query failed.
    #[error("body query: {0}")]
    Query(#[from] weft_body::query::QueryError),
    /// A drape starts with vertices deeper inside the body than push-out can repair.
    #[error(
        "{count} garment vertices start more than {limit_mm:.0} mm inside the body (deepest {deepest_mm:.1} mm at vertex {vertex}): \
         push-out would pull them through to the wrong side; fit the garment to this body first (weft garment resize)"
    )]
    DeeplyInside {
        /// Vertices deeper than the limit.
        count: usize,
        /// The deepest one.
        vertex: usize,
        /// Its depth, mm.
        deepest_mm: f64,
        /// The limit, mm.
        limit_mm: f64,
    },
    /// A drape option is out of range.
    #[error("drape option {name} = {value} is out of range: expected {expected}")]
    Option {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The accepted range, in words.
        expected: &'static str,
    },
    /// The simulator could not be set up (bad material, a body mesh it cannot query).
    #[error(transparent)]
    Sim(#[from] weft_sim::SimError),
    /// A simulator step failed (diverged); `frame` is the drape frame.
    #[error("drape frame {frame}")]
    Simulation {
        /// The frame that failed (0-based).
        frame: usize,
        /// The cause.
        #[source]
        source: weft_sim::SimError,
    },
    /// The garment OBJ text does not match the positions to write into it.
    #[error("{path}: {message}")]
    ObjText {
        /// The file.
        path: String,
        /// What does not match.
        message: String,
    },
    /// Generation-side failure (body measurements, push-out).
    #[error(transparent)]
    Garment(#[from] crate::GarmentError),
}
