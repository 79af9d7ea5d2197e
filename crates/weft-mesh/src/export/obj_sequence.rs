//! OBJ sequences: one Wavefront OBJ per frame, `frame_00000.obj`, `frame_00001.obj`, …,
//! each with the template's faces and the vertices in the template's order, and the
//! template's texture coordinates (`vt`, `f v/vt`) when it has them.
//!
//! The most portable animation there is: every tool reads OBJ, and per-vertex data
//! (errors, attributions) stays aligned because vertex order is kept. Coordinates are
//! written with the shortest decimal that reads back to the same `f32`, so a sequence
//! round-trips bit for bit.
//!
//! The sequence is written as a whole or not at all: frames go to a temporary directory
//! beside the destination, which is renamed into place when every file is complete and
//! synced. An existing destination is replaced only when it is empty or holds nothing but
//! `frame_*.obj` files (a previous export); anything else is refused, so a typo in
//! `--out` cannot delete a user's files.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::error::ExportError;
use super::scene::{check_uvs, CornerUvs, IndexedUvs};
use super::Frames;

/// Distinguishes temporary directories of concurrent exports from one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The file name of frame `k`: `frame_00000.obj` (at least five digits, more when needed,
/// so names sort in frame order up to 100 000 frames and naturally beyond).
pub fn frame_file_name(k: usize) -> String {
    format!("frame_{k:05}.obj")
}

/// Writes `frames` into the directory `dir` as one OBJ per frame with `faces` (0-based
/// indices into each frame's vertices), replacing a previous sequence there.
///
/// Fails without touching `dir` when there are no frames, a coordinate is NaN or
/// infinite, a face names a missing vertex, `dir` is a file, or `dir` holds anything but
/// `frame_*.obj` files.
pub fn write_obj_sequence(
    dir: &Path,
    faces: &[[u32; 3]],
    uvs: Option<&CornerUvs>,
    frames: &Frames,
) -> Result<(), ExportError> {
    if frames.is_empty() {
        return Err(ExportError::NoFrames);
    }
    frames.check_finite()?;
    check_faces(faces, frames.vertex_count())?;
    if let Some(uvs) = uvs {
        check_uvs(faces, uvs)?;
    }
    let existing = inspect_destination(dir)?;

    let parent = parent_of(dir);
    let name = dir
        .file_name()
        .ok_or_else(|| {
            ExportError::write(
                dir,
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    "the output path names no directory (expected a path like out/frames)",
                ),
            )
        })?
        .to_string_lossy()
        .into_owned();
    fs::create_dir_all(&parent).map_err(|e| ExportError::write(dir, e))?;
    let temp = TempDir::create(&parent, &name).map_err(|e| ExportError::write(dir, e))?;

    let trailer = Trailer::new(faces, uvs);
    write_frames_parallel(&temp.0, frames, &trailer).map_err(|e| ExportError::write(dir, e))?;
    sync_dir(&temp.0);
    temp.commit(dir, existing)
        .map_err(|e| ExportError::write(dir, e))?;
    sync_dir(&parent);
    Ok(())
}

/// Removes the OBJ sequence a previous export left in `dir`, so that a new run that
/// writes none leaves no stale frames beside its outputs. Returns whether there was one.
/// A directory holding anything but `frame_*.obj` files is not touched (an error, as
/// for [`write_obj_sequence`]).
pub fn remove_obj_sequence(dir: &Path) -> Result<bool, ExportError> {
    if let Existing::Nothing = inspect_destination(dir)? {
        return Ok(false);
    }
    fs::remove_dir_all(dir).map_err(|e| ExportError::write(dir, e))?;
    Ok(true)
}

/// How many frame files are formatted, written and synced at once.
///
/// Why threads for file output: each file must be synced before the directory is renamed
/// into place, and a sync waits for a journal commit (about 7 ms on the benchmark
/// machine), which dominated the export: 1 000 frames over an earlier sequence took
/// 7.8 s one file after another and about 4 s from 16 threads on a 2-core machine.
/// Concurrent syncs share commits, and formatting runs on every core meanwhile.
const WRITER_THREADS: usize = 16;

