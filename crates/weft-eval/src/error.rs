//! Why an evaluation could not be done, naming the file, array or value at fault.

use std::path::PathBuf;

/// Everything weft-eval can fail on.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// Two arrays that must agree in length do not.
    #[error("{what}: expected {expected}, found {found}")]
    Count {
        /// Which arrays.
        what: &'static str,
        /// The length required.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// An input that makes no sense, with the reason.
    #[error("{0}")]
    Invalid(String),
    /// A body query failed (empty or non-finite body).
    #[error(transparent)]
    Query(#[from] weft_body::query::QueryError),
    /// A body model operation failed.
    #[error(transparent)]
    Body(#[from] weft_body::BodyError),
    /// A body feature (weight transfer) failed.
    #[error(transparent)]
    Feature(#[from] weft_body::features::FeatureError),
    /// A picture or report could not be drawn or written.
    #[error(transparent)]
    Render(#[from] weft_render::RenderError),
    /// A deformer (a model or a baseline) refused its input or failed.
    #[error(transparent)]
    Model(#[from] weft_models::ModelError),
    /// The dataset could not be read.
    #[error(transparent)]
    Data(#[from] weft_data::DataError),
    /// A file could not be read or written.
    #[error("{}: cannot read or write the file", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A JSON file is not what was expected.
    #[error("{}: not the JSON expected", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        source: serde_json::Error,
    },
    /// A tensor operation (attribution gradients) failed.
    #[error("network: {0}")]
    Network(String),
}
