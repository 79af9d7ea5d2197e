//! New positions written into a garment's own OBJ text.
//!
//! weft-mesh's mesh holds only positions and triangles (UVs come beside it, per triangle
//! corner, and groups and materials not at all), but a garment's UVs are its sewing
//! pattern, the rest frames of the simulator's membrane energy. Preparation moves
//! vertices and never changes the topology, so instead of writing a fresh OBJ it rewrites
//! the `v` lines of the input in place: the i-th `v` statement gets the i-th position
//! (weft-mesh keeps the file's global vertex order), and every other line — `vt`,
//! `f v/vt`, groups, materials, comments — is kept byte for byte.

use std::path::Path;

use super::PrepareError;

/// Rewrites the `v` lines of the OBJ `text` with `positions` (`path` only names the file
/// in errors). Fails when the file has a different number of `v` statements.
pub fn write_positions_into_obj(
    text: &str,
    positions: &[[f64; 3]],
    path: &Path,
) -> Result<String, PrepareError> {
    let mut out = String::with_capacity(text.len() + positions.len() * 8);
    let mut next = 0usize;
    for raw in text.split_inclusive('\n') {
        let body = raw.trim_end_matches(['\n', '\r']);
        let ending = &raw[body.len()..];
        let content = body.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        if tokens.next() == Some("v") {
            let Some(p) = positions.get(next) else {
                return Err(PrepareError::ObjText {
                    path: path.display().to_string(),
                    message: format!(
                        "has more `v` lines than the {} positions to write",
                        positions.len()
                    ),
                });
            };
            // `{}` of an f64 is the shortest text that reads back to the same value.
            out.push_str(&format!("v {} {} {}", p[0], p[1], p[2]));
            if let Some(comment) = body.find('#').map(|i| &body[i..]) {
                out.push(' ');
                out.push_str(comment);
            }
            out.push_str(ending);
            next += 1;
        } else {
            out.push_str(raw);
        }
    }
    if next != positions.len() {
        return Err(PrepareError::ObjText {
            path: path.display().to_string(),
            message: format!(
                "has {next} `v` lines, expected {} (one per garment vertex)",
                positions.len()
            ),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_v_lines_and_keeps_everything_else() {
        let text = "# garment\nv 0 0 0\nv 1 0 0 # corner\r\nvt 0.5 0.5\nv 0 1 0\nf 1/1 2/1 3/1\n";
        let out = write_positions_into_obj(
            text,
            &[[0.25, 0.0, -1.0], [1.0, 2.0, 3.0], [0.1, 0.2, 0.3]],
            Path::new("g.obj"),
        )
        .unwrap();
        assert_eq!(
            out,
            "# garment\nv 0.25 0 -1\nv 1 2 3 # corner\r\nvt 0.5 0.5\nv 0.1 0.2 0.3\nf 1/1 2/1 3/1\n"
        );
        let mesh = weft_mesh::io::load_obj_bytes(out.as_bytes(), Path::new("g.obj"))
            .unwrap()
            .mesh;
        assert_eq!(mesh.positions[1], [1.0, 2.0, 3.0]);
    }

    #[test]
    fn count_mismatch_is_an_error() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let e = write_positions_into_obj(text, &[[0.0; 3]; 2], Path::new("g.obj")).unwrap_err();
        assert!(e.to_string().contains("more `v` lines"), "{e}");
        let e = write_positions_into_obj(text, &[[0.0; 3]; 4], Path::new("g.obj")).unwrap_err();
        assert!(e.to_string().contains("has 3 `v` lines, expected 4"), "{e}");
    }
}
