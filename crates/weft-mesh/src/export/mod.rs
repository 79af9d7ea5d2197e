//! Animation export: a garment's (or a body's) vertex positions over time, written in the
//! formats graphics tools read, each with a reader so round trips are tested.
//!
//! | format | module | what it is for |
//! |---|---|---|
//! | OBJ sequence | [`obj_sequence`] | one OBJ per frame; every tool reads it |
//! | PC2 | [`pc2`] | point cache for Blender's Mesh Cache modifier, 3ds Max, Unreal |
//! | MDD | [`mdd`] | point cache for Blender, Maya, Cinema 4D, Houdini |
//! | glTF 2.0 binary | [`gltf`] | morph-target animation for engines and the web |
//! | USD | [`usd`] | time-sampled points for Maya, Houdini, Unreal, Omniverse |
//!
//! The animation itself is a [`Frames`] sequence, read from a `.npy` array
//! ([`npy`], shape `(frames, vertices, 3)`) or a directory of OBJ frames; the faces come
//! from the template mesh. All writers are atomic (temporary file, then rename) and
//! refuse NaN, so a failed export never leaves a partial or corrupt file. Units are
//! weft's throughout: metres, seconds, right-handed, Y up.

mod error;
pub mod frames;
pub mod gltf;
pub mod mdd;
pub mod npy;
pub mod obj_sequence;
pub mod pc2;
pub mod scene;
pub mod usd;

use std::fmt;
use std::io::{self, Write};
use std::path::Path;
use std::str::FromStr;

pub use error::ExportError;
pub use frames::Frames;
pub use gltf::{write_glb, write_skinned_glb, GlbOptions, Skeleton, SkinBinding};
pub use mdd::write_mdd;
pub use obj_sequence::{remove_obj_sequence, write_obj_sequence, write_obj_with_uvs};
pub use pc2::{write_pc2, Pc2Timing};
pub use scene::{AnimatedMesh, CornerUvs, BODY_COLOR, GARMENT_COLOR};
pub use usd::write_usd;

use crate::mesh::TriMesh;

/// An animation format weft writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ExportFormat {
    /// A directory of `frame_NNNNN.obj` files.
    ObjSequence,
    /// A PC2 point cache.
    Pc2,
    /// An MDD point cache.
    Mdd,
    /// A glTF 2.0 binary with morph-target animation.
    Glb,
    /// A USD text layer with time-sampled points.
    Usd,
}

impl ExportFormat {
    /// Every format, in the order the CLI lists them.
    pub const ALL: [ExportFormat; 5] = [
        ExportFormat::ObjSequence,
        ExportFormat::Pc2,
        ExportFormat::Mdd,
        ExportFormat::Glb,
        ExportFormat::Usd,
    ];

    /// The short name used on the command line: `obj`, `pc2`, `mdd`, `glb`, `usd`.
    pub fn name(self) -> &'static str {
        match self {
            ExportFormat::ObjSequence => "obj",
            ExportFormat::Pc2 => "pc2",
            ExportFormat::Mdd => "mdd",
            ExportFormat::Glb => "glb",
            ExportFormat::Usd => "usd",
        }
    }

    /// Whether the output is a directory (OBJ sequence) rather than one file.
    pub fn writes_directory(self) -> bool {
        self == ExportFormat::ObjSequence
    }

    /// Whether the format holds a scene of several meshes (the body beside the garment)
    /// rather than one point cache.
    pub fn holds_scene(self) -> bool {
        matches!(self, ExportFormat::Glb | ExportFormat::Usd)
    }
}

impl fmt::Display for ExportFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ExportFormat::ObjSequence => "OBJ sequence",
            ExportFormat::Pc2 => "PC2",
            ExportFormat::Mdd => "MDD",
            ExportFormat::Glb => "glTF binary",
            ExportFormat::Usd => "USD",
        })
    }
}

impl FromStr for ExportFormat {
    type Err = ExportError;

    /// `obj`, `pc2`, `mdd`, `glb` or `usd` (any case; `gltf` is taken for `glb`, `usda`
    /// for `usd`).
    fn from_str(s: &str) -> Result<Self, ExportError> {
        match s.to_ascii_lowercase().as_str() {
            "obj" => Ok(ExportFormat::ObjSequence),
            "pc2" => Ok(ExportFormat::Pc2),
            "mdd" => Ok(ExportFormat::Mdd),
            "glb" | "gltf" => Ok(ExportFormat::Glb),
            "usd" | "usda" => Ok(ExportFormat::Usd),
            _ => Err(ExportError::UnknownFormat { name: s.to_owned() }),
        }
    }
}

/// Writes `frames` of `template` (whose faces are used; its positions are not) in
/// `format` to `out`, a directory for OBJ sequences and a file otherwise, at `fps`
/// frames per second (PC2 stores no rate: sample `k` is frame `k`). `uvs`, the
/// template's corner UVs, go into the formats that hold texture coordinates (OBJ, glTF,
/// USD); the point caches apply to the template itself, which keeps its own.
///
/// Checks first and writes nothing on failure: the vertex counts must agree, every
/// coordinate must be finite, `fps` positive and finite.
pub fn export(
    format: ExportFormat,
    template: &TriMesh,
    uvs: Option<&CornerUvs>,
    frames: &Frames,
    fps: f32,
    out: &Path,
) -> Result<(), ExportError> {
    check_template(template, frames)?;
    validate_fps(fps)?;
    frames.check_finite()?;
    let garment = AnimatedMesh {
        name: "garment",
        faces: &template.faces,
        uvs,
        frames,
        color: GARMENT_COLOR,
    };
    write_scene(format, &[garment], fps, out)
}

