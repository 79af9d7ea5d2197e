//! Typed errors of mesh input and output. Every variant names the file and, where there
//! is one, the line or element, and says what was expected.

use std::path::PathBuf;

/// What went wrong reading, validating or writing a mesh.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened, read or written. The operating system's reason is
    /// the error's `source()`, so a cause-chain printer shows it once.
    #[error("{path}: cannot access the file")]
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
    /// (a binary PLY body, whose message names the element and byte offset instead).
    #[error("{}{}: {message}", .path.display(), LineSuffix(*.line))]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line, 0 when not applicable.
        line: usize,
        /// What was found and what was expected.
        message: String,
    },
    /// The file parsed but holds no triangle mesh: no vertices or no faces.
    #[error("{path}: the mesh is empty ({vertices} vertices, {faces} faces); expected at least one triangle")]
    Empty {
        /// The file.
        path: PathBuf,
        /// Number of vertices read.
        vertices: usize,
        /// Number of faces read.
        faces: usize,
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

/// Formats `:LINE` after the path, or nothing for line 0 (no line applies).
struct LineSuffix(usize);

impl std::fmt::Display for LineSuffix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0 > 0 {
            write!(f, ":{}", self.0)
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_errors_show_the_line_only_when_there_is_one() {
        let e = |line| MeshError::Parse {
            path: "a.ply".into(),
            line,
            message: "bad".into(),
        };
        assert_eq!(e(3).to_string(), "a.ply:3: bad");
        assert_eq!(e(0).to_string(), "a.ply: bad");
    }
}
