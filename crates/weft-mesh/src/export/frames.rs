//! A frame sequence: the positions of one mesh's vertices at every frame of an animation.
//!
//! Stored as one contiguous `(frames × vertices)` buffer of `[f32; 3]`, frame-major, so a
//! frame is a slice, the whole sequence is a `(T, N, 3)` array without copies
//! ([`Frames::as_flat`]) and every export format writes straight from it. `f32` because
//! every animation format stores `f32` and stored datasets are `f32` in weft; physics in
//! `f64` converts once, at [`Frames::push_frame_f64`].

use std::cmp::Ordering;
use std::fs;
use std::path::{Path, PathBuf};

use super::error::ExportError;
use super::npy::{self, NpyData, NpyError};
use crate::io::read_obj;

/// The positions of `vertex_count` vertices at each of `frame_count` frames, in metres.
///
/// Invariant: the buffer holds exactly `frame_count * vertex_count` positions and
/// `vertex_count > 0`. Positions are not checked for finiteness on construction (a
/// simulation may blow up); writers call [`Frames::check_finite`] and refuse NaN.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    vertex_count: usize,
    positions: Vec<[f32; 3]>,
}

impl Frames {
    /// An empty sequence of meshes with `vertex_count` vertices, to fill with
    /// [`push_frame`](Self::push_frame). Fails for `vertex_count == 0`.
    pub fn with_vertex_count(vertex_count: usize) -> Result<Self, ExportError> {
        if vertex_count == 0 {
            return Err(ExportError::NoVertices);
        }
        Ok(Frames {
            vertex_count,
            positions: Vec::new(),
        })
    }

    /// Frames from a frame-major buffer of `frame_count * vertex_count` positions.
    pub fn from_positions(
        vertex_count: usize,
        positions: Vec<[f32; 3]>,
    ) -> Result<Self, ExportError> {
        let mut f = Frames::with_vertex_count(vertex_count)?;
        if !positions.len().is_multiple_of(vertex_count) {
            return Err(ExportError::FrameLength {
                frame: positions.len() / vertex_count,
                found: positions.len() % vertex_count,
                expected: vertex_count,
            });
        }
        f.positions = positions;
        Ok(f)
    }

    /// Frames from one position list per frame; all must have the same, nonzero length.
    pub fn from_frames(frames: &[Vec<[f32; 3]>]) -> Result<Self, ExportError> {
        let first = frames.first().ok_or(ExportError::NoFrames)?;
        let mut f = Frames::with_vertex_count(first.len())?;
        f.positions.reserve(frames.len() * first.len());
        for frame in frames {
            f.push_frame(frame)?;
        }
        Ok(f)
    }

    /// Appends one frame; fails unless it has [`vertex_count`](Self::vertex_count)
    /// positions.
    pub fn push_frame(&mut self, positions: &[[f32; 3]]) -> Result<(), ExportError> {
        self.check_length(positions.len())?;
        self.positions.extend_from_slice(positions);
        Ok(())
    }

    /// Appends one frame of `f64` positions (the simulator's), rounded to `f32`.
    pub fn push_frame_f64(&mut self, positions: &[[f64; 3]]) -> Result<(), ExportError> {
        self.check_length(positions.len())?;
        self.positions
            .extend(positions.iter().map(|p| p.map(|c| c as f32)));
        Ok(())
    }

    fn check_length(&self, found: usize) -> Result<(), ExportError> {
        if found == self.vertex_count {
            Ok(())
        } else {
            Err(ExportError::FrameLength {
                frame: self.frame_count(),
                found,
                expected: self.vertex_count,
            })
        }
    }

    /// Vertices per frame.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.positions.len() / self.vertex_count
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The positions of frame `k`, or `None` past the end.
    pub fn frame(&self, k: usize) -> Option<&[[f32; 3]]> {
        let n = self.vertex_count;
        self.positions.get(k * n..(k + 1) * n)
    }

