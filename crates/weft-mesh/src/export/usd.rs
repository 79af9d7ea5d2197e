//! USD (`.usda`, `.usd`): animated meshes for Maya, Houdini, Unreal's ML Deformer,
//! Omniverse and every other tool of the film and game pipeline.
//!
//! What is written, and why:
//!
//! - One stage with stage metadata a DCC needs to place the animation: `upAxis = "Y"`,
//!   `metersPerUnit = 1` (weft's units, so nothing is converted), `timeCodesPerSecond`
//!   and `framesPerSecond` both the frame rate, and `startTimeCode`/`endTimeCode`
//!   spanning the frames. Frame `k` is time code `k`.
//! - An `Xform` prim `/weft` (the default prim) holding one `Mesh` prim per
//!   [`AnimatedMesh`] (`garment`, `body`): `faceVertexCounts` and `faceVertexIndices` of the
//!   triangles, `points` as **time samples** (one per frame; a one-frame mesh gets a
//!   default value instead, so it is static), a time-sampled `extent` as `UsdGeomBoundable`
//!   asks, `subdivisionScheme = "none"` (garments are render meshes, not subdivision
//!   cages), `doubleSided`, a constant `primvars:displayColor`, and, when the mesh has
//!   UVs, the indexed face-varying `primvars:st` (the distinct UVs once, one index per
//!   corner), the name and layout UsdPreviewSurface and every DCC read.
//! - Triangles keep weft's counter-clockwise front faces, USD's default `rightHanded`
//!   orientation.
//! - Coordinates are the shortest decimal that reads back to the same `f32`, so the
//!   stage's points equal weft's frames bit for bit.
//!
//! Text, not the binary crate format (`.usdc`): there is no well-kept Rust writer of
//! crate files whose output Pixar's reader opens (openusd 0.6's was tried and refused by
//! usd-core 26.11), and the crate format is a large, versioned binary with compressed
//! sections — not something to write by hand beside a text format every USD reader
//! takes. `usdcat X.usda -o X.usdc` (PyPI `usd-core`) converts when the binary is wanted.

use std::io::{self, Write};
use std::path::Path;

use super::error::ExportError;
use super::frames::bounds;
use super::obj_sequence::fmt_f32;
use super::scene::{check_scene, AnimatedMesh, IndexedUvs};
use super::validate_fps;
use crate::io::write_atomic;

/// The name of the stage's root prim, its default prim.
pub const ROOT_PRIM: &str = "weft";

/// Writes the meshes as one USD text layer at `path`, atomically, at `fps` frames per
/// second. Fails without touching `path` on no meshes, a mesh without frames, NaN
/// coordinates or UVs, faces out of range, animated meshes with different frame counts,
/// a bad `fps`, a mesh name that is not a USD identifier, or a binary-only extension.
pub fn write_usd(path: &Path, meshes: &[AnimatedMesh<'_>], fps: f32) -> Result<(), ExportError> {
    check_extension(path)?;
    validate_fps(fps)?;
    let frame_count = check_scene(meshes)?;
    for m in meshes {
        check_identifier(m.name)?;
    }
    write_atomic(path, |w| write_stage(w, meshes, fps, frame_count))
        .map_err(|e| ExportError::write(path, e))
}

/// `.usda` and `.usd` hold text; `.usdc` and `.usdz` are binary and refused with the way
/// to get them.
fn check_extension(path: &Path) -> Result<(), ExportError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("usda") | Some("usd") => Ok(()),
        Some("usdc") | Some("usdz") => Err(ExportError::format(
            path,
            "weft writes USD as text (.usda or .usd); for the binary crate format write \
             .usda and convert it with `usdcat X.usda -o X.usdc` (PyPI usd-core)",
        )),
        _ => Err(ExportError::format(
            path,
            "expected a .usda or .usd file name for USD output",
        )),
    }
}

/// A prim name must be a USD identifier: a letter or `_`, then letters, digits or `_`.
fn check_identifier(name: &str) -> Result<(), ExportError> {
    let mut chars = name.chars();
    let ok = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(ExportError::MeshName {
            name: name.to_owned(),
        })
    }
}

