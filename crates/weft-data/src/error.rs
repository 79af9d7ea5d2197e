//! The one error type of weft-data. Every variant names the file, field or tensor at
//! fault and what was expected, so a user can fix a config or find a damaged shard from
//! the message alone.

use std::path::PathBuf;

use thiserror::Error;

/// What went wrong while configuring, generating or loading a dataset.
#[derive(Debug, Error)]
pub enum DataError {
    /// A file or directory could not be read, written or created.
    #[error("{}: {action}", .path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What was being done ("cannot read the manifest", …).
        action: String,
        /// The operating system's reason.
        #[source]
        source: std::io::Error,
    },
    /// The dataset directory is held by another process.
    #[error(transparent)]
    Lock(#[from] weft_mesh::io::lock::LockError),
    /// A config file does not parse as TOML of the expected layout.
    #[error("{}: {message}", .path.display())]
    ConfigSyntax {
        /// The config file.
        path: PathBuf,
        /// The TOML reader's message (line, column, field).
        message: String,
    },
    /// A config value is out of range or inconsistent (`field` is its TOML path).
    #[error("config field {field}: {message}")]
    Config {
        /// Dotted TOML path of the field (`train.garments[2].vertices`).
        field: String,
        /// The value found and what was expected.
        message: String,
    },
    /// Two splits share a garment, a body shape or a motion (seed 000 §4 forbids it).
    #[error("splits overlap: {what} appears in both {first} and {second}")]
    SplitOverlap {
        /// The shared item (its description).
        what: String,
        /// The first split holding it.
        first: &'static str,
        /// The second split holding it.
        second: &'static str,
    },
    /// A manifest does not parse or breaks one of its invariants.
    #[error("{}: {message}", .path.display())]
    Manifest {
        /// The manifest file.
        path: PathBuf,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A shard is not a readable safetensors file.
    #[error("{}: not a valid safetensors shard: {message}", .path.display())]
    Shard {
        /// The shard file.
        path: PathBuf,
        /// The reader's message.
        message: String,
    },
    /// A shard lacks a tensor, or a tensor has the wrong type or shape.
    #[error("{}: tensor {tensor:?}: expected {expected}, found {found}", .path.display())]
    Tensor {
        /// The shard file.
        path: PathBuf,
        /// The tensor's name.
        tensor: String,
        /// Expected dtype and shape (`f32 [40, 712, 3]`).
        expected: String,
        /// What the file holds (`missing`, `u32 [40, 712, 3]`, …).
        found: String,
    },
    /// A shard's bytes are not the ones written: their SHA-256 differs from the one the
    /// manifest recorded (a value edited, a file replaced, a bit flipped on disk).
    #[error("{}: changed since it was written: its SHA-256 is {found}, the manifest records {expected}", .path.display())]
    Digest {
        /// The shard file.
        path: PathBuf,
        /// The SHA-256 the manifest records (lowercase hex).
        expected: String,
        /// The file's SHA-256 now.
        found: String,
    },
    /// A garment, body, motion or sequence id the dataset does not list.
    #[error("{kind} {id:?} is not in the dataset {}", .dir.display())]
    UnknownId {
        /// "garment", "sequence", …
        kind: &'static str,
        /// The id asked for.
        id: String,
        /// The dataset directory.
        dir: PathBuf,
    },
    /// A record cannot be loaded because its shard was never (fully) written.
    #[error("sequence {id}: status {status}, no shard to load")]
    NotGenerated {
        /// The sequence id.
        id: String,
        /// Its status in the manifest.
        status: String,
    },
    /// Building a garment failed.
    #[error("garment {id}")]
    Garment {
        /// The garment id.
        id: String,
        /// weft-garment's reason.
        #[source]
        source: Box<weft_garment::GarmentError>,
    },
    /// Loading or shaping the body failed.
    #[error("body {what}")]
    Body {
        /// Which body or shape.
        what: String,
        /// weft-body's reason.
        #[source]
        source: Box<weft_body::BodyError>,
    },
    /// An import's input is wrong: the file named, what was found and what was expected.
    #[error("{}: {message}", .path.display())]
    Import {
        /// The import file, cache, rest mesh or motion.
        path: PathBuf,
        /// What is wrong and what was expected.
        message: String,
    },
    /// Generating or reading a motion failed.
    #[error("motion {id}")]
    Motion {
        /// The motion id.
        id: String,
        /// weft-body's reason.
        #[source]
        source: Box<weft_motion::MotionError>,
    },
    /// Reading or writing a mesh failed.
    #[error("mesh")]
    Mesh(#[source] Box<weft_mesh::MeshError>),
    /// The simulator refused a sequence's input or failed (other than diverging, which
    /// is recorded in the manifest instead).
    #[error("sequence {id}: simulation failed: {message}")]
    Simulation {
        /// The sequence id.
        id: String,
        /// The simulator's message.
        message: String,
    },
    /// The output directory holds a dataset made from another config or seed, or an
    /// unmerged set of partial manifests.
    #[error("{}: {message}", .path.display())]
    Conflict {
        /// The directory or manifest.
        path: PathBuf,
        /// What differs and what to do.
        message: String,
    },
}

impl DataError {
    /// An [`DataError::Io`] for `path`.
    pub(crate) fn io(path: impl Into<PathBuf>, action: &str, source: std::io::Error) -> Self {
        DataError::Io {
            path: path.into(),
            action: action.to_string(),
            source,
        }
    }

    /// A [`DataError::Config`] for `field`.
    pub(crate) fn config(field: impl Into<String>, message: impl Into<String>) -> Self {
        DataError::Config {
            field: field.into(),
            message: message.into(),
        }
    }
}
