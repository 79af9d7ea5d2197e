//! Mesh files: Wavefront OBJ and Stanford PLY in, OBJ and PLY out.
//!
//! Readers take the whole file into memory (garment meshes are megabytes), parse it
//! without panicking on any input, triangulate polygons as fans and run the strict
//! [`check`](crate::validate::check), so a mesh that comes out of [`read_mesh`] has
//! finite coordinates, in-range indices and at least one face. Every error names the
//! file and the line (text) or element (binary) and says what was expected.
//!
//! Writers go through [`write_atomic`]: a crash or an error never leaves a partial file.

mod atomic;
mod input;
pub mod lock;
pub mod npy;
pub mod npz;
mod obj;
mod ply;

use std::fmt;
use std::io;
use std::path::Path;

pub use atomic::write_atomic;
pub use input::{read_input, read_input_to_string, MAX_STREAM_BYTES};
pub use obj::{load_obj_bytes, write_obj_to};
pub use ply::{load_ply_bytes, write_ply_graph_to, write_ply_to, PlyEncoding};

use crate::error::MeshError;
use crate::mesh::TriMesh;

/// A mesh file format and, for PLY, its encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (text).
    Obj,
    /// Stanford PLY in the given encoding.
    Ply(PlyEncoding),
}

impl MeshFormat {
    /// The format a path's extension names (`.obj` or `.ply`, any case). PLY is reported
    /// as binary little-endian, the encoding weft writes.
    pub fn from_path(path: &Path) -> Result<Self, MeshError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply(PlyEncoding::BinaryLittleEndian)),
            _ => Err(MeshError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

impl fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MeshFormat::Obj => f.write_str("OBJ"),
            MeshFormat::Ply(e) => write!(f, "PLY ({e})"),
        }
    }
}

/// A mesh as read, with what the reader did to it on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadReport {
    /// The triangle mesh; passed [`check`](crate::validate::check).
    pub mesh: TriMesh,
    /// The file's format (for PLY, the encoding the header declared).
    pub format: MeshFormat,
    /// Faces with more than three corners, split into triangle fans from their first
    /// corner. Fans are right for convex polygons only; callers should report a nonzero
    /// count so a user can check concave ones.
    pub triangulated_polygons: usize,
    /// Texture coordinates of each triangle's three corners, when the file gives every
    /// face corner one (OBJ `f v/vt`); `None` otherwise and for PLY. A garment's UVs are
    /// its pattern, so exports carry them.
    pub corner_uvs: Option<Vec<[[f32; 2]; 3]>>,
}

/// Reads an OBJ or PLY mesh (by extension, any case) and says what loading did.
pub fn load_mesh(path: &Path) -> Result<LoadReport, MeshError> {
    match MeshFormat::from_path(path)? {
        MeshFormat::Obj => load_obj(path),
        MeshFormat::Ply(_) => load_ply(path),
    }
}

/// Reads an OBJ or PLY mesh (by extension, any case).
pub fn read_mesh(path: &Path) -> Result<TriMesh, MeshError> {
    load_mesh(path).map(|r| r.mesh)
}

/// Reads a Wavefront OBJ file; see [`load_obj_bytes`] for what is read.
pub fn load_obj(path: &Path) -> Result<LoadReport, MeshError> {
    load_obj_bytes(&read_bytes(path)?, path)
}

/// Reads a Wavefront OBJ file.
pub fn read_obj(path: &Path) -> Result<TriMesh, MeshError> {
    load_obj(path).map(|r| r.mesh)
}

/// Reads a PLY file (ascii, binary little- or big-endian); see [`load_ply_bytes`].
pub fn load_ply(path: &Path) -> Result<LoadReport, MeshError> {
    load_ply_bytes(&read_bytes(path)?, path)
}

/// Reads a PLY file (ascii, binary little- or big-endian).
pub fn read_ply(path: &Path) -> Result<TriMesh, MeshError> {
    load_ply(path).map(|r| r.mesh)
}

/// Writes `mesh` in the format of the path's extension: OBJ, or binary little-endian PLY.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), MeshError> {
    match MeshFormat::from_path(path)? {
        MeshFormat::Obj => write_obj(path, mesh),
        MeshFormat::Ply(encoding) => write_ply_with(path, mesh, encoding),
    }
}

