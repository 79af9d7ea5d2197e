//! Errors of training: configuration, data, run directories and checkpoints, and
//! losses that stop being finite.

use std::path::PathBuf;

/// Everything a training run can fail on, with the file, field or step it concerns.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// A configuration value out of its range.
    #[error("training config: {field} = {value}: {expected}")]
    Config {
        /// The field, as in config.toml.
        field: String,
        /// The value found.
        value: String,
        /// What is expected instead.
        expected: String,
    },
    /// Reading or writing a file of the run.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A config.toml or a trainer state that does not parse.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A checkpoint that does not belong to this run's configuration.
    #[error(
        "{}: checkpoint does not match this run: {field} is {found} in the checkpoint, {expected} here; \
         start a new run directory or pass the same preset and config",
        path.display()
    )]
    Mismatch {
        /// The checkpoint or config file.
        path: PathBuf,
        /// The field that differs (`format_version`, `preset`, `model.<key>`, ...).
        field: String,
        /// The value in the checkpoint.
        found: String,
        /// The value of this run.
        expected: String,
    },
    /// A model record or optimizer record burn could not read or apply.
    #[error("{}: {message}", path.display())]
    Record {
        /// The file.
        path: PathBuf,
        /// burn's message.
        message: String,
    },
    /// `--resume` on a directory without a checkpoint, or a new run over an old one.
    #[error("{}: {message}", path.display())]
    RunDir {
        /// The run directory.
        path: PathBuf,
        /// What is wrong and what to do.
        message: String,
    },
    /// A loss term stopped being finite too many times in a row.
    #[error(
        "loss term `{term}` was not finite at step {step} ({consecutive} steps in a row, limit {limit}); \
         training stopped at the last good state (lower the learning rate or check the data)"
    )]
    NonFinite {
        /// The first non-finite term of the last failed step.
        term: String,
        /// The step.
        step: usize,
        /// How many steps in a row failed.
        consecutive: usize,
        /// The configured limit.
        limit: usize,
    },
    /// Shapes or sizes of loss inputs that do not agree.
    #[error("{what}: expected {expected}, found {found}")]
    Shape {
        /// The input.
        what: String,
        /// The expected shape.
        expected: String,
        /// The shape found.
        found: String,
    },
    /// A physics term rejected its input.
    #[error("physics loss: {0}")]
    Sim(#[from] weft_sim::SimError),
    /// A body query failed (non-finite prediction, empty body).
    #[error("collision loss: {0}")]
    Query(String),
    /// A network layer rejected its input.
    #[error("network: {0}")]
    Nn(#[from] weft_nn::NnError),
    /// Drawing the curves.
    #[error("training curves: {0}")]
    Render(#[from] weft_render::RenderError),
    /// An error of the model or data crate, passed through with its message.
    #[error("{0}")]
    Model(String),
}

/// Shorthand.
pub type Result<T, E = TrainError> = std::result::Result<T, E>;

impl TrainError {
    /// A [`TrainError::Config`].
    pub fn config(field: &str, value: impl ToString, expected: &str) -> Self {
        TrainError::Config {
            field: field.into(),
            value: value.to_string(),
            expected: expected.into(),
        }
    }

    /// A [`TrainError::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        TrainError::Io {
            path: path.into(),
            source,
        }
    }
}