/// Writes every frame file into `dir` from up to [`WRITER_THREADS`] threads, each taking
/// the next unwritten frame. The first error stops the others and is returned.
fn write_frames_parallel(dir: &Path, frames: &Frames, trailer: &Trailer) -> io::Result<()> {
    use std::sync::atomic::{AtomicBool, AtomicUsize};
    use std::sync::Mutex;

    let total = frames.frame_count();
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let first_error: Mutex<Option<io::Error>> = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..WRITER_THREADS.min(total) {
            scope.spawn(|| {
                let mut line = String::with_capacity(64 * frames.vertex_count());
                while !failed.load(Ordering::Relaxed) {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(positions) = frames.frame(k) else {
                        break;
                    };
                    let path = dir.join(frame_file_name(k));
                    let written = File::create(&path).and_then(|file| {
                        let mut w = BufWriter::with_capacity(1 << 16, file);
                        write_frame_to(&mut w, positions, trailer, k, total, &mut line)?;
                        let file = w.into_inner().map_err(io::IntoInnerError::into_error)?;
                        file.sync_all()
                    });
                    if let Err(e) = written {
                        failed.store(true, Ordering::Relaxed);
                        let mut slot = first_error.lock().unwrap_or_else(|p| p.into_inner());
                        slot.get_or_insert(e);
                        break;
                    }
                }
            });
        }
    });
    match first_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Writes one OBJ at `path` (atomically): `positions` with `faces` and, when given, the
/// corner `uvs` — a garment template as the OBJ sequence writes each frame.
pub fn write_obj_with_uvs(
    path: &Path,
    positions: &[[f32; 3]],
    faces: &[[u32; 3]],
    uvs: Option<&CornerUvs>,
) -> Result<(), ExportError> {
    let frames = Frames::from_frames(&[positions.to_vec()])?;
    frames.check_finite()?;
    check_faces(faces, positions.len())?;
    if let Some(uvs) = uvs {
        check_uvs(faces, uvs)?;
    }
    let trailer = Trailer::new(faces, uvs);
    let mut line = String::new();
    crate::io::write_atomic(path, |w| {
        write_frame_to(w, positions, &trailer, 0, 1, &mut line)
    })
    .map_err(|e| ExportError::write(path, e))
}

/// Reads a sequence back: every `.obj` in `dir`, in natural name order (see
/// [`Frames::read_obj_dir`]).
pub fn read_obj_sequence(dir: &Path) -> Result<Frames, ExportError> {
    Frames::read_obj_dir(dir)
}

/// Writes one frame: a comment, `v x y z` per vertex, then the prepared `vt` and face
/// lines. `line` is a scratch buffer reused across frames.
fn write_frame_to(
    w: &mut dyn Write,
    positions: &[[f32; 3]],
    trailer: &Trailer,
    k: usize,
    total: usize,
    line: &mut String,
) -> io::Result<()> {
    line.clear();
    use std::fmt::Write as _;
    let _ = writeln!(
        line,
        "# weft frame {k} of {total}: {} vertices, {} triangles",
        positions.len(),
        trailer.triangles
    );
    for p in positions {
        line.push('v');
        for &c in p {
            line.push(' ');
            fmt_f32(line, c);
        }
        line.push('\n');
    }
    w.write_all(line.as_bytes())?;
    w.write_all(&trailer.text)?;
    w.flush()
}

/// What follows the vertices in every frame file, built once for all frames: the
/// distinct UVs as `vt u v` and the faces as `f a b c` or `f a/ta b/tb c/tc` (1-based).
struct Trailer {
    text: Vec<u8>,
    triangles: usize,
}

impl Trailer {
    fn new(faces: &[[u32; 3]], uvs: Option<&CornerUvs>) -> Self {
        use std::fmt::Write as _;
        let mut s = String::with_capacity(faces.len() * 40);
        let indexed = uvs.map(IndexedUvs::new);
        if let Some(indexed) = &indexed {
            for uv in &indexed.values {
                s.push_str("vt ");
                fmt_f32(&mut s, uv[0]);
                s.push(' ');
                fmt_f32(&mut s, uv[1]);
                s.push('\n');
            }
        }
        for (i, f) in faces.iter().enumerate() {
            s.push('f');
            for (k, &v) in f.iter().enumerate() {
                let _ = write!(s, " {}", u64::from(v) + 1);
                if let Some(indexed) = &indexed {
                    let _ = write!(s, "/{}", u64::from(indexed.corners[i][k]) + 1);
                }
            }
            s.push('\n');
        }
        Trailer {
            text: s.into_bytes(),
            triangles: faces.len(),
        }
    }
}

/// The shortest decimal that parses back to the same `f32`; exponent form only for very
/// small or large magnitudes.
pub(crate) fn fmt_f32(out: &mut String, x: f32) {
    use std::fmt::Write as _;
    let a = x.abs();
    let _ = if a != 0.0 && !(1e-5..1e16).contains(&a) {
        write!(out, "{x:e}")
    } else {
        write!(out, "{x}")
    };
}

/// Fails on the first face naming a vertex at or beyond `vertices`.
pub(crate) fn check_faces(faces: &[[u32; 3]], vertices: usize) -> Result<(), ExportError> {
    for (face, f) in faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&i| i as usize >= vertices) {
            return Err(ExportError::FaceIndex {
                face,
                vertex,
                vertices,
            });
        }
    }
    Ok(())
}

