//! MDD point caches (LightWave's format), read by Blender's Mesh Cache modifier, Maya,
//! Cinema 4D and Houdini.
//!
//! Layout, all **big-endian** (as Blender's `MOD_meshcache_mdd` reads it):
//!
//! ```text
//! i32           frame count T
//! i32           point count N
//! f32[T]        time of each frame, in seconds
//! f32[T][N][3]  positions, frame-major
//! ```
//!
//! weft writes frame `k` at time `k / fps` and exactly `T` position blocks. Two habits of
//! other writers it does not copy, on purpose: Blender's own MDD exporter writes an extra
//! "rest" block before the frames (so its block `k + 1` is frame `k`), and it swaps Y and
//! Z into LightWave's left-handed Y-up axes. weft keeps its own coordinates (metres,
//! right-handed, Y up) — those of the template OBJ — so the cache applies to the imported
//! template with the Mesh Cache modifier's default axes, exactly like the PC2 export.

use std::io::{self, Write};
use std::path::Path;

use super::error::ExportError;
use super::{check_i32, frame_times, read_f32_triples, write_f32_frames, Endian, Frames};
use crate::io::write_atomic;

/// An MDD file read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Mdd {
    /// The frames.
    pub frames: Frames,
    /// The time of each frame, in seconds.
    pub times: Vec<f32>,
}

/// Writes `frames` as an MDD file with frame `k` at `k / fps` seconds, atomically. Fails
/// without touching `path` when there are no frames, `fps` is not positive and finite, a
/// coordinate is not finite, or a count exceeds `i32`.
pub fn write_mdd(path: &Path, frames: &Frames, fps: f32) -> Result<(), ExportError> {
    if frames.is_empty() {
        return Err(ExportError::NoFrames);
    }
    check_i32("MDD", "the vertex count", frames.vertex_count())?;
    check_i32("MDD", "the frame count", frames.frame_count())?;
    let times = frame_times(frames.frame_count(), fps)?;
    frames.check_finite()?;
    write_atomic(path, |w| write_mdd_to(w, frames, &times)).map_err(|e| ExportError::write(path, e))
}

/// Writes an MDD file to `w` with the given frame times (one per frame). Unchecked: call
/// through [`write_mdd`], or check counts and values yourself.
pub fn write_mdd_to(w: &mut dyn Write, frames: &Frames, times: &[f32]) -> io::Result<()> {
    if times.len() != frames.frame_count() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{} frame times for {} frames",
                times.len(),
                frames.frame_count()
            ),
        ));
    }
    let mut head = Vec::with_capacity(8 + 4 * times.len());
    head.extend_from_slice(&(frames.frame_count() as i32).to_be_bytes());
    head.extend_from_slice(&(frames.vertex_count() as i32).to_be_bytes());
    for t in times {
        head.extend_from_slice(&t.to_be_bytes());
    }
    w.write_all(&head)?;
    write_f32_frames(w, frames, Endian::Big)
}

/// Reads an MDD file; see [`parse_mdd`].
pub fn read_mdd(path: &Path) -> Result<Mdd, ExportError> {
    let bytes = crate::io::read_input(path).map_err(|e| ExportError::read(path, e))?;
    parse_mdd(&bytes, path)
}

