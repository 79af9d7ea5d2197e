//! Why a body feature could not be computed from the data given.

use crate::query::QueryError;

/// What is wrong with the arrays or parameters handed to a feature function.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FeatureError {
    /// Two arrays that must have matching lengths do not.
    #[error("{what}: expected {expected}, found {found}")]
    CountMismatch {
        /// Which arrays, e.g. `weights rows vs rest positions`.
        what: &'static str,
        /// The length required.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// A flat weight (or feature) buffer whose length is not a multiple of the joint
    /// count, or a joint count of zero.
    #[error("a row-major matrix of {cols} columns cannot hold {len} values (need a multiple of {cols}, and at least one column)")]
    Shape {
        /// Length of the flat buffer.
        len: usize,
        /// Columns (joints) requested.
        cols: usize,
    },
    /// A NaN or infinite value.
    #[error("{what} {index} is not finite")]
    NonFinite {
        /// What holds it, e.g. `vertex`, `joint`, `weight`.
        what: &'static str,
        /// 0-based index (row-major for matrices).
        index: usize,
    },
    /// A skinning weight below zero.
    #[error("skinning weight of vertex {vertex} for joint {joint} is {value}; weights must be non-negative")]
    NegativeWeight {
        /// Vertex (row).
        vertex: usize,
        /// Joint (column).
        joint: usize,
        /// The value found.
        value: f64,
    },
    /// A vertex whose weights are all zero: it follows no joint.
    #[error("vertex {vertex} has skinning weights summing to zero; every vertex must follow at least one joint")]
    ZeroWeightRow {
        /// Vertex (row).
        vertex: usize,
    },
    /// A kinematic tree whose parent links are not a forest ordered parents-first.
    #[error(
        "joint {joint} has parent {parent}; a parent must be an earlier joint (index < {joint})"
    )]
    BadParent {
        /// The joint.
        joint: usize,
        /// Its parent as given.
        parent: usize,
    },
    /// A parameter outside its valid range.
    #[error("{name} = {value} is invalid: {expected}")]
    BadParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// A frame index past the end of a sequence.
    #[error("frame {frame} is out of range for a sequence of {frames} frames")]
    FrameOutOfRange {
        /// The frame asked for.
        frame: usize,
        /// Frames available.
        frames: usize,
    },
    /// Posing the body model failed (its message).
    #[error("posing the body: {0}")]
    Posing(String),
    /// A spatial query failed (bad mesh or point).
    #[error(transparent)]
    Query(#[from] QueryError),
}