/// What is at the destination now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Existing {
    /// Nothing.
    Nothing,
    /// An empty directory.
    Empty,
    /// A directory holding only `frame_*.obj` files.
    Sequence,
}

fn inspect_destination(dir: &Path) -> Result<Existing, ExportError> {
    let meta = match fs::symlink_metadata(dir) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Existing::Nothing),
        Err(e) => return Err(ExportError::write(dir, e)),
    };
    if !meta.is_dir() {
        return Err(ExportError::OutputDirectory {
            path: dir.to_path_buf(),
            message: "exists and is not a directory; an OBJ sequence is written as a directory of frame_NNNNN.obj files".into(),
        });
    }
    let mut any = false;
    for entry in fs::read_dir(dir).map_err(|e| ExportError::write(dir, e))? {
        let entry = entry.map_err(|e| ExportError::write(dir, e))?;
        any = true;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_frame = is_frame_name(&name) && entry.file_type().is_ok_and(|t| t.is_file());
        if !is_frame {
            return Err(ExportError::OutputDirectory {
                path: dir.to_path_buf(),
                message: format!(
                    "holds `{name}`, which is not a frame of a previous export; choose a new or empty directory (weft replaces only directories of frame_NNNNN.obj files)"
                ),
            });
        }
    }
    Ok(if any {
        Existing::Sequence
    } else {
        Existing::Empty
    })
}

/// `frame_` + digits + `.obj`.
fn is_frame_name(name: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|r| r.strip_suffix(".obj"))
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Best-effort directory sync, so renames and new entries survive a crash.
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

/// A temporary directory beside the destination, removed with its content on drop
/// unless committed.
struct TempDir(PathBuf);

impl TempDir {
    fn create(parent: &Path, name: &str) -> io::Result<TempDir> {
        let mut last = None;
        for _ in 0..64 {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let path = parent.join(format!(".{name}.{}.{n}.tmp", std::process::id()));
            match fs::create_dir(&path) {
                Ok(()) => return Ok(TempDir(path)),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last = Some(e),
                Err(e) => return Err(e),
            }
        }
        Err(last.unwrap_or_else(|| io::Error::other("could not create a temporary directory")))
    }

