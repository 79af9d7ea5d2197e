//! [`PipelineError`]: what stopped a pipeline, with the stage and its cause.

use std::path::PathBuf;

/// What can stop a pipeline. The stage wrappers keep their cause, so the CLI prints the
/// whole chain on one line.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Training failed.
    #[error(transparent)]
    Train(#[from] weft_train::TrainError),
    /// Evaluation or export failed.
    #[error(transparent)]
    Eval(#[from] weft_eval::EvalError),
    /// A model or baseline could not be built, loaded or run.
    #[error(transparent)]
    Model(#[from] weft_models::ModelError),
    /// The dataset could not be generated or read.
    #[error(transparent)]
    Data(#[from] weft_data::DataError),
    /// A picture or report could not be drawn or written.
    #[error(transparent)]
    Render(#[from] weft_render::RenderError),
    /// A stage failed; the cause says why.
    #[error("{stage}")]
    Stage {
        /// What was being done.
        stage: String,
        /// The cause.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A file or directory could not be written.
    #[error("{}: cannot write", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A request this build cannot serve, with what to do instead.
    #[error("{0}")]
    Invalid(String),
}

/// Wraps an error as a [`PipelineError::Stage`] named `stage`.
pub(crate) fn stage<E>(stage: &str) -> impl Fn(E) -> PipelineError + '_
where
    E: std::error::Error + Send + Sync + 'static,
{
    move |e| PipelineError::Stage {
        stage: stage.to_string(),
        source: Box::new(e),
    }
}