/// Writes a scene: for OBJ sequences and point caches only its first mesh (they hold
/// one), for glTF and USD every mesh.
pub fn write_scene(
    format: ExportFormat,
    meshes: &[AnimatedMesh<'_>],
    fps: f32,
    out: &Path,
) -> Result<(), ExportError> {
    let first = meshes.first().ok_or(ExportError::NoFrames)?;
    match format {
        ExportFormat::ObjSequence => write_obj_sequence(out, first.faces, first.uvs, first.frames),
        ExportFormat::Pc2 => write_pc2(out, first.frames, Pc2Timing::default()),
        ExportFormat::Mdd => write_mdd(out, first.frames, fps),
        ExportFormat::Glb => write_glb(out, meshes, GlbOptions { fps, normals: true }),
        ExportFormat::Usd => write_usd(out, meshes, fps),
    }
}

/// Fails unless `frames` has one position per vertex of `template` and at least one
/// frame.
pub fn check_template(template: &TriMesh, frames: &Frames) -> Result<(), ExportError> {
    if frames.vertex_count() != template.vertex_count() {
        return Err(ExportError::VertexCount {
            frames: frames.vertex_count(),
            template: template.vertex_count(),
        });
    }
    if frames.is_empty() {
        return Err(ExportError::NoFrames);
    }
    Ok(())
}

/// Fails unless `fps` is a positive, finite frame rate.
pub fn validate_fps(fps: f32) -> Result<(), ExportError> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(ExportError::Fps { fps })
    }
}

/// `k / fps` for each frame, strictly increasing (checked: at absurd frame counts `f32`
/// times would repeat, and glTF requires increasing key times).
pub(crate) fn frame_times(frames: usize, fps: f32) -> Result<Vec<f32>, ExportError> {
    validate_fps(fps)?;
    let times: Vec<f32> = (0..frames)
        .map(|k| (k as f64 / f64::from(fps)) as f32)
        .collect();
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(ExportError::TooLarge {
            format: "32-bit frame times",
            what: "the frame count",
            value: frames as u64,
            max: (1u64 << 24),
        });
    }
    Ok(times)
}

/// Fails when `value` does not fit the `i32` fields of PC2 and MDD headers.
pub(crate) fn check_i32(
    format: &'static str,
    what: &'static str,
    value: usize,
) -> Result<(), ExportError> {
    if value <= i32::MAX as usize {
        Ok(())
    } else {
        Err(ExportError::TooLarge {
            format,
            what,
            value: value as u64,
            max: i32::MAX as u64,
        })
    }
}

/// Byte order of a binary point cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Endian {
    Little,
    Big,
}

/// Writes every position of every frame as three `f32` in `endian` order, in blocks.
pub(crate) fn write_f32_frames(
    w: &mut dyn Write,
    frames: &Frames,
    endian: Endian,
) -> io::Result<()> {
    const BLOCK: usize = 4096;
    let mut buf = Vec::with_capacity(BLOCK * 12);
    for chunk in frames.positions().chunks(BLOCK) {
        buf.clear();
        for &c in chunk.as_flattened() {
            buf.extend_from_slice(&match endian {
                Endian::Little => c.to_le_bytes(),
                Endian::Big => c.to_be_bytes(),
            });
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

/// Reads `f32` triples in `endian` order; `bytes.len()` must be a multiple of 12.
pub(crate) fn read_f32_triples(bytes: &[u8], endian: Endian) -> Vec<[f32; 3]> {
    let f = |b: &[u8]| {
        let a = [b[0], b[1], b[2], b[3]];
        match endian {
            Endian::Little => f32::from_le_bytes(a),
            Endian::Big => f32::from_be_bytes(a),
        }
    };
    bytes
        .chunks_exact(12)
        .map(|c| [f(&c[0..4]), f(&c[4..8]), f(&c[8..12])])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_dir::TestDir;
    use crate::primitives::grid;

    #[test]
    fn format_names() {
        for f in ExportFormat::ALL {
            assert_eq!(f.name().parse::<ExportFormat>().unwrap(), f);
        }
        assert_eq!("GLTF".parse::<ExportFormat>().unwrap(), ExportFormat::Glb);
        assert_eq!(
            "fbx".parse::<ExportFormat>().unwrap_err().to_string(),
            "unknown export format `fbx`; expected one of obj, pc2, mdd, glb, usd"
        );
        assert_eq!("usda".parse::<ExportFormat>().unwrap(), ExportFormat::Usd);
    }

    #[test]
    fn export_checks_before_writing() {
        let dir = TestDir::new("export");
        let g = grid(2, 3, 1.0);
        let f = Frames::from_frames(&[vec![[0.0; 3]; 5]]).unwrap();
        let e = export(ExportFormat::Pc2, &g, None, &f, 30.0, &dir.0.join("a.pc2")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the frames have 5 vertices but the template has 6; expected one position per template vertex, in the template's order"
        );
        let f = Frames::from_frames(&[vec![[0.0; 3]; 6]]).unwrap();
        let e = export(
            ExportFormat::Mdd,
            &g,
            None,
            &f,
            f32::NAN,
            &dir.0.join("a.mdd"),
        )
        .unwrap_err();
        assert!(matches!(e, ExportError::Fps { .. }));
        assert!(dir.entries().is_empty());
        for format in ExportFormat::ALL {
            let out = dir.0.join(format!("x.{}", format.name()));
            export(format, &g, None, &f, 30.0, &out).unwrap();
        }
        assert_eq!(
            dir.entries(),
            vec!["x.glb", "x.mdd", "x.obj", "x.pc2", "x.usd"]
        );
    }

    #[test]
    fn frame_times_increase() {
        assert_eq!(frame_times(3, 2.0).unwrap(), vec![0.0, 0.5, 1.0]);
        assert!(frame_times(3, -2.0).is_err());
    }
}
