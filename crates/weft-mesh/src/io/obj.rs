//! Wavefront OBJ: the polygon subset weft needs (`v`, `vt` and `f`), read with
//! line-accurate errors and written with round-trip precision.
//!
//! Why not `tobj`: it renumbers vertices in order of first use per object, drops unused
//! vertices, and duplicates a vertex for every object (`o`/`g`/`usemtl` split) and, with
//! `single_index`, for every distinct texture/normal index that uses it. For cloth that
//! tears a garment apart along its UV seams and between its panels, and loses the vertex
//! order that per-vertex data (skinning weights, correspondences) relies on. It also
//! panics on some relative texture indices (an overflow in `vt * 2 + 1`) and reports
//! errors without a line. Reading `v`/`f` ourselves keeps the file's global vertex list —
//! all objects merged with their indices as written — and every error names its line.
//! The tests compare the triangles with tobj's on generated files.

use std::io::{self, Write};
use std::path::Path;

use super::{fmt_f64, line_of, LoadReport, MeshFormat};
use crate::error::MeshError;
use crate::mesh::TriMesh;
use crate::validate::check;

/// Parses an OBJ file held in memory; `path` only names the file in errors.
///
/// Reads `v x y z` (further numbers — a `w` weight or `r g b` colour — are checked and
/// ignored), `vt u [v [w]]` and `f` with corners `v`, `v/vt`, `v/vt/vn` or `v//vn`,
/// indices 1-based or negative (relative to the elements defined so far). Positive
/// indices may point forward. Texture and normal indices are range-checked; the texture
/// coordinates become [`LoadReport::corner_uvs`] when every face corner has one, normals
/// are not used. Polygons are split into triangle fans and counted. `o`, `g`, `usemtl`, `s`, `l`, `p`,
/// `mtllib` and unknown statements are ignored; `#` starts a comment anywhere.
///
/// Fails on binary or non-UTF-8 data, malformed `v`/`f` lines, non-finite
/// coordinates, indices out of range, and a mesh without vertices or faces.
pub fn load_obj_bytes(bytes: &[u8], path: &Path) -> Result<LoadReport, MeshError> {
    let err = |line: usize, message: String| MeshError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    if let Some(nul) = bytes.iter().position(|&b| b == 0) {
        return Err(err(
            line_of(bytes, nul),
            "binary data (a NUL byte); expected a text OBJ file".to_owned(),
        ));
    }
    let text = std::str::from_utf8(bytes).map_err(|e| {
        err(
            line_of(bytes, e.valid_up_to()),
            "not UTF-8 text; expected a text OBJ file".to_owned(),
        )
    })?;

    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    let mut counts = Counts::default();
    let mut triangulated_polygons = 0usize;
    let mut corners: Vec<(u32, Option<usize>)> = Vec::new();
    let mut uvs: Vec<[f32; 2]> = Vec::new();
    // Texture-coordinate indices of each triangle's corners while every corner has one.
    let mut corner_uv_indices: Option<Vec<[usize; 3]>> = Some(Vec::new());

    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut words = content.split_whitespace();
        match words.next() {
            Some("v") => {
                if positions.len() > u32::MAX as usize {
                    return Err(err(line, "more vertices than weft indexes (2^32)".into()));
                }
                positions.push(parse_vertex(words).map_err(|m| err(line, m))?);
                counts.v = positions.len();
            }
            Some("vt") => {
                uvs.push(parse_uv(words).map_err(|m| err(line, m))?);
                counts.vt = uvs.len();
            }
            Some("vn") => counts.vn += 1,
            Some("f") => {
                corners.clear();
                for word in words {
                    corners.push(counts.corner(word, line).map_err(|m| err(line, m))?);
                }
                if corners.len() < 3 {
                    return Err(err(
                        line,
                        format!("face with {} corners; expected at least 3", corners.len()),
                    ));
                }
                if corners.len() > 3 {
                    triangulated_polygons += 1;
                }
                let first = corners[0];
                for pair in corners[1..].windows(2) {
                    faces.push([first.0, pair[0].0, pair[1].0]);
                    corner_uv_indices = corner_uv_indices.and_then(|mut all| {
                        all.push([first.1?, pair[0].1?, pair[1].1?]);
                        Some(all)
                    });
                }
            }
            _ => {}
        }
    }
    counts
        .check_forward_references()
        .map_err(|(line, m)| err(line, m))?;

    let mesh = TriMesh::new(positions, faces);
    check(&mesh, path)?;
    // Indices are range-checked above, forward ones included.
    let corner_uvs = corner_uv_indices
        .filter(|_| !uvs.is_empty())
        .map(|all| all.iter().map(|t| t.map(|k| uvs[k])).collect());
    Ok(LoadReport {
        mesh,
        format: MeshFormat::Obj,
        triangulated_polygons,
        corner_uvs,
    })
}

