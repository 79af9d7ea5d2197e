//! Why a bench could not run.

/// Why a bench could not run: a bad option, or a stage of the measured pipeline that
/// failed (with its own error as the source).
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// An option is out of range; `what` names it.
    #[error("{what}: {message}")]
    Option {
        /// The option.
        what: &'static str,
        /// What was given and what was expected.
        message: String,
    },
    /// The device reported an error while running the queued operations.
    #[error("the device failed: {0}")]
    Device(String),
    /// A stage of the measured pipeline failed.
    #[error("{stage}")]
    Stage {
        /// What was being done.
        stage: &'static str,
        /// The stage's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

impl BenchError {
    /// A `map_err` adaptor: the error of `stage`.
    pub fn stage<E: std::error::Error + Send + Sync + 'static>(
        stage: &'static str,
    ) -> impl FnOnce(E) -> BenchError {
        move |e| BenchError::Stage {
            stage,
            source: Box::new(e),
        }
    }
}
