//! Typed errors of mesh input and output. Every variant names the file and, where there
//! is one, the line or element, and says what was expected.

use std::path::PathBuf;

/// What went wrong reading, validating or writing a mesh.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The extension names no format weft reads or writes.
    #[error("{path}: unknown mesh format (expected a .obj or .ply file)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The file does not parse; `line` is 1-based, 0 when the position is not a line
    /// (a binary PLY body).
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line, 0 when not applicable.
        line: usize,
        /// What was found and what was expected.
        message: String,
    },
    /// The file parsed but breaks a mesh invariant weft relies on.
    #[error("{path}: {element} {index}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// `vertex`, `face` or `edge`.
        element: &'static str,
        /// 0-based index of the element.
        index: usize,
        /// What is wrong and what was expected.
        message: String,
    },
}