/// Parses an MDD file held in memory; `path` only names the file in errors.
///
/// Strict: positive counts and a size of exactly `8 + 4T + 12NT` bytes, so a file with
/// Blender's extra rest block (`T + 1` blocks) is reported, not silently shifted.
pub fn parse_mdd(bytes: &[u8], path: &Path) -> Result<Mdd, ExportError> {
    let bad = |m: String| ExportError::format(path, m);
    if bytes.len() < 8 {
        return Err(bad(format!(
            "{} bytes; an MDD file starts with two big-endian i32 counts",
            bytes.len()
        )));
    }
    let t = i32::from_be_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
    let n = i32::from_be_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
    if t <= 0 || n <= 0 {
        return Err(bad(format!(
            "{t} frames and {n} points; expected positive counts (is this an MDD file?)"
        )));
    }
    let (t, n) = (t as usize, n as usize);
    let block = n * 12;
    let data_start = 8 + 4 * t;
    let expected = block.checked_mul(t).and_then(|x| x.checked_add(data_start));
    if expected != Some(bytes.len()) {
        let hint = if expected.and_then(|e| e.checked_add(block)) == Some(bytes.len()) {
            " (one block more: a file with a leading rest frame, as Blender's exporter writes)"
        } else {
            ""
        };
        return Err(bad(format!(
            "{} bytes, but {t} frames of {n} points need {}{hint}",
            bytes.len(),
            expected.map_or("more than fits in memory".into(), |e| e.to_string())
        )));
    }
    let times: Vec<f32> = bytes[8..data_start]
        .chunks_exact(4)
        .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let positions = read_f32_triples(&bytes[data_start..], Endian::Big);
    Ok(Mdd {
        frames: Frames::from_positions(n, positions)?,
        times,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_dir::TestDir;

    fn frames() -> Frames {
        Frames::from_frames(&[
            vec![[0., 0., 0.], [1., 0., 0.5], [2., 2., 2.]],
            vec![
                [0.25, -1., 1e-30],
                [f32::MAX, f32::MIN_POSITIVE, -0.0],
                [9., 8., 7.],
            ],
        ])
        .unwrap()
    }

    #[test]
    fn layout_is_big_endian_with_times() {
        let mut b = Vec::new();
        write_mdd_to(&mut b, &frames(), &[0.0, 0.5]).unwrap();
        assert_eq!(b.len(), 8 + 8 + 2 * 3 * 12);
        assert_eq!(b[0..4], 2i32.to_be_bytes());
        assert_eq!(b[4..8], 3i32.to_be_bytes());
        assert_eq!(b[12..16], 0.5f32.to_be_bytes());
        // Frame 1, point 0, y.
        assert_eq!(b[16 + 36 + 4..16 + 36 + 8], (-1f32).to_be_bytes());
        assert!(write_mdd_to(&mut Vec::new(), &frames(), &[0.0]).is_err());
    }

    #[test]
    fn round_trip_is_exact() {
        let dir = TestDir::new("mdd");
        let path = dir.0.join("a.mdd");
        write_mdd(&path, &frames(), 25.0).unwrap();
        let back = read_mdd(&path).unwrap();
        assert_eq!(back.frames, frames());
        assert_eq!(back.times, vec![0.0, 0.04]);
    }

    #[test]
    fn strict_reader_and_writer() {
        let p = Path::new("m.mdd");
        let mut good = Vec::new();
        write_mdd_to(&mut good, &frames(), &[0.0, 1.0]).unwrap();
        let err = |b: &[u8]| parse_mdd(b, p).unwrap_err().to_string();
        assert!(err(&good[..5]).contains("5 bytes"));
        assert!(err(&good[..good.len() - 4]).contains("2 frames of 3 points need 88"));
        let mut rest = good.clone();
        rest.extend_from_slice(&[0u8; 36]);
        assert!(err(&rest).contains("leading rest frame"));
        assert!(err(&[0xff; 16]).contains("expected positive counts"));

        let dir = TestDir::new("mdd-bad");
        for fps in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let e = write_mdd(&dir.0.join("a.mdd"), &frames(), fps).unwrap_err();
            assert!(matches!(e, ExportError::Fps { .. }), "{e}");
        }
        let mut f = frames();
        f.positions_mut_for_test()[2][2] = f32::NEG_INFINITY;
        let e = write_mdd(&dir.0.join("a.mdd"), &f, 30.0).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("frame 0, vertex 2: the z coordinate is -inf"));
        assert!(dir.entries().is_empty());
    }
}