    /// The frames in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[[f32; 3]]> + '_ {
        self.positions.chunks_exact(self.vertex_count)
    }

    /// All positions, frame-major.
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// Mutable access for tests that plant bad values.
    #[cfg(test)]
    pub(crate) fn positions_mut_for_test(&mut self) -> &mut [[f32; 3]] {
        &mut self.positions
    }

    /// All coordinates as a flat `(T, N, 3)` C-order buffer.
    pub fn as_flat(&self) -> &[f32] {
        self.positions.as_flattened()
    }

    /// The first NaN or infinite coordinate, in frame, vertex, axis order.
    pub fn check_finite(&self) -> Result<(), ExportError> {
        let Some(i) = self
            .positions
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()))
        else {
            return Ok(());
        };
        let p = self.positions[i];
        let axis = (0..3).find(|&a| !p[a].is_finite()).unwrap_or(0);
        Err(ExportError::NonFinite {
            frame: i / self.vertex_count,
            vertex: i % self.vertex_count,
            axis: ['x', 'y', 'z'][axis],
            value: p[axis],
        })
    }

    /// Smallest and largest coordinate on each axis over all frames, `None` when empty.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        bounds(&self.positions)
    }

    /// Reads a frame sequence from a directory of OBJ files ([`read_obj_dir`](Self::read_obj_dir)),
    /// a `.npy` array ([`read_npy`](Self::read_npy)) or a PC2 or MDD point cache, by what
    /// `path` is.
    pub fn load(path: &Path) -> Result<Self, ExportError> {
        let meta = fs::metadata(path).map_err(|e| ExportError::read(path, e))?;
        if meta.is_dir() {
            return Frames::read_obj_dir(path);
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("npy") => Frames::read_npy(path),
            Some("pc2") => Ok(super::pc2::read_pc2(path)?.frames),
            Some("mdd") => Ok(super::mdd::read_mdd(path)?.frames),
            _ => Err(ExportError::format(
                path,
                "expected a directory of .obj frames, a .npy array of shape (frames, vertices, 3), or a .pc2 or .mdd point cache",
            )),
        }
    }

    /// Reads a `.npy` array of shape `(frames, vertices, 3)`, `<f4` or `<f8`, C order.
    /// `f64` values are rounded to `f32`; a finite value beyond `f32`'s range fails.
    pub fn read_npy(path: &Path) -> Result<Self, ExportError> {
        let a = npy::read_npy(path)?;
        let shape_error = || {
            ExportError::format(
                path,
                format!(
                    "array of shape {} and dtype '{}'; expected shape (frames, vertices, 3) with frames, vertices ≥ 1, dtype '<f4' or '<f8'",
                    npy::ShapeDisplay(&a.shape),
                    a.data.descr()
                ),
            )
        };
        let &[t, n, 3] = a.shape.as_slice() else {
            return Err(shape_error());
        };
        if t == 0 || n == 0 {
            return Err(shape_error());
        }
        let flat: Vec<f32> = match &a.data {
            NpyData::F32(v) => v.clone(),
            NpyData::F64(v) => {
                let mut out = Vec::with_capacity(v.len());
                for (i, &x) in v.iter().enumerate() {
                    out.push(f64_to_f32(x).ok_or_else(|| {
                        ExportError::format(
                            path,
                            format!(
                                "frame {}, vertex {}: {x:e} does not fit in a 32-bit float; expected positions in metres",
                                i / (3 * n),
                                (i / 3) % n
                            ),
                        )
                    })?);
                }
                out
            }
            _ => return Err(shape_error()),
        };
        let positions = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Frames::from_positions(n, positions)
    }

    /// Writes the frames as a `(frames, vertices, 3)` `<f4` `.npy` array, atomically.
    pub fn write_npy(&self, path: &Path) -> Result<(), NpyError> {
        npy::write_npy(
            path,
            &[self.frame_count(), self.vertex_count, 3],
            self.as_flat(),
        )
    }

    /// Reads every `.obj` file of `dir` (any case) as one frame, in name order with digit
    /// runs compared as numbers (`frame_2` before `frame_10`; zero-padded names sort the
    /// same either way). Every file must have the first file's vertex count.
    ///
    /// Each file goes through the strict OBJ reader, so a NaN coordinate fails with its
    /// file and line. Faces are read but not kept: the template supplies them.
    pub fn read_obj_dir(dir: &Path) -> Result<Self, ExportError> {
        let files = obj_files(dir)?;
        let Some(first) = files.first() else {
            return Err(ExportError::format(
                dir,
                "no .obj files in the directory; expected one OBJ per frame (frame_00000.obj, frame_00001.obj, …)",
            ));
        };
        let mut frames: Option<Frames> = None;
        for path in &files {
            let mesh = read_obj(path)?;
            let f = match &mut frames {
                Some(f) => f,
                None => frames.insert(Frames::with_vertex_count(mesh.vertex_count())?),
            };
            if mesh.vertex_count() != f.vertex_count {
                return Err(ExportError::FrameFileVertexCount {
                    path: path.clone(),
                    found: mesh.vertex_count(),
                    first: first.clone(),
                    expected: f.vertex_count,
                });
            }
            f.positions.reserve(f.vertex_count);
            for (v, p) in mesh.positions.iter().enumerate() {
                let mut q = [0f32; 3];
                for k in 0..3 {
                    q[k] = f64_to_f32(p[k]).ok_or_else(|| {
                        ExportError::format(
                            path,
                            format!(
                                "vertex {v}: {:e} does not fit in a 32-bit float; expected positions in metres",
                                p[k]
                            ),
                        )
                    })?;
                }
                f.positions.push(q);
            }
        }
        frames.ok_or(ExportError::NoFrames)
    }
}