/// `u [v [w]]` after `vt`: `v` defaults to 0 and `w` is checked and ignored.
fn parse_uv<'a>(words: impl Iterator<Item = &'a str>) -> Result<[f32; 2], String> {
    let mut uv = [0.0f32; 2];
    let mut n = 0;
    for word in words {
        let x = parse_number(word)?;
        if n < 2 {
            uv[n] = x as f32;
            if !uv[n].is_finite() {
                return Err(format!(
                    "texture coordinate `{word}` is not a finite 32-bit float"
                ));
            }
        } else if n > 2 {
            return Err("`vt` with more than three numbers; expected `vt u [v [w]]`".to_owned());
        }
        n += 1;
    }
    if n == 0 {
        return Err("`vt` without numbers; expected `vt u [v [w]]`".to_owned());
    }
    Ok(uv)
}

/// `x y z` and optional further numbers after `v`.
fn parse_vertex<'a>(mut words: impl Iterator<Item = &'a str>) -> Result<[f64; 3], String> {
    let mut p = [0.0; 3];
    for (k, c) in p.iter_mut().enumerate() {
        let word = words
            .next()
            .ok_or_else(|| format!("vertex with {k} coordinates; expected `v x y z`"))?;
        *c = parse_number(word)?;
        if !c.is_finite() {
            return Err(format!(
                "coordinate `{word}` is not finite; expected a finite number"
            ));
        }
    }
    for word in words {
        parse_number(word).map_err(|_| {
            format!("`{word}` after the coordinates; expected only numbers (w, or r g b)")
        })?;
    }
    Ok(p)
}

fn parse_number(word: &str) -> Result<f64, String> {
    word.parse()
        .map_err(|_| format!("`{word}` is not a number; expected a coordinate"))
}

/// Elements defined so far, and the largest positive (forward-reaching) index of each
/// kind with its line, to check once the whole file is read.
#[derive(Default)]
struct Counts {
    v: usize,
    vt: usize,
    vn: usize,
    max: [(usize, usize); 3],
}

/// Singular and plural names of the three index kinds.
const KINDS: [(&str, &str); 3] = [
    ("vertex", "vertices"),
    ("texture coordinate", "texture coordinates"),
    ("normal", "normals"),
];

impl Counts {
    /// The 0-based position and texture-coordinate indices of one face corner
    /// `v[/vt[/vn]]`; checks all three.
    fn corner(&mut self, word: &str, line: usize) -> Result<(u32, Option<usize>), String> {
        let mut parts = word.split('/');
        let mut v = 0;
        let mut vt = None;
        for kind in 0..3 {
            let Some(part) = parts.next() else { break };
            if part.is_empty() && kind > 0 {
                continue; // `v//vn` or `v/`
            }
            let index = self.resolve(part, kind, line)?;
            if kind == 0 {
                v = u32::try_from(index).map_err(|_| {
                    format!("vertex index `{part}` is larger than weft indexes (2^32)")
                })?;
            } else if kind == 1 {
                vt = Some(index);
            }
        }
        if parts.next().is_some() {
            return Err(format!(
                "face corner `{word}` has more than three parts; expected v, v/vt, v/vt/vn or v//vn"
            ));
        }
        Ok((v, vt))
    }

    /// A 0-based index from a 1-based or negative (relative) OBJ index.
    fn resolve(&mut self, part: &str, kind: usize, line: usize) -> Result<usize, String> {
        let what = KINDS[kind].0;
        let defined = [self.v, self.vt, self.vn][kind];
        let k: i64 = part.parse().map_err(|_| {
            format!("{what} index `{part}` is not an integer; expected a 1-based or negative index")
        })?;
        if k > 0 {
            let index = (k - 1) as usize;
            if index >= self.max[kind].0 {
                self.max[kind] = (index + 1, line);
            }
            Ok(index)
        } else if k < 0 {
            let back = k.unsigned_abs();
            if back > defined as u64 {
                return Err(format!(
                    "relative {what} index {k} reaches before the first {what} \
                     ({defined} defined so far)"
                ));
            }
            Ok(defined - back as usize)
        } else {
            Err(format!("{what} index 0; OBJ indices start at 1"))
        }
    }

