//! PC2 point caches, the vertex-animation format of 3ds Max that Blender's Mesh Cache
//! modifier, Maya (via plug-ins), Houdini and Unreal's importers read.
//!
//! Layout, all little-endian (as Blender's `MOD_meshcache_pc2` reads it):
//!
//! ```text
//! char[12]  "POINTCACHE2\0"
//! i32       file version, 1
//! i32       point count N
//! f32       start frame
//! f32       sampling: frames between samples
//! i32       sample count T
//! f32[T][N][3]  positions, sample-major
//! ```
//!
//! What weft writes in the timing fields, and why: `start frame = 0`, `sampling = 1`, so
//! sample `k` is frame `k`, which is also the glTF exporter's time `k / fps`. Blender's
//! Mesh Cache modifier in its default "Frame" time mode ignores both fields (sample index
//! = scene frame − the modifier's own *Frame Start*, default 0); only its "Seconds" mode
//! reads them. PC2 stores no frame rate: the scene's rate applies.
//!
//! Coordinates are weft's: metres, right-handed, Y up. They are the template OBJ's own
//! coordinates, so the cache applies to a template imported into Blender (whose OBJ
//! importer puts the Y-up→Z-up turn on the object, not on the vertices) with the
//! modifier's default axes.

use std::io::{self, Write};
use std::path::Path;

use super::error::ExportError;
use super::{check_i32, write_f32_frames, Endian, Frames};
use crate::io::write_atomic;

/// The 12 magic bytes every PC2 file starts with.
pub const PC2_MAGIC: &[u8; 12] = b"POINTCACHE2\0";

/// Bytes before the first position.
pub const PC2_HEADER_LEN: usize = 32;

/// The two timing fields of a PC2 header.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pc2Timing {
    /// The frame of the first sample.
    pub start_frame: f32,
    /// Frames between samples (1 = a sample every frame).
    pub sampling: f32,
}

impl Default for Pc2Timing {
    /// Sample `k` at frame `k`.
    fn default() -> Self {
        Pc2Timing {
            start_frame: 0.0,
            sampling: 1.0,
        }
    }
}

/// A PC2 file read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Pc2 {
    /// The samples.
    pub frames: Frames,
    /// The header's timing fields.
    pub timing: Pc2Timing,
}

/// Writes `frames` as a PC2 point cache, atomically. Fails without touching `path` when
/// there are no frames, a coordinate is not finite, the timing is not finite (or the
/// sampling not positive), or a count exceeds `i32`.
pub fn write_pc2(path: &Path, frames: &Frames, timing: Pc2Timing) -> Result<(), ExportError> {
    check(frames, timing)?;
    write_atomic(path, |w| write_pc2_to(w, frames, timing)).map_err(|e| ExportError::write(path, e))
}

/// Writes a PC2 file to `w`. Unchecked: call through [`write_pc2`], or check the frames
/// yourself (counts within `i32`, finite values).
pub fn write_pc2_to(w: &mut dyn Write, frames: &Frames, timing: Pc2Timing) -> io::Result<()> {
    let mut head = Vec::with_capacity(PC2_HEADER_LEN);
    head.extend_from_slice(PC2_MAGIC);
    head.extend_from_slice(&1i32.to_le_bytes());
    head.extend_from_slice(&(frames.vertex_count() as i32).to_le_bytes());
    head.extend_from_slice(&timing.start_frame.to_le_bytes());
    head.extend_from_slice(&timing.sampling.to_le_bytes());
    head.extend_from_slice(&(frames.frame_count() as i32).to_le_bytes());
    w.write_all(&head)?;
    write_f32_frames(w, frames, Endian::Little)
}

fn check(frames: &Frames, timing: Pc2Timing) -> Result<(), ExportError> {
    if frames.is_empty() {
        return Err(ExportError::NoFrames);
    }
    check_i32("PC2", "the vertex count", frames.vertex_count())?;
    check_i32("PC2", "the frame count", frames.frame_count())?;
    if !(timing.start_frame.is_finite() && timing.sampling.is_finite() && timing.sampling > 0.0) {
        return Err(ExportError::Pc2Timing {
            start_frame: timing.start_frame,
            sampling: timing.sampling,
        });
    }
    frames.check_finite()
}

/// Reads a PC2 file; see [`parse_pc2`].
pub fn read_pc2(path: &Path) -> Result<Pc2, ExportError> {
    let bytes = crate::io::read_input(path).map_err(|e| ExportError::read(path, e))?;
    parse_pc2(&bytes, path)
}

