//! Why a body surface or a query could not be built from the data given.

/// What is wrong with the mesh, positions or parameters handed to a query structure.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum QueryError {
    /// The mesh has no triangles (or, for a vertex tree, no vertices): nothing to query.
    #[error("the mesh is empty ({vertices} vertices, {faces} faces); a query needs at least one {needed}")]
    Empty {
        /// Number of vertices given.
        vertices: usize,
        /// Number of faces given.
        faces: usize,
        /// `triangle` or `vertex`.
        needed: &'static str,
    },
    /// A face names a vertex that does not exist.
    #[error("face {face} names vertex {vertex}, but the mesh has {vertex_count} vertices")]
    FaceOutOfRange {
        /// 0-based face index.
        face: usize,
        /// The offending vertex index.
        vertex: u32,
        /// Number of vertices of the mesh.
        vertex_count: usize,
    },
    /// A position is NaN or infinite; boxes and distances would be meaningless.
    #[error("{what} {index} has a non-finite position {position:?}")]
    NonFinite {
        /// `vertex` or `query point`.
        what: &'static str,
        /// 0-based index.
        index: usize,
        /// The position found.
        position: [f64; 3],
    },
    /// A refit was given a position buffer of another length than the one the tree was
    /// built on (topology must stay fixed for a refit; rebuild instead).
    #[error("refit needs {expected} positions (the vertex count the tree was built on), got {found}; rebuild the tree when the topology changes")]
    CountMismatch {
        /// Vertex count at build time.
        expected: usize,
        /// Length of the buffer given.
        found: usize,
    },
    /// A radius that is negative or not finite.
    #[error("the search radius must be finite and non-negative, got {0}")]
    BadRadius(f64),
}