    /// Positive indices may point forward: check them against the final counts.
    fn check_forward_references(&self) -> Result<(), (usize, String)> {
        let defined = [self.v, self.vt, self.vn];
        for kind in 0..3 {
            let (largest, line) = self.max[kind];
            if largest > defined[kind] {
                let (what, plural) = KINDS[kind];
                return Err((
                    line,
                    format!(
                        "{what} index {largest} is out of range; the file defines {} {plural}",
                        defined[kind]
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Writes `mesh` as ascii OBJ: a comment, `v x y z` (round-trip precision) and
/// `f a b c` (1-based).
pub fn write_obj_to(w: &mut dyn Write, mesh: &TriMesh) -> io::Result<()> {
    writeln!(
        w,
        "# weft: {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.faces.len()
    )?;
    let mut line = String::with_capacity(80);
    for p in &mesh.positions {
        line.clear();
        line.push('v');
        for &c in p {
            line.push(' ');
            fmt_f64(&mut line, c);
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    for f in &mesh.faces {
        writeln!(
            w,
            "f {} {} {}",
            u64::from(f[0]) + 1,
            u64::from(f[1]) + 1,
            u64::from(f[2]) + 1
        )?;
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;

    fn load(text: &str) -> Result<LoadReport, MeshError> {
        load_obj_bytes(text.as_bytes(), Path::new("t.obj"))
    }

    fn err(text: &str) -> String {
        load(text).unwrap_err().to_string()
    }

    const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

    #[test]
    fn reads_triangles_and_ignores_what_it_does_not_need() {
        let text = "# a comment\r\nmtllib x.mtl\r\no thing\r\nv 0 0 0\r\nv 1 0 0 1\r\n\
                    v 0 1 0 0.5 0.5 0.5\r\nvt 0 0\r\nvn 0 0 1\r\ns off\r\nusemtl red\r\n\
                    f 1/1/1 2//1 3/1 # trailing comment\r\nl 1 2\r\np 3\r\n";
        let r = load(text).unwrap();
        assert_eq!(
            r.mesh.positions,
            vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]
        );
        assert_eq!(r.mesh.faces, vec![[0, 1, 2]]);
        assert_eq!(r.triangulated_polygons, 0);
        assert_eq!(r.format, MeshFormat::Obj);
    }

    #[test]
    fn quads_and_ngons_become_fans_and_are_counted() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\n\
                    f 1 2 3 4\nf 1 2 3\nf 1 2 3 4 5\n";
        let r = load(text).unwrap();
        assert_eq!(
            r.mesh.faces,
            vec![
                [0, 1, 2],
                [0, 2, 3],
                [0, 1, 2],
                [0, 1, 2],
                [0, 2, 3],
                [0, 3, 4]
            ]
        );
        assert_eq!(r.triangulated_polygons, 2);
    }

    #[test]
    fn objects_and_groups_share_the_global_vertex_list() {
        // Two panels sharing the seam 2–3: one connected mesh, vertex order as written,
        // the unused vertex kept.
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 9 9 9\n\
                    o front\nf 1 2 3\ng back\nusemtl other\nf 2 5 3\n";
        let m = load(text).unwrap().mesh;
        assert_eq!(m.positions.len(), 6);
        assert_eq!(m.faces, vec![[0, 1, 2], [1, 4, 2]]);
        assert_eq!(m.graph().components().count, 3); // the mesh, vertex 3, vertex 5
    }

    #[test]
    fn uv_seams_do_not_split_vertices() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                    vt 5 5\nf 1/1 2/2 3/3\nf 1/5 3/5 4/4\n";
        let m = load(text).unwrap().mesh;
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn corner_uvs_follow_the_triangle_fans() {
        // A quad with its own UVs and a triangle reaching a forward `vt`.
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                    f 1/1 2/2 3/3 4/4\nf 2/-3 3/5 4/4\nvt 0.25 0.5 0\n";
        let r = load(text).unwrap();
        assert_eq!(r.mesh.faces, vec![[0, 1, 2], [0, 2, 3], [1, 2, 3]]);
        assert_eq!(
            r.corner_uvs.unwrap(),
            vec![
                [[0., 0.], [1., 0.], [1., 1.]],
                [[0., 0.], [1., 1.], [0., 1.]],
                [[1., 0.], [0.25, 0.5], [0., 1.]]
            ]
        );
        // One corner without a UV, or no `vt` at all: no UVs.
        assert_eq!(
            load("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3\n")
                .unwrap()
                .corner_uvs,
            None
        );
        assert_eq!(load(&format!("{TRI}f 1 2 3\n")).unwrap().corner_uvs, None);
        assert_eq!(
            load("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5\nf 1/1 2/1 3/1\n")
                .unwrap()
                .corner_uvs
                .unwrap()[0][0],
            [0.5, 0.0]
        );
        assert_eq!(
            err("vt\n"),
            "t.obj:1: `vt` without numbers; expected `vt u [v [w]]`"
        );
        assert_eq!(
            err("vt 0 x\n"),
            "t.obj:1: `x` is not a number; expected a coordinate"
        );
        assert_eq!(
            err("vt 0 1e40\n"),
            "t.obj:1: texture coordinate `1e40` is not a finite 32-bit float"
        );
        assert_eq!(
            err("vt 0 0 0 0\n"),
            "t.obj:1: `vt` with more than three numbers; expected `vt u [v [w]]`"
        );
    }

    #[test]
    fn relative_and_forward_indices() {
        let m = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1 2 4\nv 1 1 0\n")
            .unwrap()
            .mesh;
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 1, 3]]);
    }

    #[test]
    fn errors_name_the_file_and_line() {
        assert_eq!(
            err("v 0 0 0\nv 1 0\n"),
            "t.obj:2: vertex with 2 coordinates; expected `v x y z`"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 zero 0\n"),
            "t.obj:2: `zero` is not a number; expected a coordinate"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\n\nv nan 0 0\n"),
            "t.obj:4: coordinate `nan` is not finite; expected a finite number"
        );
        assert!(err("v 1 inf 0\n").starts_with("t.obj:1: coordinate `inf`"));
        assert!(err("v 1 0 0 w\n").starts_with("t.obj:1: `w` after the coordinates"));
        assert_eq!(
            err(&format!("{TRI}f 1 2 9\nf 1 2 3\n")),
            "t.obj:4: vertex index 9 is out of range; the file defines 3 vertices"
        );
        assert_eq!(
            err(&format!("{TRI}f 0 1 2\n")),
            "t.obj:4: vertex index 0; OBJ indices start at 1"
        );
        assert_eq!(
            err(&format!("{TRI}f -1 -2 -4\n")),
            "t.obj:4: relative vertex index -4 reaches before the first vertex (3 defined so far)"
        );
        assert_eq!(
            err(&format!("{TRI}f 1 2\n")),
            "t.obj:4: face with 2 corners; expected at least 3"
        );
        assert!(err(&format!("{TRI}f 1 2 3.5\n"))
            .starts_with("t.obj:4: vertex index `3.5` is not an integer"));
        assert!(err(&format!("{TRI}f 1 2 99999999999999999999\n"))
            .starts_with("t.obj:4: vertex index `99999999999999999999`"));
        assert!(err(&format!("{TRI}f 1 2 9999999999\n"))
            .starts_with("t.obj:4: vertex index `9999999999` is larger"));
        assert!(err(&format!("{TRI}f 1/1/1/1 2 3\n"))
            .starts_with("t.obj:4: face corner `1/1/1/1` has more than three parts"));
        assert!(err(&format!("{TRI}f /1 2 3\n"))
            .starts_with("t.obj:4: vertex index `` is not an integer"));
    }

    #[test]
    fn texture_and_normal_indices_are_range_checked() {
        assert_eq!(
            err(&format!("{TRI}vt 0 0\nf 1/1 2/2 3/1\n")),
            "t.obj:5: texture coordinate index 2 is out of range; the file defines 1 texture coordinates"
        );
        // The relative texture index that overflows inside tobj.
        assert_eq!(
            err(&format!("{TRI}vt 0 0\nf 1/-3 2/1 3/1\n")),
            "t.obj:5: relative texture coordinate index -3 reaches before the first texture coordinate (1 defined so far)"
        );
        assert!(err(&format!("{TRI}f 1//1 2//1 3//1\n"))
            .starts_with("t.obj:4: normal index 1 is out of range"));
    }

    #[test]
    fn binary_and_empty_input_fail() {
        assert_eq!(
            load_obj_bytes(b"v 0 0 0\n\xff\xfe", Path::new("g.obj"))
                .unwrap_err()
                .to_string(),
            "g.obj:2: not UTF-8 text; expected a text OBJ file"
        );
        assert_eq!(
            load_obj_bytes(b"v 0 0 0\nv \0", Path::new("g.obj"))
                .unwrap_err()
                .to_string(),
            "g.obj:2: binary data (a NUL byte); expected a text OBJ file"
        );
        for text in ["", "# nothing\n", "v 0 0 0\n", "garbage words\n"] {
            let e = load(text).unwrap_err();
            assert!(matches!(e, MeshError::Empty { .. }), "{text:?}: {e}");
        }
    }

    /// A random small mesh with valid indices and finite coordinates.
    pub(crate) fn small_mesh() -> impl Strategy<Value = TriMesh> {
        (1usize..12).prop_flat_map(|n| {
            (
                prop::collection::vec(prop::array::uniform3(-1e6f64..1e6), n),
                prop::collection::vec(prop::array::uniform3(0..n as u32), 1..20),
            )
                .prop_map(|(positions, faces)| TriMesh::new(positions, faces))
        })
    }

    proptest! {
        #[test]
        fn write_then_read_is_identity(mut mesh in small_mesh(), tiny in any::<bool>()) {
            if tiny {
                // Exercise exponent formatting too.
                for p in &mut mesh.positions {
                    p[0] *= 1e-12;
                }
            }
            let mut bytes = Vec::new();
            write_obj_to(&mut bytes, &mesh).unwrap();
            let back = load_obj_bytes(&bytes, Path::new("p.obj")).unwrap();
            prop_assert_eq!(back.mesh, mesh);
            prop_assert_eq!(back.triangulated_polygons, 0);
        }

        /// On files without objects or groups, tobj (which renumbers vertices) must see
        /// the same triangles, compared by their corner positions.
        #[test]
        fn triangles_agree_with_tobj(
            positions in prop::collection::vec(prop::array::uniform3(-100i32..100), 3..10),
            polygons in prop::collection::vec(prop::collection::vec(any::<prop::sample::Index>(), 3..7), 1..8),
            style in 0usize..4,
            crlf in any::<bool>(),
        ) {
            let n = positions.len();
            let eol = if crlf { "\r\n" } else { "\n" };
            let mut text = String::new();
            for p in &positions {
                text += &format!("v {} {} {}{eol}", p[0], p[1], p[2]);
            }
            text += &format!("vt 0 0{eol}vn 0 0 1{eol}");
            for poly in &polygons {
                text += "f";
                for ix in poly {
                    let i = ix.index(n);
                    let v = if style == 3 { format!("-{}", n - i) } else { (i + 1).to_string() };
                    text += &match style {
                        0 | 3 => format!(" {v}"),
                        1 => format!(" {v}/1"),
                        _ => format!(" {v}/1/1"),
                    };
                }
                text += eol;
            }
            let ours = load_obj_bytes(text.as_bytes(), Path::new("d.obj")).unwrap();
            let opts = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
            let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
                Err(tobj::LoadError::OpenFileFailed)
            }).unwrap();
            let mut theirs = Vec::new();
            for m in &models {
                let p = &m.mesh.positions;
                for t in m.mesh.indices.chunks(3) {
                    theirs.push(t.iter().map(|&i| {
                        let i = i as usize * 3;
                        [p[i] as f64, p[i + 1] as f64, p[i + 2] as f64]
                    }).collect::<Vec<_>>());
                }
            }
            let mine: Vec<Vec<[f64; 3]>> = ours.mesh.faces.iter()
                .map(|f| f.iter().map(|&i| ours.mesh.positions[i as usize]).collect())
                .collect();
            prop_assert_eq!(mine, theirs);
            prop_assert_eq!(ours.triangulated_polygons, polygons.iter().filter(|p| p.len() > 3).count());
        }
    }
}
