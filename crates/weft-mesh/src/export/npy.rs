//! NumPy `.npy` arrays: a small, strict reader and an atomic writer.
//!
//! Frame sequences travel between weft and Python (simulations, training data, a user's
//! own predictions) as `.npy` arrays of shape `(frames, vertices, 3)`. The format is a
//! magic string, a version, a Python dict literal describing the array, and the raw
//! little-endian data in C order:
//!
//! ```text
//! \x93NUMPY  major minor  header_len (u16 LE for 1.0, u32 LE for 2.0 / 3.0)
//! {'descr': '<f4', 'fortran_order': False, 'shape': (2, 4000, 3), }   (space padded, '\n')
//! data
//! ```
//!
//! Why our own reader rather than a crate: the subset we need is tiny, and strictness is
//! the point. Everything outside it fails with an error that names the file and says what
//! was expected, instead of reading garbage: big-endian data, Fortran order, object
//! arrays, unknown dtypes, extra header keys, and a data section whose size does not match
//! the shape (a truncated download fails here, not as a wrong animation later).
//!
//! Supported element types: `<f4`, `<f8`, `<i4`, `<i8`, `<u4`, `|u1` (see [`NpyData`]).
//! The format itself (header, dtypes, memory bounds) lives in [`crate::io::npy`], shared
//! with the `.npz` reader.

use std::fs::File;
use std::io::{self, BufReader, Write};
use std::path::{Path, PathBuf};

pub(crate) use crate::io::npy::ShapeDisplay;
pub use crate::io::npy::{npy_header, Element};

use crate::io::npy::{self, Dtype, Header, ReadError};
use crate::io::write_atomic;

/// What went wrong reading or writing a `.npy` file.
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    /// The file could not be opened or read.
    #[error("cannot read {}: {error}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's error. Part of the message, not a `source()`, so a
        /// report that prints the cause chain does not repeat it.
        error: io::Error,
    },
    /// The file could not be written (nothing is left behind).
    #[error("cannot write {}: {error}", .path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's error. Part of the message, not a `source()`, so a
        /// report that prints the cause chain does not repeat it.
        error: io::Error,
    },
    /// The file is not a `.npy` array weft reads.
    #[error("{}: {message}", .path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What was found and what was expected.
        message: String,
    },
    /// An array to write whose element count does not match its shape.
    #[error("{}: shape {} holds {expected} elements but {found} were given", .path.display(), ShapeDisplay(.shape))]
    ShapeMismatch {
        /// The file that was to be written.
        path: PathBuf,
        /// The shape given.
        shape: Vec<usize>,
        /// Product of the shape.
        expected: usize,
        /// Number of elements given.
        found: usize,
    },
}

/// The elements of an array, by type.
#[derive(Clone, Debug, PartialEq)]
pub enum NpyData {
    /// `<f4`
    F32(Vec<f32>),
    /// `<f8`
    F64(Vec<f64>),
    /// `<i4`
    I32(Vec<i32>),
    /// `<i8`
    I64(Vec<i64>),
    /// `<u4`
    U32(Vec<u32>),
    /// `|u1`
    U8(Vec<u8>),
}