/// Writes an ascii OBJ: `v x y z` with round-trip precision, `f a b c` 1-based.
pub fn write_obj(path: &Path, mesh: &TriMesh) -> Result<(), MeshError> {
    atomically(path, |w| write_obj_to(w, mesh))
}

/// Writes a binary little-endian PLY with `double` coordinates.
pub fn write_ply(path: &Path, mesh: &TriMesh) -> Result<(), MeshError> {
    write_ply_with(path, mesh, PlyEncoding::BinaryLittleEndian)
}

/// Writes a PLY in the given encoding.
pub fn write_ply_with(path: &Path, mesh: &TriMesh, encoding: PlyEncoding) -> Result<(), MeshError> {
    atomically(path, |w| write_ply_to(w, mesh, encoding, None))
}

/// Writes a binary little-endian PLY with one RGB colour per vertex (`red`, `green`,
/// `blue` as `uchar`), e.g. to show which vertices a hierarchy level keeps.
///
/// Fails without touching `path` unless there is exactly one colour per vertex.
pub fn write_ply_colored(path: &Path, mesh: &TriMesh, colors: &[[u8; 3]]) -> Result<(), MeshError> {
    check_colors(path, mesh.positions.len(), colors)?;
    atomically(path, |w| {
        write_ply_to(w, mesh, PlyEncoding::BinaryLittleEndian, Some(colors))
    })
}

/// Writes a binary little-endian PLY of a graph: vertices (optionally coloured) and an
/// `edge` element with `vertex1`, `vertex2`, no faces. Coarse hierarchy levels are
/// graphs, not triangle meshes; viewers such as MeshLab draw the edges.
///
/// Fails without touching `path` when `colors` is given but not one per vertex.
pub fn write_ply_graph(
    path: &Path,
    positions: &[[f64; 3]],
    edges: &[[u32; 2]],
    colors: Option<&[[u8; 3]]>,
) -> Result<(), MeshError> {
    if let Some(colors) = colors {
        check_colors(path, positions.len(), colors)?;
    }
    atomically(path, |w| {
        write_ply_graph_to(w, positions, edges, colors, PlyEncoding::BinaryLittleEndian)
    })
}

