//! Typed errors of the models: every input a user controls (a garment, a body, a motion, a
//! config file, a checkpoint) is checked at the API boundary and a mismatch is reported by
//! name, with the expected and the found value.

use std::path::PathBuf;

/// What can go wrong building inputs, running or loading a model.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// An input's size disagrees with the configuration or with another input.
    #[error("{what}: expected {expected}, found {found}")]
    Mismatch {
        /// Which input or quantity.
        what: String,
        /// What the configuration (or the other input) requires.
        expected: String,
        /// What was given.
        found: String,
    },
    /// A NaN or infinite number in an input.
    #[error("{what} holds a non-finite value at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Flat index of the first bad value.
        index: usize,
    },
    /// A configuration value that cannot build the model.
    #[error("invalid model configuration: {0}")]
    Config(String),
    /// A garment that the model cannot run on (too small to pool, no faces, ...).
    #[error("garment: {0}")]
    Garment(String),
    /// Body model, feature or motion computations failed.
    #[error("body: {0}")]
    Body(String),
    /// The body model refused an input (a shape, a pose, a frame).
    #[error("{what}")]
    BodyModel {
        /// What was being computed.
        what: String,
        /// The cause.
        #[source]
        source: Box<weft_body::BodyError>,
    },
    /// A body feature (weight transfer, joint distances) could not be computed.
    #[error("{what}")]
    Feature {
        /// What was being computed.
        what: String,
        /// The cause.
        #[source]
        source: Box<weft_body::features::FeatureError>,
    },
    /// A config table refused by the one configuration path (an unknown key, a value
    /// that does not fit).
    #[error(transparent)]
    ConfigFile(#[from] weft_config::ConfigError),
    /// A layer refused its input.
    #[error(transparent)]
    Nn(#[from] weft_nn::NnError),
    /// A run directory or checkpoint could not be read.
    #[error("{path}: {message}")]
    Run {
        /// The file or directory.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A file of a run directory could not be read.
    #[error("{}: cannot read", path.display())]
    RunRead {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A run's config.toml that is not TOML.
    #[error("{}: not valid TOML: {message}", path.display())]
    RunToml {
        /// The file.
        path: PathBuf,
        /// The cause, with its line and column.
        message: String,
    },
    /// A rollout that left the physically possible (a non-finite position, a vertex
    /// faster than the guard allows).
    #[error("the rollout diverged at frame {frame}: {message}")]
    Diverged {
        /// The first frame that could not be produced.
        frame: usize,
        /// What happened.
        message: String,
    },
    /// A run's config.toml naming a model this build does not know.
    #[error("{}: model_kind", path.display())]
    RunKind {
        /// The file.
        path: PathBuf,
        /// The unknown name and the known ones.
        #[source]
        source: crate::kind::UnknownModelKind,
    },
}

impl ModelError {
    /// The first of `fields` (config name, value) that is 0, as a configuration error
    /// naming it; sizes of layers, blocks and heads must be at least 1.
    pub fn check_positive(fields: &[(&str, usize)]) -> Result<(), ModelError> {
        match fields.iter().find(|(_, v)| *v == 0) {
            Some((field, _)) => Err(ModelError::Config(format!(
                "{field} = 0; expected at least 1"
            ))),
            None => Ok(()),
        }
    }

    /// A [`ModelError::Mismatch`] from displayable values.
    pub fn mismatch(
        what: impl Into<String>,
        expected: impl std::fmt::Display,
        found: impl std::fmt::Display,
    ) -> Self {
        ModelError::Mismatch {
            what: what.into(),
            expected: expected.to_string(),
            found: found.to_string(),
        }
    }
}

/// Fails with [`ModelError::NonFinite`] at the first non-finite value.
pub(crate) fn check_finite(what: &'static str, values: &[f32]) -> Result<(), ModelError> {
    match values.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(ModelError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// A [`ModelError::BodyModel`] naming what was being computed, for `map_err`.
pub(crate) fn body_err(what: &str) -> impl Fn(weft_body::BodyError) -> ModelError + '_ {
    move |source| ModelError::BodyModel {
        what: what.to_string(),
        source: Box::new(source),
    }
}