    /// Moves the finished sequence to `dest`, replacing what [`inspect_destination`]
    /// found there. A previous sequence is moved aside first and put back if the final
    /// rename fails.
    fn commit(self, dest: &Path, existing: Existing) -> io::Result<()> {
        match existing {
            Existing::Nothing => fs::rename(&self.0, dest)?,
            Existing::Empty => {
                fs::remove_dir(dest)?;
                fs::rename(&self.0, dest)?;
            }
            Existing::Sequence => {
                let n = COUNTER.fetch_add(1, Ordering::Relaxed);
                let name = dest
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let old = parent_of(dest).join(format!(".{name}.{}.{n}.old", std::process::id()));
                fs::rename(dest, &old)?;
                if let Err(e) = fs::rename(&self.0, dest) {
                    let _ = fs::rename(&old, dest);
                    return Err(e);
                }
                let _ = fs::remove_dir_all(&old);
            }
        }
        // Committed: nothing left to clean up.
        std::mem::forget(self);
        Ok(())
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_dir::TestDir;

    fn frames() -> Frames {
        Frames::from_frames(&[
            vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0.1, 1e-7, -3e20]],
            vec![
                [0., 0., 1.],
                [1., 0., 1.],
                [0., 1., 1.],
                [1.0 / 3.0, 2.5, 7.0],
            ],
        ])
        .unwrap()
    }

    const FACES: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

    #[test]
    fn names_sort_in_frame_order() {
        assert_eq!(frame_file_name(0), "frame_00000.obj");
        assert_eq!(frame_file_name(123456), "frame_123456.obj");
        assert!(is_frame_name("frame_00012.obj"));
        assert!(!is_frame_name("frame_.obj") && !is_frame_name("frame_1.obj.tmp"));
    }

    #[test]
    fn round_trip_is_exact_and_keeps_faces() {
        let dir = TestDir::new("objseq");
        let out = dir.0.join("seq");
        let f = frames();
        write_obj_sequence(&out, &FACES, None, &f).unwrap();
        assert_eq!(read_obj_sequence(&out).unwrap(), f);
        let m = crate::io::read_obj(&out.join("frame_00001.obj")).unwrap();
        assert_eq!(m.faces, FACES.to_vec());
        // Only the sequence, no temporary directory.
        assert_eq!(dir.entries(), vec!["seq"]);

        // A previous sequence is replaced, fewer frames leave no stale files.
        let one = Frames::from_frames(&[f.frame(1).unwrap().to_vec()]).unwrap();
        write_obj_sequence(&out, &FACES, None, &one).unwrap();
        assert_eq!(read_obj_sequence(&out).unwrap(), one);
        assert_eq!(dir.entries(), vec!["seq"]);
    }

    #[test]
    fn template_uvs_are_written_with_every_frame() {
        let dir = TestDir::new("objseq-uv");
        let out = dir.0.join("seq");
        // A seam: vertex 0 and 2 have another UV in the second triangle.
        let uvs = [
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            [[0.5, 0.0], [0.25, 1.0], [0.0, 1.0]],
        ];
        write_obj_sequence(&out, &FACES, Some(&uvs), &frames()).unwrap();
        assert_eq!(read_obj_sequence(&out).unwrap(), frames());
        for k in 0..2 {
            let r = crate::io::load_obj(&out.join(frame_file_name(k))).unwrap();
            assert_eq!(r.mesh.faces, FACES.to_vec());
            assert_eq!(r.corner_uvs.unwrap(), uvs.to_vec());
        }
        let text = fs::read_to_string(out.join("frame_00000.obj")).unwrap();
        assert!(
            text.contains("vt 0.25 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/4 3/5 4/6\n"),
            "{text}"
        );
        let e = write_obj_sequence(&out, &FACES, Some(&uvs[..1]), &frames()).unwrap_err();
        assert!(matches!(e, ExportError::UvCount { uvs: 1, faces: 2 }));
    }

    #[test]
    fn one_obj_with_uvs_reads_back() {
        let dir = TestDir::new("obj-uv");
        let uvs = [
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        ];
        let f = frames();
        let path = dir.0.join("g.obj");
        write_obj_with_uvs(&path, f.frame(1).unwrap(), &FACES, Some(&uvs)).unwrap();
        let r = crate::io::load_obj(&path).unwrap();
        assert_eq!(r.corner_uvs.unwrap(), uvs.to_vec());
        assert_eq!(r.mesh.faces, FACES.to_vec());
        assert_eq!(
            r.mesh.positions[3].map(|c| c as f32),
            f.frame(1).unwrap()[3]
        );
        assert!(write_obj_with_uvs(&path, f.frame(1).unwrap(), &[[0, 1, 9]], None).is_err());
    }

    /// Issue 17 item 12: missing parents are created; a stale sequence is removed only
    /// when it holds nothing but frames.
    #[test]
    fn parents_are_created_and_stale_sequences_removed() {
        let dir = TestDir::new("objseq-parents");
        let out = dir.0.join("a/b/seq");
        write_obj_sequence(&out, &FACES, None, &frames()).unwrap();
        assert_eq!(read_obj_sequence(&out).unwrap(), frames());
        assert!(remove_obj_sequence(&out).unwrap());
        assert!(!out.exists());
        assert!(!remove_obj_sequence(&out).unwrap());
        fs::create_dir(&out).unwrap();
        fs::write(out.join("notes.txt"), "mine").unwrap();
        assert!(remove_obj_sequence(&out).is_err());
        assert_eq!(fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");
    }

    #[test]
    fn refuses_to_replace_other_files_and_bad_input() {
        let dir = TestDir::new("objseq-refuse");
        let out = dir.0.join("seq");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("notes.txt"), "mine").unwrap();
        let e = write_obj_sequence(&out, &FACES, None, &frames())
            .unwrap_err()
            .to_string();
        assert!(e.contains("holds `notes.txt`"), "{e}");
        assert_eq!(fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");

        let file = dir.0.join("file");
        fs::write(&file, "x").unwrap();
        let e = write_obj_sequence(&file, &FACES, None, &frames())
            .unwrap_err()
            .to_string();
        assert!(e.contains("is not a directory"), "{e}");

        let e = write_obj_sequence(&dir.0.join("new"), &[[0, 1, 4]], None, &frames()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "face 0 names vertex 4, but the frames have 4 vertices"
        );

        let mut nan = frames();
        nan.positions_mut_for_test()[5][1] = f32::NAN;
        let e = write_obj_sequence(&dir.0.join("new"), &FACES, None, &nan).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("frame 1, vertex 1: the y coordinate is NaN"),
            "{e}"
        );

        let e = write_obj_sequence(&dir.0.join("file/seq"), &FACES, None, &frames()).unwrap_err();
        assert!(matches!(e, ExportError::Write { .. }), "{e}");
        assert_eq!(dir.entries(), vec!["file", "seq"]);
    }

    #[test]
    fn an_empty_directory_is_filled() {
        let dir = TestDir::new("objseq-empty");
        write_obj_sequence(&dir.0, &FACES, None, &frames()).unwrap();
        assert_eq!(dir.entries(), vec!["frame_00000.obj", "frame_00001.obj"]);
    }
}