/// The whole file, or an I/O error naming it.
fn read_bytes(path: &Path) -> Result<Vec<u8>, MeshError> {
    read_input(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// [`write_atomic`] with errors naming `path`.
fn atomically<F>(path: &Path, write: F) -> Result<(), MeshError>
where
    F: FnOnce(&mut dyn io::Write) -> io::Result<()>,
{
    write_atomic(path, write).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn check_colors(path: &Path, vertices: usize, colors: &[[u8; 3]]) -> Result<(), MeshError> {
    if colors.len() == vertices {
        return Ok(());
    }
    Err(MeshError::Invalid {
        path: path.to_path_buf(),
        element: "vertex",
        index: colors.len().min(vertices),
        message: format!(
            "{} colours given for {vertices} vertices; expected one colour per vertex",
            colors.len()
        ),
    })
}

/// Formats a coordinate so that parsing it gives back the same `f64`: Rust's shortest
/// round-trip digits, in exponent form only for very small or large magnitudes (plain
/// form would spell out hundreds of zeros).
pub(crate) fn fmt_f64(out: &mut String, x: f64) {
    use std::fmt::Write as _;
    let a = x.abs();
    // Writing into a String cannot fail.
    let _ = if a != 0.0 && !(1e-5..1e16).contains(&a) {
        write!(out, "{x:e}")
    } else {
        write!(out, "{x}")
    };
}

/// 1-based line of byte `offset` in `bytes`.
pub(crate) fn line_of(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

#[cfg(test)]
pub(crate) mod test_dir {
    use std::fs;
    use std::path::PathBuf;
    use std::sync::atomic::{AtomicU64, Ordering};

    static N: AtomicU64 = AtomicU64::new(0);

    /// A fresh, empty directory under the system temp dir, removed on drop.
    pub(crate) struct TestDir(pub PathBuf);

    impl TestDir {
        pub(crate) fn new(tag: &str) -> Self {
            let n = N.fetch_add(1, Ordering::Relaxed);
            let dir =
                std::env::temp_dir().join(format!("weft-mesh-{tag}-{}-{n}", std::process::id()));
            let _ = fs::remove_dir_all(&dir);
            fs::create_dir_all(&dir).expect("create test dir");
            TestDir(dir)
        }

        /// File names in the directory, sorted.
        pub(crate) fn entries(&self) -> Vec<String> {
            let mut v: Vec<String> = fs::read_dir(&self.0)
                .expect("read dir")
                .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        }
    }

    impl Drop for TestDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::test_dir::TestDir;
    use super::*;
    use crate::primitives::grid;

    #[test]
    fn format_follows_the_extension_in_any_case() {
        assert_eq!(
            MeshFormat::from_path(Path::new("a/B.OBJ")).unwrap(),
            MeshFormat::Obj
        );
        assert!(matches!(
            MeshFormat::from_path(Path::new("x.Ply")),
            Ok(MeshFormat::Ply(_))
        ));
        let e = MeshFormat::from_path(Path::new("x.stl")).unwrap_err();
        assert!(e.to_string().contains("x.stl"), "{e}");
        assert!(MeshFormat::from_path(Path::new("noext")).is_err());
    }

    #[test]
    fn coordinates_round_trip_through_text() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.1,
            -1.0 / 3.0,
            1e-300,
            f64::MIN_POSITIVE,
            5e-324,
            1e300,
            f64::MAX,
            123456.789e10,
            1e-5,
            9.99999e-6,
        ] {
            let mut s = String::new();
            fmt_f64(&mut s, x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
            assert!(s.len() < 30, "{s}");
        }
    }

    #[test]
    fn mesh_files_round_trip_by_extension() {
        let dir = TestDir::new("io");
        let mut m = grid(3, 4, 0.1);
        m.positions[5][1] = -1.0 / 3.0;
        for name in ["a.obj", "b.ply", "C.PLY", "d.OBJ"] {
            let path = dir.0.join(name);
            write_mesh(&path, &m).unwrap();
            assert_eq!(read_mesh(&path).unwrap(), m, "{name}");
        }
        for enc in [PlyEncoding::Ascii, PlyEncoding::BinaryBigEndian] {
            let path = dir.0.join("e.ply");
            write_ply_with(&path, &m, enc).unwrap();
            let r = load_mesh(&path).unwrap();
            assert_eq!((r.mesh, r.format), (m.clone(), MeshFormat::Ply(enc)));
        }
        assert_eq!(
            dir.entries(),
            vec!["C.PLY", "a.obj", "b.ply", "d.OBJ", "e.ply"]
        );
    }

    #[test]
    fn reading_a_missing_file_names_it() {
        let e = read_mesh(Path::new("/no/such/dir/m.obj")).unwrap_err();
        assert!(matches!(e, MeshError::Io { .. }));
        assert!(e.to_string().starts_with("/no/such/dir/m.obj: "), "{e}");
    }

    #[test]
    fn colored_and_graph_plys_check_colour_counts() {
        let dir = TestDir::new("io-color");
        let m = grid(2, 2, 1.0);
        let path = dir.0.join("c.ply");
        let e = write_ply_colored(&path, &m, &[[1, 2, 3]]).unwrap_err();
        assert!(
            e.to_string().contains("1 colours given for 4 vertices"),
            "{e}"
        );
        assert!(dir.entries().is_empty());
        write_ply_colored(&path, &m, &[[255, 0, 0]; 4]).unwrap();
        // Colours are extra vertex properties: the mesh reads back unchanged.
        assert_eq!(read_ply(&path).unwrap(), m);

        let g = dir.0.join("g.ply");
        write_ply_graph(&g, &m.positions, &m.edges(), Some(&[[0, 0, 9]; 4])).unwrap();
        assert!(write_ply_graph(&g, &m.positions, &m.edges(), Some(&[[0, 0, 9]; 3])).is_err());
        // A graph has no faces, so it is no triangle mesh.
        let e = read_ply(&g).unwrap_err();
        assert!(
            matches!(
                e,
                MeshError::Empty {
                    faces: 0,
                    vertices: 4,
                    ..
                }
            ),
            "{e}"
        );
    }
}
