//! Errors of the MPFB2 import: each names the file and, for text, the line.

use std::path::PathBuf;

use crate::error::BodyError;

/// What went wrong importing MPFB2 data.
#[derive(Debug, thiserror::Error)]
pub enum MpfbError {
    /// A file could not be read.
    #[error("{}: cannot access the file", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A file does not parse; `line` is 1-based, 0 when no line applies.
    #[error("{}{}: {message}", .path.display(), if *.line > 0 { format!(":{}", .line) } else { String::new() })]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line, 0 when not applicable.
        line: usize,
        /// What was found and what was expected.
        message: String,
    },
    /// The data set lacks something the import needs, or holds something it cannot use.
    #[error("{}: {message}", .path.display())]
    Data {
        /// The file or directory.
        path: PathBuf,
        /// What is missing or wrong, and what was expected.
        message: String,
    },
    /// The converted model failed its own checks (a bug in the import, or odd data).
    #[error(transparent)]
    Model(#[from] BodyError),
}

impl MpfbError {
    pub(crate) fn parse(path: &std::path::Path, line: usize, message: impl Into<String>) -> Self {
        MpfbError::Parse {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    pub(crate) fn data(path: &std::path::Path, message: impl Into<String>) -> Self {
        MpfbError::Data {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        MpfbError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
