//! Typed errors of the network layers.
//!
//! Every shape or index that a caller (ultimately a user's mesh or config file) controls is
//! checked at the API boundary and reported here, instead of panicking deep inside a tensor
//! kernel.

use weft_hierarchy::HierarchyError;

/// What can go wrong building or running a layer.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NnError {
    /// A tensor had the wrong shape for the layer it was fed to.
    #[error("{what}: expected shape {expected:?}, got {got:?}")]
    Shape {
        /// The tensor, named as the layer documents it.
        what: &'static str,
        /// The expected shape; `usize::MAX` marks a free dimension.
        expected: Vec<usize>,
        /// The shape that came in.
        got: Vec<usize>,
    },
    /// An index (vertex, node, row) was outside its range.
    #[error("{what}: index {index} is out of range for {len} entries")]
    Index {
        /// What the index points into.
        what: &'static str,
        /// The offending index.
        index: usize,
        /// The number of valid entries.
        len: usize,
    },
    /// A configuration value that cannot build a layer (zero heads, zero width, ratio
    /// outside (0, 1], ...).
    #[error("invalid configuration: {0}")]
    Config(String),
    /// A host value that must be finite (a feature, a statistic) was NaN or infinite.
    #[error("{what}: row {row}, column {column} is not finite ({value})")]
    NonFinite {
        /// The matrix, named as the function documents it.
        what: &'static str,
        /// Row of the value.
        row: usize,
        /// Column of the value.
        column: usize,
        /// The value.
        value: f32,
    },
    /// A batch needs at least one graph.
    #[error("a graph batch needs at least one graph")]
    EmptyBatch,
    /// The graph and the node features disagree on the number of nodes.
    #[error("{what}: the graph has {graph} nodes but the features have {features} rows")]
    NodeCount {
        /// The layer or operation.
        what: &'static str,
        /// Nodes in the graph.
        graph: usize,
        /// Rows of the feature tensor.
        features: usize,
    },
    /// Hierarchy construction failed.
    #[error(transparent)]
    Hierarchy(#[from] HierarchyError),
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, NnError>;

/// Checks that `got` equals `expected`, where `usize::MAX` in `expected` is a wildcard.
pub(crate) fn check_shape(what: &'static str, expected: &[usize], got: &[usize]) -> Result<()> {
    let ok = expected.len() == got.len()
        && expected
            .iter()
            .zip(got)
            .all(|(&e, &g)| e == usize::MAX || e == g);
    if ok {
        Ok(())
    } else {
        Err(NnError::Shape {
            what,
            expected: expected.to_vec(),
            got: got.to_vec(),
        })
    }
}

/// Wildcard dimension for [`check_shape`].
pub(crate) const ANY: usize = usize::MAX;