impl NpyData {
    /// The NumPy `descr` of the element type.
    pub fn descr(&self) -> &'static str {
        match self {
            NpyData::F32(_) => f32::DESCR,
            NpyData::F64(_) => f64::DESCR,
            NpyData::I32(_) => i32::DESCR,
            NpyData::I64(_) => i64::DESCR,
            NpyData::U32(_) => u32::DESCR,
            NpyData::U8(_) => u8::DESCR,
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        match self {
            NpyData::F32(v) => v.len(),
            NpyData::F64(v) => v.len(),
            NpyData::I32(v) => v.len(),
            NpyData::I64(v) => v.len(),
            NpyData::U32(v) => v.len(),
            NpyData::U8(v) => v.len(),
        }
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// An array read from a `.npy` file: its shape and its elements in C order.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// Extent of each axis; empty for a 0-dimensional array (one element).
    pub shape: Vec<usize>,
    /// The elements, `shape.iter().product()` of them.
    pub data: NpyData,
}

/// Reads a `.npy` file; see [`parse_npy`]. Memory is bounded by the file: a header
/// whose shape needs more bytes than the file holds is refused before anything is
/// allocated for it, and a stream (a pipe, a device) is read no further than the shape.
pub fn read_npy(path: &Path) -> Result<NpyArray, NpyError> {
    let read_err = |error| NpyError::Read {
        path: path.to_path_buf(),
        error,
    };
    let file = File::open(path).map_err(read_err)?;
    let meta = file.metadata().map_err(read_err)?;
    let len = meta.is_file().then_some(meta.len());
    let mut r = BufReader::new(file);
    let checked = |e: ReadError| match e {
        ReadError::Io(error) => read_err(error),
        ReadError::Invalid(message) => invalid(path, message),
    };
    let header = npy::read_header(&mut r, len).map_err(checked)?;
    let dtype = supported(&header).map_err(|m| invalid(path, m))?;
    let data = npy::read_data(&mut r, &header, len.is_some()).map_err(checked)?;
    Ok(NpyArray {
        data: decode(dtype, &data),
        shape: header.shape,
    })
}

/// Parses a `.npy` file held in memory; `path` only names the file in errors.
///
/// Accepts format versions 1.0, 2.0 and 3.0, C order, the element types of [`NpyData`],
/// and exactly the keys `descr`, `fortran_order` and `shape`. The data section must hold
/// exactly the bytes the shape needs.
pub fn parse_npy(bytes: &[u8], path: &Path) -> Result<NpyArray, NpyError> {
    let mut r = bytes;
    let header = npy::read_header(&mut r, Some(bytes.len() as u64)).map_err(|e| match e {
        ReadError::Invalid(message) => invalid(path, message),
        // Reading a slice fails only by ending, which `read_header` reports as invalid.
        ReadError::Io(error) => NpyError::Read {
            path: path.to_path_buf(),
            error,
        },
    })?;
    let dtype = supported(&header).map_err(|m| invalid(path, m))?;
    // `read_header` checked that exactly the data section is left.
    Ok(NpyArray {
        data: decode(dtype, r),
        shape: header.shape,
    })
}

fn invalid(path: &Path, message: String) -> NpyError {
    NpyError::Invalid {
        path: path.to_path_buf(),
        message,
    }
}

/// The header's dtype if [`NpyData`] holds it and the order is C; the refusal otherwise.
fn supported(header: &Header) -> Result<Dtype, String> {
    if header.fortran_order {
        return Err(
            "fortran_order is True; expected a C-order array (in NumPy: np.ascontiguousarray(a))"
                .into(),
        );
    }
    match header.dtype {
        d @ (Dtype::F4 | Dtype::F8 | Dtype::I4 | Dtype::I8 | Dtype::U4 | Dtype::U1) => Ok(d),
        _ => Err(format!(
            "dtype '{}' is not supported; expected one of '<f4', '<f8', '<i4', '<i8', '<u4', '|u1'",
            header.descr
        )),
    }
}

/// The elements of `data` (exactly a whole number of them), as the variant of `dtype`.
fn decode(dtype: Dtype, data: &[u8]) -> NpyData {
    fn each<T, const N: usize>(data: &[u8], f: fn([u8; N]) -> T) -> Vec<T> {
        data.chunks_exact(N)
            .map(|c| f(c.try_into().expect("chunks of N bytes")))
            .collect()
    }
    match dtype {
        Dtype::F4 => NpyData::F32(each(data, f32::from_le_bytes)),
        Dtype::F8 => NpyData::F64(each(data, f64::from_le_bytes)),
        Dtype::I4 => NpyData::I32(each(data, i32::from_le_bytes)),
        Dtype::I8 => NpyData::I64(each(data, i64::from_le_bytes)),
        Dtype::U4 => NpyData::U32(each(data, u32::from_le_bytes)),
        _ => NpyData::U8(data.to_vec()),
    }
}

/// Writes `data` with `shape` as a version 1.0 (2.0 for huge headers) `.npy` file,
/// atomically: a failure leaves no partial file and keeps any previous file intact.
pub fn write_npy<T: Element>(path: &Path, shape: &[usize], data: &[T]) -> Result<(), NpyError> {
    let expected = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    if expected != Some(data.len()) {
        return Err(NpyError::ShapeMismatch {
            path: path.to_path_buf(),
            shape: shape.to_vec(),
            expected: expected.unwrap_or(usize::MAX),
            found: data.len(),
        });
    }
    write_atomic(path, |w| write_npy_to(w, shape, data)).map_err(|error| NpyError::Write {
        path: path.to_path_buf(),
        error,
    })
}

/// Writes a `.npy` file to `w`. Fails with [`io::ErrorKind::InvalidInput`] before writing
/// anything when `data` does not hold exactly the elements `shape` describes.
pub fn write_npy_to<T: Element>(w: &mut dyn Write, shape: &[usize], data: &[T]) -> io::Result<()> {
    let expected = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    if expected != Some(data.len()) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "shape {} does not hold {} elements",
                ShapeDisplay(shape),
                data.len()
            ),
        ));
    }
    w.write_all(&npy_header(T::DESCR, shape))?;
    // Encode in blocks: one allocation, few write calls, no per-element syscalls.
    const BLOCK: usize = 1 << 14;
    let mut buf = Vec::with_capacity(BLOCK * std::mem::size_of::<T>());
    for chunk in data.chunks(BLOCK) {
        buf.clear();
        for &x in chunk {
            x.put(&mut buf);
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::npy::MAGIC;
    use proptest::prelude::*;

    fn parse(bytes: &[u8]) -> Result<NpyArray, NpyError> {
        parse_npy(bytes, Path::new("a.npy"))
    }

    fn err(bytes: &[u8]) -> String {
        parse(bytes).unwrap_err().to_string()
    }

    /// A file with a hand-written header (v1.0) and data.
    fn file(header: &str, data: &[u8]) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn f32_bytes(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    #[test]
    fn header_is_64_byte_aligned_and_numpy_shaped() {
        for shape in [&[][..], &[5], &[2, 3], &[1000, 4000, 3]] {
            let h = npy_header("<f4", shape);
            assert_eq!(h.len() % 64, 0);
            assert_eq!(*h.last().unwrap(), b'\n');
        }
        let h = npy_header("<f8", &[2, 3]);
        let text = std::str::from_utf8(&h[10..]).unwrap();
        assert!(
            text.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"),
            "{text}"
        );
        assert!(std::str::from_utf8(&npy_header("<f4", &[5])[10..])
            .unwrap()
            .contains("'shape': (5,)"));
    }

    /// Bytes `numpy.save` writes for `np.arange(6, dtype='<f4').reshape(2, 3)` (NumPy 1.26).
    #[test]
    fn reads_what_numpy_writes() {
        let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }";
        let mut padded = header.to_string();
        while !(10 + padded.len() + 1).is_multiple_of(64) {
            padded.push(' ');
        }
        padded.push('\n');
        let bytes = file(&padded, &f32_bytes(&[0., 1., 2., 3., 4., 5.]));
        assert_eq!(
            &bytes[..npy_header("<f4", &[2, 3]).len()],
            &npy_header("<f4", &[2, 3])[..]
        );
        let a = parse(&bytes).unwrap();
        assert_eq!(a.shape, vec![2, 3]);
        assert_eq!(a.data, NpyData::F32(vec![0., 1., 2., 3., 4., 5.]));
    }

    #[test]
    fn lenient_where_numpy_is_and_strict_elsewhere() {
        // Key order, quotes, whitespace, no trailing comma, Python 2 longs, 0-d arrays.
        let a = parse(&file(
            "{ \"shape\" : (2L,) ,'fortran_order':False,'descr':'<i8'}\n",
            &[1, 0, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0],
        ))
        .unwrap();
        assert_eq!((a.shape, a.data), (vec![2], NpyData::I64(vec![1, 2])));
        let a = parse(&file(
            "{'descr':'|u1','fortran_order':False,'shape':()}",
            &[7],
        ))
        .unwrap();
        assert_eq!((a.shape, a.data), (vec![], NpyData::U8(vec![7])));
        let a = parse(&file(
            "{'descr':'<f8','fortran_order':False,'shape':(0, 3)}",
            &[],
        ))
        .unwrap();
        assert_eq!(a.data, NpyData::F64(vec![]));
    }

    #[test]
    fn errors_name_the_file_and_say_what_was_expected() {
        let d = f32_bytes(&[1.0, 2.0]);
        assert!(err(b"PK\x03\x04 a zip").starts_with("a.npy: not a .npy file"));
        assert!(err(&file(
            "{'descr': '>f4', 'fortran_order': False, 'shape': (2,)}",
            &d
        ))
        .contains("dtype '>f4' is big-endian"));
        assert!(err(&file(
            "{'descr': '<c8', 'fortran_order': False, 'shape': (2,)}",
            &d
        ))
        .contains("dtype '<c8' is not supported"));
        assert!(err(&file(
            "{'descr': '|O', 'fortran_order': False, 'shape': (2,)}",
            &d
        ))
        .contains("dtype '|O' is not supported"));
        assert!(err(&file(
            "{'descr': '<f4', 'fortran_order': True, 'shape': (2,)}",
            &d
        ))
        .contains("fortran_order is True"));
        assert!(err(&file(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (3,)}",
            &d
        ))
        .contains("the data has 8 bytes but shape (3,) of '<f4' needs 12"));
        assert!(err(&file("{'descr': '<f4', 'fortran_order': False}", &d))
            .contains("key 'shape' is missing"));
        assert!(err(&file(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), 'x': 1}",
            &d
        ))
        .contains("unknown key 'x'"));
        assert!(err(&file(
            "{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (2,)}",
            &d
        ))
        .contains("key 'descr' appears twice"));
        assert!(err(&file(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (-2,)}",
            &d
        ))
        .contains("expected a non-negative integer"));
        assert!(err(&file(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999, 99999999999)}",
            &d
        ))
        .contains("too large"));
        assert!(err(&file(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2,)} x",
            &d
        ))
        .contains("unexpected text after the dict"));
        let mut truncated = file(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2,)}",
            &d,
        );
        truncated[8] = 200; // header length beyond the end
        assert!(err(&truncated).contains("the file is truncated"));
        let mut v9 = file("{}", &[]);
        v9[6] = 9;
        assert!(err(&v9).contains("version 9.0"));
    }

    #[test]
    fn writer_checks_the_shape_and_is_atomic() {
        let dir = crate::io::test_dir::TestDir::new("npy");
        let path = dir.0.join("x.npy");
        let e = write_npy(&path, &[2, 3], &[1.0f32; 5]).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "{}: shape (2, 3) holds 6 elements but 5 were given",
                path.display()
            )
        );
        assert!(dir.entries().is_empty());
        // A parent that is a file.
        std::fs::write(dir.0.join("f"), b"").unwrap();
        let e = write_npy(&dir.0.join("f/x.npy"), &[1], &[1u8]).unwrap_err();
        assert!(e.to_string().starts_with("cannot write "), "{e}");
        assert_eq!(dir.entries(), vec!["f"]);
    }

    proptest! {
        #[test]
        fn write_then_read_is_identity(
            dims in prop::collection::vec(0usize..5, 0..4),
            seed in any::<u64>(),
            kind in 0usize..6,
        ) {
            let n: usize = dims.iter().product();
            let f = |i: usize| (seed.wrapping_mul(6364136223846793005).wrapping_add(i as u64).wrapping_mul(1442695040888963407)) as i64;
            let mut bytes = Vec::new();
            let want = match kind {
                0 => { let v: Vec<f32> = (0..n).map(|i| f(i) as f32 * 1e-9).collect(); write_npy_to(&mut bytes, &dims, &v).unwrap(); NpyData::F32(v) }
                1 => { let v: Vec<f64> = (0..n).map(|i| f(i) as f64 / 3.0).collect(); write_npy_to(&mut bytes, &dims, &v).unwrap(); NpyData::F64(v) }
                2 => { let v: Vec<i32> = (0..n).map(|i| f(i) as i32).collect(); write_npy_to(&mut bytes, &dims, &v).unwrap(); NpyData::I32(v) }
                3 => { let v: Vec<i64> = (0..n).map(f).collect(); write_npy_to(&mut bytes, &dims, &v).unwrap(); NpyData::I64(v) }
                4 => { let v: Vec<u32> = (0..n).map(|i| f(i) as u32).collect(); write_npy_to(&mut bytes, &dims, &v).unwrap(); NpyData::U32(v) }
                _ => { let v: Vec<u8> = (0..n).map(|i| f(i) as u8).collect(); write_npy_to(&mut bytes, &dims, &v).unwrap(); NpyData::U8(v) }
            };
            let a = parse_npy(&bytes, Path::new("p.npy")).unwrap();
            prop_assert_eq!(a.shape, dims);
            prop_assert_eq!(a.data, want);
        }

        /// Arbitrary bytes after a valid magic never panic the reader.
        #[test]
        fn garbage_never_panics(tail in prop::collection::vec(any::<u8>(), 0..200), major in 0u8..4) {
            let mut bytes = MAGIC.to_vec();
            bytes.push(major);
            bytes.push(0);
            bytes.extend_from_slice(&tail);
            let _ = parse_npy(&bytes, Path::new("g.npy"));
        }
    }
}