fn write_stage(
    w: &mut dyn Write,
    meshes: &[AnimatedMesh<'_>],
    fps: f32,
    frame_count: usize,
) -> io::Result<()> {
    let rate = f64::from(fps);
    writeln!(w, "#usda 1.0")?;
    writeln!(w, "(")?;
    writeln!(w, "    defaultPrim = \"{ROOT_PRIM}\"")?;
    writeln!(
        w,
        "    doc = \"weft {}: metres, Y up, frame k at time code k\"",
        env!("CARGO_PKG_VERSION")
    )?;
    writeln!(w, "    endTimeCode = {}", frame_count - 1)?;
    writeln!(w, "    framesPerSecond = {rate}")?;
    writeln!(w, "    metersPerUnit = 1")?;
    writeln!(w, "    startTimeCode = 0")?;
    writeln!(w, "    timeCodesPerSecond = {rate}")?;
    writeln!(w, "    upAxis = \"Y\"")?;
    writeln!(w, ")")?;
    writeln!(w)?;
    writeln!(w, "def Xform \"{ROOT_PRIM}\"")?;
    writeln!(w, "{{")?;
    for (i, m) in meshes.iter().enumerate() {
        if i > 0 {
            writeln!(w)?;
        }
        write_mesh(w, m)?;
    }
    writeln!(w, "}}")
}

fn write_mesh(w: &mut dyn Write, m: &AnimatedMesh<'_>) -> io::Result<()> {
    let mut s = String::new();
    writeln!(w, "    def Mesh \"{}\"", m.name)?;
    writeln!(w, "    {{")?;
    writeln!(w, "        uniform bool doubleSided = 1")?;

    sampled(w, m, "float3[] extent", &mut |s, frame| {
        let (lo, hi) = bounds(frame).unwrap_or(([0.0; 3], [0.0; 3]));
        push_tuples(s, [lo, hi].iter().map(|p| p.as_slice()));
    })?;
    writeln!(
        w,
        "        int[] faceVertexCounts = [{}]",
        vec!["3"; m.faces.len()].join(", ")
    )?;
    s.clear();
    push_ints(&mut s, m.faces.as_flattened().iter().copied());
    writeln!(w, "        int[] faceVertexIndices = [{s}]")?;
    sampled(w, m, "point3f[] points", &mut |s, frame| {
        push_tuples(s, frame.iter().map(|p| p.as_slice()));
    })?;

    s.clear();
    push_tuples(&mut s, std::iter::once(&m.color[..3]));
    writeln!(w, "        color3f[] primvars:displayColor = {s} (")?;
    writeln!(w, "            interpolation = \"constant\"")?;
    writeln!(w, "        )")?;
    if let Some(uvs) = m.uvs {
        let indexed = IndexedUvs::new(uvs);
        s.clear();
        push_tuples(&mut s, indexed.values.iter().map(|uv| uv.as_slice()));
        writeln!(w, "        texCoord2f[] primvars:st = {s} (")?;
        writeln!(w, "            interpolation = \"faceVarying\"")?;
        writeln!(w, "        )")?;
        s.clear();
        push_ints(&mut s, indexed.corners.as_flattened().iter().copied());
        writeln!(w, "        int[] primvars:st:indices = [{s}]")?;
    }
    writeln!(w, "        uniform token subdivisionScheme = \"none\"")?;
    writeln!(w, "    }}")
}

/// An attribute with one value per frame (`value` writes it): a default value for a
/// static mesh, time samples otherwise.
fn sampled(
    w: &mut dyn Write,
    m: &AnimatedMesh<'_>,
    decl: &str,
    value: &mut dyn FnMut(&mut String, &[[f32; 3]]),
) -> io::Result<()> {
    let mut s = String::new();
    if m.frames.frame_count() > 1 {
        writeln!(w, "        {decl}.timeSamples = {{")?;
        for (k, frame) in m.frames.iter().enumerate() {
            s.clear();
            value(&mut s, frame);
            writeln!(w, "            {k}: {s},")?;
        }
        writeln!(w, "        }}")
    } else {
        value(&mut s, m.frames.frame(0).unwrap_or(&[]));
        writeln!(w, "        {decl} = {s}")
    }
}

/// `[(a, b, c), (d, e, f)]` with the shortest round-trip decimals.
fn push_tuples<'v>(s: &mut String, values: impl Iterator<Item = &'v [f32]>) {
    s.push('[');
    for (i, v) in values.enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        s.push('(');
        for (k, &c) in v.iter().enumerate() {
            if k > 0 {
                s.push_str(", ");
            }
            fmt_f32(s, c);
        }
        s.push(')');
    }
    s.push(']');
}

