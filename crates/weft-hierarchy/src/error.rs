//! Typed errors of hierarchy construction.

/// What can go wrong building a hierarchy.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum HierarchyError {
    /// Unpooling needs a kept vertex in every component of the fine graph.
    #[error("vertex {vertex}: its connected component keeps no vertex, so unpooling has nothing to fill it from")]
    NoKeptVertex {
        /// The fine vertex that cannot be filled.
        vertex: usize,
    },
    /// Given pooling centres must be one per connected component, in component order
    /// (components numbered by their smallest vertex).
    #[error("pooling centres: {0}")]
    BadCenters(String),
    /// A hierarchy has at least its finest level.
    #[error("a hierarchy needs at least 1 level, got 0")]
    NoLevels,
}