/// Parses a PC2 file held in memory; `path` only names the file in errors.
///
/// Strict: the magic, version 1, positive counts, finite timing, and a file size of
/// exactly the header plus `T × N × 12` bytes.
pub fn parse_pc2(bytes: &[u8], path: &Path) -> Result<Pc2, ExportError> {
    let bad = |m: String| ExportError::format(path, m);
    if bytes.len() < PC2_HEADER_LEN || &bytes[..12] != PC2_MAGIC {
        return Err(bad(
            "not a PC2 file (it does not start with \"POINTCACHE2\\0\" and a 32-byte header)"
                .into(),
        ));
    }
    let i32_at =
        |o: usize| i32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let f32_at =
        |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let version = i32_at(12);
    if version != 1 {
        return Err(bad(format!("PC2 version {version}; expected 1")));
    }
    let (points, start_frame, sampling, samples) = (i32_at(16), f32_at(20), f32_at(24), i32_at(28));
    if points <= 0 || samples <= 0 {
        return Err(bad(format!(
            "{points} points and {samples} samples; expected positive counts"
        )));
    }
    if !(start_frame.is_finite() && sampling.is_finite()) {
        return Err(bad(format!(
            "start frame {start_frame} and sampling {sampling}; expected finite numbers"
        )));
    }
    let (n, t) = (points as usize, samples as usize);
    let expected = n
        .checked_mul(t)
        .and_then(|x| x.checked_mul(12))
        .and_then(|x| x.checked_add(PC2_HEADER_LEN));
    if expected != Some(bytes.len()) {
        return Err(bad(format!(
            "{} bytes, but {t} samples of {n} points need {}; the file is truncated or its header is wrong",
            bytes.len(),
            expected.map_or("more than fits in memory".into(), |e| e.to_string())
        )));
    }
    let positions = super::read_f32_triples(&bytes[PC2_HEADER_LEN..], Endian::Little);
    Ok(Pc2 {
        frames: Frames::from_positions(n, positions)?,
        timing: Pc2Timing {
            start_frame,
            sampling,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_dir::TestDir;

    fn frames() -> Frames {
        Frames::from_frames(&[
            vec![[0., 0., 0.], [1., 0., 0.5]],
            vec![[0.25, -1., 1e-30], [f32::MAX, f32::MIN_POSITIVE, -0.0]],
            vec![[3., 2., 1.], [0.1, 0.2, 0.3]],
        ])
        .unwrap()
    }

    #[test]
    fn header_layout_matches_blender() {
        let mut bytes = Vec::new();
        write_pc2_to(&mut bytes, &frames(), Pc2Timing::default()).unwrap();
        assert_eq!(bytes.len(), 32 + 3 * 2 * 12);
        assert_eq!(&bytes[..12], b"POINTCACHE2\0");
        assert_eq!(bytes[12..16], 1i32.to_le_bytes());
        assert_eq!(bytes[16..20], 2i32.to_le_bytes());
        assert_eq!(bytes[20..24], 0f32.to_le_bytes());
        assert_eq!(bytes[24..28], 1f32.to_le_bytes());
        assert_eq!(bytes[28..32], 3i32.to_le_bytes());
        // Sample 1, point 0, y.
        assert_eq!(bytes[32 + 24 + 4..32 + 24 + 8], (-1f32).to_le_bytes());
    }

    #[test]
    fn round_trip_is_exact() {
        let dir = TestDir::new("pc2");
        let path = dir.0.join("a.pc2");
        let timing = Pc2Timing {
            start_frame: 1.0,
            sampling: 0.5,
        };
        write_pc2(&path, &frames(), timing).unwrap();
        let back = read_pc2(&path).unwrap();
        assert_eq!(
            back,
            Pc2 {
                frames: frames(),
                timing
            }
        );
    }

    #[test]
    fn strict_reader() {
        let p = Path::new("c.pc2");
        let mut good = Vec::new();
        write_pc2_to(&mut good, &frames(), Pc2Timing::default()).unwrap();
        let err = |b: &[u8]| parse_pc2(b, p).unwrap_err().to_string();
        assert!(err(b"POINTCACHE").starts_with("c.pc2: not a PC2 file"));
        assert!(err(&good[..good.len() - 1]).contains("bytes, but 3 samples of 2 points need 104"));
        let mut v = good.clone();
        v[12] = 2;
        assert!(err(&v).contains("PC2 version 2; expected 1"));
        let mut v = good.clone();
        v[28..32].copy_from_slice(&0i32.to_le_bytes());
        assert!(err(&v).contains("expected positive counts"));
        let mut v = good.clone();
        v[16..20].copy_from_slice(&i32::MAX.to_le_bytes());
        v[28..32].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(err(&v).contains("the file is truncated"));
    }

    #[test]
    fn refuses_nan_and_leaves_nothing() {
        let dir = TestDir::new("pc2-nan");
        let mut f = frames();
        f.positions_mut_for_test()[3][0] = f32::NAN;
        let e = write_pc2(&dir.0.join("a.pc2"), &f, Pc2Timing::default()).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("frame 1, vertex 1: the x coordinate is NaN"));
        assert!(dir.entries().is_empty());
        std::fs::write(dir.0.join("f"), b"").unwrap();
        let e = write_pc2(&dir.0.join("f/a.pc2"), &frames(), Pc2Timing::default()).unwrap_err();
        assert!(e.to_string().starts_with("cannot write "), "{e}");
        assert_eq!(dir.entries(), vec!["f"]);
    }
}
