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
    #[error("{}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file of the run that is not what it should be (a metrics log line, a
    /// `latest` pointer).
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A config file that is not valid TOML.
    #[error("{}: not valid TOML: {message}", path.display())]
    Toml {
        /// The file.
        path: PathBuf,
        /// The cause, with its line and column.
        message: String,
    },
    /// A trainer state or metrics record that is not valid JSON.
    #[error("{}: not a valid training record", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: serde_json::Error,
    },
    /// A configuration or record that cannot be written out.
    #[error("{what} cannot be written")]
    Write {
        /// What was being written.
        what: String,
        /// The cause.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
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
    #[error("{}: cannot read or apply the record", path.display())]
    Record {
        /// The file.
        path: PathBuf,
        /// burn's error.
        #[source]
        source: burn::store::RecordError,
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
    #[error("physics loss")]
    Sim(#[from] weft_sim::SimError),
    /// The posed body for the collision loss could not be built.
    #[error("collision loss: the posed body")]
    Body(#[from] weft_body::BodyError),
    /// A network layer rejected its input.
    #[error("network")]
    Nn(#[from] weft_nn::NnError),
    /// Drawing the curves.
    #[error("training curves")]
    Render(#[from] weft_render::RenderError),
    /// The run directory (weft-models owns its layout) or the model refused something.
    #[error(transparent)]
    Model(#[from] weft_models::ModelError),
    /// A config file refused by the one configuration path (an unknown key, a value
    /// that does not fit).
    #[error(transparent)]
    ConfigFile(#[from] weft_config::ConfigError),
    /// The model refused the inputs of one training sequence.
    #[error("sequence {id}")]
    Sequence {
        /// The sequence.
        id: String,
        /// The cause.
        #[source]
        source: weft_models::ModelError,
    },
    /// The dataset could not be read.
    #[error(transparent)]
    Data(#[from] weft_data::DataError),
    /// The run directory is held by another process.
    #[error(transparent)]
    Lock(#[from] weft_mesh::io::lock::LockError),
    /// A tensor could not be read back to the host.
    #[error("reading {what} back from the device")]
    Tensor {
        /// Which tensor.
        what: &'static str,
        /// burn's error.
        #[source]
        source: burn::tensor::DataError,
    },
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