/// `a, b, c` without brackets.
fn push_ints(s: &mut String, values: impl Iterator<Item = u32>) {
    use std::fmt::Write as _;
    for (i, v) in values.enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        let _ = write!(s, "{v}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::{Frames, GARMENT_COLOR};
    use crate::io::test_dir::TestDir;

    fn quad_frames() -> Frames {
        Frames::from_frames(&[
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![
                [0.0, 0.0, 0.5],
                [1.0, 0.0, 0.5],
                [1.0, 1.0, 0.5],
                [0.0, 1e-7, 1.0 / 3.0],
            ],
        ])
        .unwrap()
    }

    const FACES: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

    #[test]
    fn the_layer_holds_time_samples_uvs_and_stage_metadata() {
        let dir = TestDir::new("usd");
        let frames = quad_frames();
        let uvs = [
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        ];
        let out = dir.0.join("a.usda");
        let mesh = AnimatedMesh {
            name: "garment",
            faces: &FACES,
            uvs: Some(&uvs),
            frames: &frames,
            color: GARMENT_COLOR,
        };
        write_usd(&out, &[mesh], 24.0).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        for expected in [
            "#usda 1.0\n(\n    defaultPrim = \"weft\"\n",
            "    endTimeCode = 1\n    framesPerSecond = 24\n    metersPerUnit = 1\n",
            "    timeCodesPerSecond = 24\n    upAxis = \"Y\"\n)",
            "def Xform \"weft\"\n{\n    def Mesh \"garment\"\n",
            "int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]",
            "point3f[] points.timeSamples = {\n            0: [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)],\n            1: [(0, 0, 0.5), (1, 0, 0.5), (1, 1, 0.5), (0, 1e-7, 0.33333334)],\n        }",
            "float3[] extent.timeSamples = {\n            0: [(0, 0, 0), (1, 1, 0)],",
            "texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (\n            interpolation = \"faceVarying\"",
            "int[] primvars:st:indices = [0, 1, 2, 0, 2, 3]",
        ] {
            assert!(text.contains(expected), "missing {expected:?} in\n{text}");
        }

        // One frame: a static mesh with default values and no UVs.
        let still = Frames::from_frames(&[frames.frame(0).unwrap().to_vec()]).unwrap();
        let mesh = AnimatedMesh {
            uvs: None,
            frames: &still,
            ..mesh
        };
        write_usd(&out, &[mesh], 30.0).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains("point3f[] points = [(0, 0, 0),"), "{text}");
        assert!(!text.contains("timeSamples") && !text.contains("primvars:st"));
    }

    #[test]
    fn bad_scenes_and_names_write_nothing() {
        let dir = TestDir::new("usd-bad");
        let frames = quad_frames();
        let mesh = AnimatedMesh {
            name: "garment",
            faces: &FACES,
            uvs: None,
            frames: &frames,
            color: GARMENT_COLOR,
        };
        let e = write_usd(&dir.0.join("a.usdc"), &[mesh], 30.0).unwrap_err();
        assert!(e.to_string().contains("usdcat X.usda -o X.usdc"), "{e}");
        let e = write_usd(&dir.0.join("a.abc"), &[mesh], 30.0).unwrap_err();
        assert!(e
            .to_string()
            .ends_with("expected a .usda or .usd file name for USD output"));
        let e = write_usd(
            &dir.0.join("a.usda"),
            &[AnimatedMesh {
                name: "my garment",
                ..mesh
            }],
            30.0,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "mesh name `my garment` is not a USD identifier; expected a letter or `_`, then letters, digits or `_`"
        );
        let e = write_usd(
            &dir.0.join("a.usda"),
            &[AnimatedMesh {
                faces: &[[0, 1, 9]],
                ..mesh
            }],
            30.0,
        )
        .unwrap_err();
        assert!(matches!(e, ExportError::FaceIndex { .. }));
        assert!(matches!(
            write_usd(&dir.0.join("a.usda"), &[mesh], 0.0).unwrap_err(),
            ExportError::Fps { .. }
        ));
        assert!(dir.entries().is_empty());
    }
}