/// `x` as `f32`, `None` when a finite `x` overflows (NaN and ±inf pass through, for
/// [`Frames::check_finite`] to report with their frame and vertex).
fn f64_to_f32(x: f64) -> Option<f32> {
    let y = x as f32;
    (y.is_finite() || !x.is_finite()).then_some(y)
}

/// Componentwise min and max of `points`.
pub(crate) fn bounds(points: &[[f32; 3]]) -> Option<([f32; 3], [f32; 3])> {
    let first = *points.first()?;
    let (mut lo, mut hi) = (first, first);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    Some((lo, hi))
}

/// The `.obj` files of `dir`, sorted by [`natural_cmp`] of their names.
fn obj_files(dir: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir).map_err(|e| ExportError::read(dir, e))? {
        let entry = entry.map_err(|e| ExportError::read(dir, e))?;
        let path = entry.path();
        let is_obj = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if is_obj && path.is_file() {
            files.push(path);
        }
    }
    files.sort_by(|a, b| {
        let name = |p: &PathBuf| {
            p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        natural_cmp(&name(a), &name(b))
    });
    Ok(files)
}

/// Compares names with runs of ASCII digits compared as numbers (`a2` < `a10`), ties
/// (`a01` vs `a1`) broken by plain byte order so the order is total.
pub(crate) fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (x, y) = (a.as_bytes(), b.as_bytes());
    let (mut i, mut j) = (0, 0);
    while i < x.len() && j < y.len() {
        if x[i].is_ascii_digit() && y[j].is_ascii_digit() {
            let si = i;
            while i < x.len() && x[i].is_ascii_digit() {
                i += 1;
            }
            let sj = j;
            while j < y.len() && y[j].is_ascii_digit() {
                j += 1;
            }
            // Compare the digit runs as numbers without parsing: strip leading zeros,
            // then a longer run is larger, then compare digit by digit.
            let trim = |s: &[u8]| {
                let z = s.iter().take_while(|&&c| c == b'0').count();
                s[z..].to_vec()
            };
            let (p, q) = (trim(&x[si..i]), trim(&y[sj..j]));
            let ord = p.len().cmp(&q.len()).then_with(|| p.cmp(&q));
            if ord != Ordering::Equal {
                return ord;
            }
        } else {
            if x[i] != y[j] {
                return x[i].cmp(&y[j]);
            }
            i += 1;
            j += 1;
        }
    }
    (x.len() - i).cmp(&(y.len() - j)).then_with(|| a.cmp(b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_dir::TestDir;

    fn two_frames() -> Frames {
        Frames::from_frames(&[
            vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]],
            vec![[0., 0., 1.], [1., 0., 1.], [0., 1., 1.]],
        ])
        .unwrap()
    }

    #[test]
    fn shapes_and_access() {
        let f = two_frames();
        assert_eq!((f.frame_count(), f.vertex_count()), (2, 3));
        assert_eq!(f.frame(1).unwrap()[2], [0., 1., 1.]);
        assert!(f.frame(2).is_none());
        assert_eq!(f.as_flat().len(), 18);
        assert_eq!(f.iter().len(), 2);
        assert_eq!(f.bounds(), Some(([0., 0., 0.], [1., 1., 1.])));
        let mut g = Frames::with_vertex_count(3).unwrap();
        assert!(g.is_empty());
        g.push_frame_f64(&[[0.; 3]; 3]).unwrap();
        let e = g.push_frame(&[[0.; 3]; 2]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "frame 1 has 2 positions; expected 3 like the frames before it"
        );
        assert!(Frames::from_positions(2, vec![[0.; 3]; 3]).is_err());
        assert!(Frames::with_vertex_count(0).is_err());
        assert!(matches!(
            Frames::from_frames(&[]),
            Err(ExportError::NoFrames)
        ));
    }

    #[test]
    fn non_finite_coordinates_are_reported_with_frame_and_vertex() {
        let mut f = two_frames();
        f.positions[4][2] = f32::NAN;
        f.positions[5][0] = f32::INFINITY;
        assert_eq!(
            f.check_finite().unwrap_err().to_string(),
            "frame 1, vertex 1: the z coordinate is NaN; expected finite positions (the frames are not exported)"
        );
    }

    #[test]
    fn natural_order() {
        let mut v = vec!["f10.obj", "f2.obj", "f1.obj", "f01.obj", "a.obj", "f.obj"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            v,
            ["a.obj", "f.obj", "f01.obj", "f1.obj", "f2.obj", "f10.obj"]
        );
        assert_eq!(natural_cmp("frame_00009", "frame_00010"), Ordering::Less);
        assert_eq!(natural_cmp("x", "x"), Ordering::Equal);
    }

    #[test]
    fn npy_round_trip_and_f64_input() {
        let dir = TestDir::new("frames-npy");
        let f = two_frames();
        let path = dir.0.join("f.npy");
        f.write_npy(&path).unwrap();
        assert_eq!(Frames::load(&path).unwrap(), f);

        let p64 = dir.0.join("d.npy");
        let v: Vec<f64> = f.as_flat().iter().map(|&x| f64::from(x)).collect();
        npy::write_npy(&p64, &[2, 3, 3], &v).unwrap();
        assert_eq!(Frames::read_npy(&p64).unwrap(), f);

        npy::write_npy(&p64, &[1, 1, 3], &[0.0, 1e300, 0.0]).unwrap();
        let e = Frames::read_npy(&p64).unwrap_err().to_string();
        assert!(e.ends_with("frame 0, vertex 0: 1e300 does not fit in a 32-bit float; expected positions in metres"), "{e}");

        for (shape, n) in [(&[2usize, 3][..], 6), (&[2, 3, 2], 12), (&[0, 3, 3], 0)] {
            npy::write_npy(&p64, shape, &vec![0.0f64; n]).unwrap();
            let e = Frames::read_npy(&p64).unwrap_err().to_string();
            assert!(e.contains("expected shape (frames, vertices, 3)"), "{e}");
        }
        npy::write_npy(&p64, &[1, 1, 3], &[1i32, 2, 3]).unwrap();
        assert!(Frames::read_npy(&p64)
            .unwrap_err()
            .to_string()
            .contains("dtype '<i4'"));
    }

    #[test]
    fn obj_directories_are_read_in_natural_order() {
        let dir = TestDir::new("frames-obj");
        let tri = |z: f32| format!("v 0 0 {z}\nv 1 0 {z}\nv 0 1 {z}\nf 1 2 3\n");
        for (name, z) in [("f10.obj", 10.0), ("f2.obj", 2.0), ("f1.OBJ", 1.0)] {
            fs::write(dir.0.join(name), tri(z)).unwrap();
        }
        fs::write(dir.0.join("notes.txt"), "not a frame").unwrap();
        let f = Frames::load(&dir.0).unwrap();
        let z: Vec<f32> = f.iter().map(|fr| fr[0][2]).collect();
        assert_eq!(z, [1.0, 2.0, 10.0]);

        fs::write(
            dir.0.join("f3.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n",
        )
        .unwrap();
        let e = Frames::load(&dir.0).unwrap_err().to_string();
        assert!(
            e.contains("f3.obj: 4 vertices, but ") && e.contains("f1.OBJ has 3"),
            "{e}"
        );

        fs::write(
            dir.0.join("f3.obj"),
            "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        let e = Frames::load(&dir.0).unwrap_err().to_string();
        assert!(
            e.contains("f3.obj:1: coordinate `nan` is not finite"),
            "{e}"
        );

        let empty = TestDir::new("frames-empty");
        assert!(Frames::load(&empty.0)
            .unwrap_err()
            .to_string()
            .contains("no .obj files"));
        let e = Frames::load(&empty.0.join("x.csv")).unwrap_err();
        assert!(matches!(e, ExportError::Read { .. }), "{e}");
        fs::write(empty.0.join("x.csv"), "1,2,3").unwrap();
        let e = Frames::load(&empty.0.join("x.csv"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("expected a directory of .obj frames, a .npy array"),
            "{e}"
        );

        // Point caches read back as the frames written.
        let f =
            Frames::from_frames(&[vec![[1.0, 2.0, 3.0]; 4], vec![[0.5, 0.0, -1.0]; 4]]).unwrap();
        super::super::pc2::write_pc2(&empty.0.join("a.PC2"), &f, Default::default()).unwrap();
        super::super::mdd::write_mdd(&empty.0.join("a.mdd"), &f, 24.0).unwrap();
        assert_eq!(Frames::load(&empty.0.join("a.PC2")).unwrap(), f);
        assert_eq!(Frames::load(&empty.0.join("a.mdd")).unwrap(), f);
    }
}
