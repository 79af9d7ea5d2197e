//! Typed errors of animation export and of reading frame sequences back. Every variant
//! says which file, frame or vertex is wrong and what was expected, so the CLI can print
//! it as one line.

use std::io;
use std::path::PathBuf;

use super::npy::NpyError;
use crate::error::MeshError;

/// What went wrong loading frames or writing (or reading back) an animation file.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A file or directory could not be opened or read.
    #[error("cannot read {}: {error}", .path.display())]
    Read {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's error. Part of the message, not a `source()`, so a
        /// report that prints the cause chain does not repeat it.
        error: io::Error,
    },
    /// An output could not be written. Nothing is left behind: outputs are written to a
    /// temporary name and renamed into place only when complete.
    #[error("cannot write {}: {error}", .path.display())]
    Write {
        /// The output file or directory.
        path: PathBuf,
        /// The operating system's error. Part of the message, not a `source()`, so a
        /// report that prints the cause chain does not repeat it.
        error: io::Error,
    },
    /// A mesh (a template or an OBJ frame) did not read.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A `.npy` array did not read.
    #[error(transparent)]
    Npy(#[from] NpyError),
    /// A file parsed but is not what the reader expects (wrong magic, shape, size …).
    #[error("{}: {message}", .path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What was found and what was expected.
        message: String,
    },
    /// The export format name is not one weft writes.
    #[error("unknown export format `{name}`; expected one of obj, pc2, mdd, glb, usd")]
    UnknownFormat {
        /// The name given.
        name: String,
    },
    /// Frames of a mesh without vertices.
    #[error("the frames have no vertices; expected at least one vertex per frame")]
    NoVertices,
    /// An animation without frames.
    #[error("the animation has no frames; expected at least one")]
    NoFrames,
    /// The frames do not have one position per template vertex.
    #[error("the frames have {frames} vertices but the template has {template}; expected one position per template vertex, in the template's order")]
    VertexCount {
        /// Vertices per frame.
        frames: usize,
        /// Vertices of the template.
        template: usize,
    },
    /// A frame given to [`Frames::push_frame`](super::Frames::push_frame) or built from
    /// a buffer has the wrong number of positions.
    #[error("frame {frame} has {found} positions; expected {expected} like the frames before it")]
    FrameLength {
        /// 0-based frame.
        frame: usize,
        /// Positions given.
        found: usize,
        /// Vertices per frame.
        expected: usize,
    },
    /// A frame file of a directory sequence has a different vertex count than the first.
    #[error("{}: {found} vertices, but {} has {expected}; every frame must have the same vertices in the same order", .path.display(), .first.display())]
    FrameFileVertexCount {
        /// The offending frame file.
        path: PathBuf,
        /// Its vertex count.
        found: usize,
        /// The first frame file.
        first: PathBuf,
        /// Its vertex count.
        expected: usize,
    },
    /// A NaN or infinite coordinate: no format can carry it meaningfully, so nothing is
    /// written.
    #[error("frame {frame}, vertex {vertex}: the {axis} coordinate is {value}; expected finite positions (the frames are not exported)")]
    NonFinite {
        /// 0-based frame.
        frame: usize,
        /// 0-based vertex.
        vertex: usize,
        /// `x`, `y` or `z`.
        axis: char,
        /// The value (NaN or ±inf).
        value: f32,
    },
    /// A face of the template names a vertex the frames do not have.
    #[error("face {face} names vertex {vertex}, but the frames have {vertices} vertices")]
    FaceIndex {
        /// 0-based face.
        face: usize,
        /// The vertex index it names.
        vertex: u32,
        /// Vertices per frame.
        vertices: usize,
    },
    /// The frame rate is not a positive finite number.
    #[error("frame rate {fps} is not a positive, finite number of frames per second")]
    Fps {
        /// The frame rate given.
        fps: f32,
    },
    /// PC2 timing fields that are not finite, or a sampling that is not positive.
    #[error("PC2 start frame {start_frame} and sampling {sampling}; expected finite numbers and a positive sampling")]
    Pc2Timing {
        /// The start frame given.
        start_frame: f32,
        /// The sampling given.
        sampling: f32,
    },
    /// A count or size exceeds what the format can store.
    #[error("{what} is {value}, more than {format} can store (at most {max})")]
    TooLarge {
        /// The format, e.g. `PC2`.
        format: &'static str,
        /// What is counted, e.g. `the vertex count`.
        what: &'static str,
        /// The count.
        value: u64,
        /// The format's limit.
        max: u64,
    },
    /// Meshes of one glTF scene are animated with different frame counts.
    #[error("mesh `{mesh}` has {found} frames but `{first}` has {expected}; animated meshes of one scene need the same frame count (a mesh with one frame is static)")]
    FrameCountMismatch {
        /// The mesh with a different count.
        mesh: String,
        /// Its frame count.
        found: usize,
        /// The first animated mesh.
        first: String,
        /// Its frame count.
        expected: usize,
    },
    /// A scene mesh's name cannot name a USD prim.
    #[error("mesh name `{name}` is not a USD identifier; expected a letter or `_`, then letters, digits or `_`")]
    MeshName {
        /// The name given.
        name: String,
    },
    /// The template's corner UVs do not match its faces.
    #[error(
        "the template has {uvs} UV triangles but {faces} faces; expected one UV per face corner"
    )]
    UvCount {
        /// UV triples given.
        uvs: usize,
        /// Faces of the template.
        faces: usize,
    },
    /// A texture coordinate is NaN or infinite.
    #[error("face {face}, corner {corner}: the texture coordinate is not finite")]
    NonFiniteUv {
        /// Face index.
        face: usize,
        /// Corner 0, 1 or 2.
        corner: usize,
    },
    /// An output directory that holds something other than a previous frame sequence.
    #[error("{}: {message}", .path.display())]
    OutputDirectory {
        /// The directory.
        path: PathBuf,
        /// What is in the way and what to do.
        message: String,
    },
}

impl ExportError {
    /// A read error naming `path`.
    pub(crate) fn read(path: impl Into<PathBuf>, error: io::Error) -> Self {
        ExportError::Read {
            path: path.into(),
            error,
        }
    }

    /// A write error naming `path`.
    pub(crate) fn write(path: impl Into<PathBuf>, error: io::Error) -> Self {
        ExportError::Write {
            path: path.into(),
            error,
        }
    }

    /// A format error naming `path`.
    pub(crate) fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        ExportError::Format {
            path: path.into(),
            message: message.into(),
        }
    }
}
