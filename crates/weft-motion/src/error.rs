//! Typed errors of motion input, output and generation. Every variant that comes from a
//! file names it and, where there is one, the line (BVH) or array key (npz), and says
//! what was expected, so the CLI prints it as one line.

use std::fmt;
use std::path::PathBuf;

/// What went wrong reading, converting, generating or writing a motion.
#[derive(Debug, thiserror::Error)]
pub enum MotionError {
    /// The file could not be opened, read or written. The operating system's reason is
    /// the error's `source()`, so a cause-chain printer shows it once.
    #[error("{}: cannot access the file", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The extension names no motion format weft reads or writes.
    #[error("{}: unknown motion format (expected a .npz or .bvh file)", .path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// A BVH file does not parse; `line` is 1-based, 0 when no single line is at fault.
    #[error("{}{}: {message}", .path.display(), LineSuffix(*.line))]
    Bvh {
        /// The file.
        path: PathBuf,
        /// 1-based line, 0 when not applicable.
        line: usize,
        /// What was found and what was expected.
        message: String,
    },
    /// An `.npz` archive does not read (not a zip, a damaged member, a missing array, an
    /// array of the wrong type or shape), as reported by the `.npz` reader.
    #[error(transparent)]
    NpzFile(#[from] weft_mesh::io::npz::NpzError),
    /// An AMASS-style `.npz` archive is not a motion: a key is missing, an array has the
    /// wrong shape or type, or holds non-finite numbers. `key` is empty when the archive
    /// as a whole is at fault.
    #[error("{}{}: {message}", .path.display(), KeySuffix(.key))]
    Npz {
        /// The file.
        path: PathBuf,
        /// The array's name in the archive, empty when none applies.
        key: String,
        /// What was found and what was expected.
        message: String,
    },
    /// A BVH skeleton cannot be mapped onto SMPL's joints: a required joint has no
    /// counterpart, or two BVH joints claim the same SMPL joint.
    #[error("{}: {message}", .path.display())]
    Retarget {
        /// The BVH file.
        path: PathBuf,
        /// Which joint is at fault and how to fix it.
        message: String,
    },
    /// A joint-name map file (TOML or JSON) does not parse or names no SMPL joint.
    #[error("{}: {message}", .path.display())]
    NameMap {
        /// The map file.
        path: PathBuf,
        /// What was found and what was expected.
        message: String,
    },
    /// A motion's arrays break an invariant of [`Motion`](super::Motion).
    #[error("invalid motion: {0}")]
    Invalid(String),
    /// A parameter of an operation (frame rate, window, frame count …) is out of range.
    #[error("{0}")]
    Parameter(String),
}

impl MotionError {
    pub(crate) fn bvh(path: &std::path::Path, line: usize, message: impl Into<String>) -> Self {
        MotionError::Bvh {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    pub(crate) fn npz(path: &std::path::Path, key: &str, message: impl Into<String>) -> Self {
        MotionError::Npz {
            path: path.to_path_buf(),
            key: key.to_owned(),
            message: message.into(),
        }
    }

    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        MotionError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Formats `:LINE` after the path, or nothing for line 0.
struct LineSuffix(usize);

impl fmt::Display for LineSuffix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 > 0 {
            write!(f, ":{}", self.0)
        } else {
            Ok(())
        }
    }
}

/// Formats ``: `NAME` `` after the path, or nothing for an empty key.
struct KeySuffix<'a>(&'a str);

impl fmt::Display for KeySuffix<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            Ok(())
        } else {
            write!(f, ": `{}`", self.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn messages_name_file_line_and_key() {
        let e = MotionError::bvh(Path::new("a.bvh"), 12, "expected OFFSET");
        assert_eq!(e.to_string(), "a.bvh:12: expected OFFSET");
        let e = MotionError::bvh(Path::new("a.bvh"), 0, "no frames");
        assert_eq!(e.to_string(), "a.bvh: no frames");
        let e = MotionError::npz(Path::new("m.npz"), "poses", "wrong shape");
        assert_eq!(e.to_string(), "m.npz: `poses`: wrong shape");
        let e = MotionError::npz(Path::new("m.npz"), "", "not a zip archive");
        assert_eq!(e.to_string(), "m.npz: not a zip archive");
    }
}
