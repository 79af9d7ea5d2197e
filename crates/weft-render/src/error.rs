//! Typed errors of rendering, plotting and report writing. Each says what was given and
//! what was expected, so the CLI can print it as one line.

use std::path::PathBuf;

/// What went wrong drawing a picture or writing it out.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The output file could not be written (nothing partial is left behind).
    #[error("{}: cannot write the file", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The PNG encoder refused the data (cannot happen for images this crate made, but the
    /// encoder's error type allows it).
    #[error("PNG encoding failed: {0}")]
    Encode(String),
    /// An image side is zero or larger than [`MAX_SIDE`](crate::MAX_SIDE).
    #[error("image size {width}×{height} is out of range; expected 1 to {max} pixels per side")]
    Size {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Largest side allowed.
        max: u32,
    },
    /// A scalar colour map was given with a different number of values than vertices.
    #[error(
        "{mesh}: {values} scalar values for {vertices} vertices; expected one value per vertex"
    )]
    ScalarCount {
        /// The mesh's name in the scene.
        mesh: String,
        /// Number of values given.
        values: usize,
        /// Number of vertices of the mesh.
        vertices: usize,
    },
    /// A face refers to a vertex the mesh does not have.
    #[error("{mesh}: face {face} refers to vertex {index}, but the mesh has {vertices} vertices")]
    FaceIndex {
        /// The mesh's name in the scene.
        mesh: String,
        /// 0-based face index.
        face: usize,
        /// The out-of-range vertex index.
        index: u32,
        /// Number of vertices of the mesh.
        vertices: usize,
    },
    /// There is nothing with a finite position to draw or frame.
    #[error("nothing to draw: {0}")]
    Empty(String),
    /// A fixed colour-map or axis range is not finite or not increasing.
    #[error("range {min}..{max} is invalid; expected finite numbers with min < max")]
    Range {
        /// Lower end given.
        min: f64,
        /// Upper end given.
        max: f64,
    },
    /// An option is out of its documented range.
    #[error("{0}")]
    Invalid(String),
}
