//! Every mesh file (.obj, .ply) at the top of `tests/malformed/` (at the repository
//! root) must fail to read with a message that names the file — except
//! `non_manifold.obj`, which reads and must be flagged by validation. See
//! `tests/malformed/README.md` for what each file is; its subdirectories hold the inputs
//! of the other readers, run through the CLI by `crates/weft-cli/tests/malformed_cli.rs`.

use std::path::{Path, PathBuf};

use weft_mesh::validate::{validate, Finding};
use weft_mesh::{read_mesh, MeshError};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/malformed")
}

/// What reading each listed file must say after `NAME` (a colon follows the file name,
/// then the line for text formats). Files not listed must still fail naming the file.
const EXPECTED: &[(&str, &str)] = &[
    ("truncated.obj", ":3: vertex with 2 coordinates; expected `v x y z`"),
    ("nan_coordinate.obj", ":2: coordinate `nan` is not finite"),
    ("index_out_of_range.obj", ":4: vertex index 4 is out of range; the file defines 3 vertices"),
    ("index_zero.obj", ":4: vertex index 0; OBJ indices start at 1"),
    ("index_negative_overflow.obj", ":4: relative vertex index -4 reaches before the first vertex"),
    ("binary_garbage.obj", ":1: binary data (a NUL byte); expected a text OBJ file"),
    ("binary_garbage.ply", ":1: not a PLY file; expected `ply` on the first line"),
    ("empty.obj", ": the mesh is empty (0 vertices, 0 faces)"),
    ("truncated_binary.ply", ": byte 169: element vertex: the header declares 3 of them, at least 12 bytes each, but only 30 bytes follow"),
    ("huge_vertex_count.ply", ": byte 124: element vertex: the header declares 4000000000 of them, at least 12 bytes each, but only 24 bytes follow"),
    ("bad_header.ply", ":4: unknown type `flaot`"),
];

#[test]
fn every_malformed_file_fails_naming_the_file() {
    let mut names: Vec<String> = std::fs::read_dir(dir())
        .expect("tests/malformed exists")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        // The mesh files are at the top; subdirectories hold the other readers' inputs.
        .filter(|n| (n.ends_with(".obj") || n.ends_with(".ply")) && n != "non_manifold.obj")
        .collect();
    names.sort();
    for (name, _) in EXPECTED {
        assert!(names.iter().any(|n| n == name), "{name} is missing");
    }
    for name in &names {
        let path = dir().join(name);
        let err = match read_mesh(&path) {
            Ok(m) => panic!("{name} read as a mesh of {} vertices", m.vertex_count()),
            Err(e) => e,
        };
        assert!(
            !matches!(err, MeshError::Io { .. }),
            "{name}: an I/O error, not a format error: {err}"
        );
        let message = err.to_string();
        let shown = path.display().to_string();
        assert!(message.starts_with(&shown), "{name}: {message}");
        if let Some((_, rest)) = EXPECTED.iter().find(|(n, _)| n == name) {
            assert!(
                message[shown.len()..].starts_with(rest),
                "{name}: got `{message}`, expected it to continue with `{rest}`"
            );
        }
    }
}

#[test]
fn non_manifold_file_reads_and_is_flagged() {
    let path = dir().join("non_manifold.obj");
    let mesh = read_mesh(&path).expect("a non-manifold mesh is still a mesh");
    let findings = validate(&mesh);
    assert_eq!(
        findings,
        vec![Finding::NonManifoldEdge {
            edge: [0, 1],
            faces: 3
        }]
    );
}
