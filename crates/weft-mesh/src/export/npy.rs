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
//! Supported element types ([`Element`]): `<f4`, `<f8`, `<i4`, `<i8`, `<u4`, `|u1`.

use std::fmt::{self, Write as _};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use crate::io::write_atomic;

/// The first six bytes of every `.npy` file.
const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// The data section starts at a multiple of this (NumPy aligns to 64 bytes since 1.14).
const ALIGN: usize = 64;

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

mod sealed {
    pub trait Sealed {}
}

/// An element type weft reads and writes in `.npy` files, always little-endian.
pub trait Element: Copy + sealed::Sealed {
    /// The NumPy `descr` string, e.g. `<f4`.
    const DESCR: &'static str;
    /// Bytes per element.
    const SIZE: usize;
    /// Appends the little-endian bytes of `self`.
    fn put(self, out: &mut Vec<u8>);
    /// Reads one element from exactly [`Self::SIZE`] little-endian bytes.
    fn get(bytes: &[u8]) -> Self;
    /// Wraps a vector of this type.
    fn wrap(data: Vec<Self>) -> NpyData;
}

macro_rules! element {
    ($t:ty, $descr:literal, $variant:ident) => {
        impl sealed::Sealed for $t {}
        impl Element for $t {
            const DESCR: &'static str = $descr;
            const SIZE: usize = std::mem::size_of::<$t>();
            #[inline]
            fn put(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            #[inline]
            fn get(bytes: &[u8]) -> Self {
                let mut b = [0u8; std::mem::size_of::<$t>()];
                b.copy_from_slice(bytes);
                <$t>::from_le_bytes(b)
            }
            fn wrap(data: Vec<Self>) -> NpyData {
                NpyData::$variant(data)
            }
        }
    };
}

element!(f32, "<f4", F32);
element!(f64, "<f8", F64);
element!(i32, "<i4", I32);
element!(i64, "<i8", I64);
element!(u32, "<u4", U32);
element!(u8, "|u1", U8);

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

/// Reads a `.npy` file; see [`parse_npy`].
pub fn read_npy(path: &Path) -> Result<NpyArray, NpyError> {
    let bytes = std::fs::read(path).map_err(|error| NpyError::Read {
        path: path.to_path_buf(),
        error,
    })?;
    parse_npy(&bytes, path)
}

/// Parses a `.npy` file held in memory; `path` only names the file in errors.
///
/// Accepts format versions 1.0, 2.0 and 3.0, C order, the element types of [`Element`],
/// and exactly the keys `descr`, `fortran_order` and `shape`. The data section must hold
/// exactly the bytes the shape needs.
pub fn parse_npy(bytes: &[u8], path: &Path) -> Result<NpyArray, NpyError> {
    let invalid = |message: String| NpyError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err(invalid(
            "not a .npy file (it does not start with \\x93NUMPY); expected an array saved by numpy.save".into(),
        ));
    }
    let (major, minor) = (bytes[6], bytes[7]);
    let (header_len, start): (usize, usize) = match major {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        _ => {
            return Err(invalid(format!(
                ".npy format version {major}.{minor}; expected 1.0, 2.0 or 3.0"
            )))
        }
    };
    let data_start = start
        .checked_add(header_len)
        .filter(|&end| end <= bytes.len())
        .ok_or_else(|| {
            invalid(format!(
                "the header claims {header_len} bytes but the file has only {} after the preamble; the file is truncated",
                bytes.len() - start
            ))
        })?;
    let header = std::str::from_utf8(&bytes[start..data_start])
        .map_err(|_| invalid("the header is not text; expected a Python dict literal".into()))?;
    let header = parse_header(header).map_err(|m| invalid(format!("header: {m}")))?;
    let data = &bytes[data_start..];

    let count = header
        .shape
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| {
            invalid(format!(
                "shape {} is too large",
                ShapeDisplay(&header.shape)
            ))
        })?;
    let dtype = Dtype::from_descr(&header.descr).map_err(invalid)?;
    let needed = count.checked_mul(dtype.size()).ok_or_else(|| {
        invalid(format!(
            "shape {} is too large",
            ShapeDisplay(&header.shape)
        ))
    })?;
    if data.len() != needed {
        return Err(invalid(format!(
            "the data section has {} bytes but shape {} of '{}' needs {needed}; the file is truncated or not what its header says",
            data.len(),
            ShapeDisplay(&header.shape),
            header.descr
        )));
    }
    let data = match dtype {
        Dtype::F32 => decode::<f32>(data),
        Dtype::F64 => decode::<f64>(data),
        Dtype::I32 => decode::<i32>(data),
        Dtype::I64 => decode::<i64>(data),
        Dtype::U32 => decode::<u32>(data),
        Dtype::U8 => decode::<u8>(data),
    };
    Ok(NpyArray {
        shape: header.shape,
        data,
    })
}

fn decode<T: Element>(data: &[u8]) -> NpyData {
    T::wrap(data.chunks_exact(T::SIZE).map(T::get).collect())
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
    let mut buf = Vec::with_capacity(BLOCK * T::SIZE);
    for chunk in data.chunks(BLOCK) {
        buf.clear();
        for &x in chunk {
            x.put(&mut buf);
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

/// The preamble and header of a `.npy` file of `descr` and `shape`, padded with spaces
/// and a final newline so the data starts at a multiple of 64 bytes (as NumPy writes).
pub fn npy_header(descr: &str, shape: &[usize]) -> Vec<u8> {
    let mut dict = format!(
        "{{'descr': '{descr}', 'fortran_order': False, 'shape': {}, }}",
        ShapeDisplay(shape)
    );
    // Version 1.0 stores the header length in a u16; longer headers need 2.0.
    let (version, preamble) = if dict.len() + 1 + 10 + ALIGN <= usize::from(u16::MAX) {
        (1u8, 10)
    } else {
        (2u8, 12)
    };
    let total = (preamble + dict.len() + 1).div_ceil(ALIGN) * ALIGN;
    while preamble + dict.len() + 1 < total {
        dict.push(' ');
    }
    dict.push('\n');
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[version, 0]);
    if version == 1 {
        // Bounded by the check above.
        out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(dict.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(dict.as_bytes());
    out
}

/// The element types [`parse_npy`] accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dtype {
    F32,
    F64,
    I32,
    I64,
    U32,
    U8,
}

impl Dtype {
    fn from_descr(descr: &str) -> Result<Self, String> {
        Ok(match descr {
            "<f4" => Dtype::F32,
            "<f8" => Dtype::F64,
            "<i4" => Dtype::I32,
            "<i8" => Dtype::I64,
            "<u4" => Dtype::U32,
            "|u1" | "<u1" => Dtype::U8,
            d if d.starts_with('>') => {
                return Err(format!(
                    "dtype '{d}' is big-endian; expected little-endian data (in NumPy: a.astype(a.dtype.newbyteorder('<')))"
                ))
            }
            d => {
                return Err(format!(
                    "dtype '{d}' is not supported; expected one of '<f4', '<f8', '<i4', '<i8', '<u4', '|u1'"
                ))
            }
        })
    }

    fn size(self) -> usize {
        match self {
            Dtype::F32 | Dtype::I32 | Dtype::U32 => 4,
            Dtype::F64 | Dtype::I64 => 8,
            Dtype::U8 => 1,
        }
    }
}

/// The three keys of a `.npy` header.
#[derive(Debug, PartialEq)]
struct Header {
    descr: String,
    shape: Vec<usize>,
}

/// Parses the header dict: `{'descr': STR, 'fortran_order': BOOL, 'shape': TUPLE}` in
/// any order, with optional trailing comma and surrounding whitespace.
fn parse_header(text: &str) -> Result<Header, String> {
    let mut p = Parser {
        s: text.as_bytes(),
        i: 0,
    };
    let mut descr = None;
    let mut fortran = None;
    let mut shape = None;
    p.expect(b'{')?;
    loop {
        p.ws();
        if p.eat(b'}') {
            break;
        }
        let key = p.string()?;
        p.ws();
        p.expect(b':')?;
        p.ws();
        let duplicate = match key.as_str() {
            "descr" => descr.replace(p.string()?).is_some(),
            "fortran_order" => fortran.replace(p.boolean()?).is_some(),
            "shape" => shape.replace(p.tuple()?).is_some(),
            other => {
                return Err(format!(
                    "unknown key '{other}'; expected only 'descr', 'fortran_order' and 'shape'"
                ))
            }
        };
        if duplicate {
            return Err(format!("key '{key}' appears twice"));
        }
        p.ws();
        if !p.eat(b',') {
            p.ws();
            p.expect(b'}')?;
            break;
        }
    }
    if let Some(rest) = text.get(p.i..) {
        if !rest.trim().is_empty() {
            return Err(format!(
                "unexpected text after the dict: `{}`",
                rest.trim().chars().take(20).collect::<String>()
            ));
        }
    }
    let missing = |k: &str| format!("key '{k}' is missing");
    let descr = descr.ok_or_else(|| missing("descr"))?;
    if fortran.ok_or_else(|| missing("fortran_order"))? {
        return Err(
            "fortran_order is True; expected a C-order array (in NumPy: np.ascontiguousarray(a))"
                .into(),
        );
    }
    let shape = shape.ok_or_else(|| missing("shape"))?;
    Ok(Header { descr, shape })
}

/// A cursor over the header bytes.
struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn ws(&mut self) {
        while matches!(self.peek(), Some(b' ' | b'\t' | b'\n' | b'\r')) {
            self.i += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        if self.peek() == Some(c) {
            self.i += 1;
            true
        } else {
            false
        }
    }

    fn found(&self) -> String {
        match self.peek() {
            Some(c) => format!("`{}` at byte {}", c as char, self.i),
            None => "the end of the header".into(),
        }
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!("expected `{}`, found {}", c as char, self.found()))
        }
    }

    /// A quoted string without escapes (`'...'` or `"..."`).
    fn string(&mut self) -> Result<String, String> {
        let quote = match self.peek() {
            Some(q @ (b'\'' | b'"')) => q,
            _ => return Err(format!("expected a quoted string, found {}", self.found())),
        };
        self.i += 1;
        let start = self.i;
        while let Some(c) = self.peek() {
            if c == quote {
                let s = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                self.i += 1;
                return Ok(s);
            }
            if c == b'\\' {
                return Err("escape sequences in header strings are not supported".into());
            }
            self.i += 1;
        }
        Err("unterminated string".into())
    }

    fn boolean(&mut self) -> Result<bool, String> {
        for (word, value) in [("True", true), ("False", false)] {
            if self.s[self.i..].starts_with(word.as_bytes()) {
                self.i += word.len();
                return Ok(value);
            }
        }
        Err(format!("expected True or False, found {}", self.found()))
    }

    /// `()`, `(n,)`, `(n, m)`, … of non-negative integers (a Python 2 `L` suffix allowed).
    fn tuple(&mut self) -> Result<Vec<usize>, String> {
        self.expect(b'(')?;
        let mut dims = Vec::new();
        loop {
            self.ws();
            if self.eat(b')') {
                break;
            }
            let start = self.i;
            while matches!(self.peek(), Some(b'0'..=b'9')) {
                self.i += 1;
            }
            if start == self.i {
                return Err(format!(
                    "expected a non-negative integer in the shape, found {}",
                    self.found()
                ));
            }
            let digits = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
            let d: usize = digits
                .parse()
                .map_err(|_| format!("shape entry {digits} is too large"))?;
            dims.push(d);
            self.eat(b'L');
            self.ws();
            if !self.eat(b',') {
                self.ws();
                self.expect(b')')?;
                break;
            }
        }
        // Python writes a 1-tuple as `(n,)`; `(n)` is an int, not a shape, but accepting
        // it costs nothing and reads what the user meant.
        Ok(dims)
    }
}

/// Formats a shape the way Python writes a tuple: `()`, `(5,)`, `(2, 3)`.
pub(crate) struct ShapeDisplay<'a>(pub &'a [usize]);

impl fmt::Display for ShapeDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut s = String::from("(");
        for (k, d) in self.0.iter().enumerate() {
            if k > 0 {
                s.push_str(", ");
            }
            let _ = write!(s, "{d}");
        }
        if self.0.len() == 1 {
            s.push(',');
        }
        s.push(')');
        f.write_str(&s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
        while (10 + padded.len() + 1) % 64 != 0 {
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
        .contains("the data section has 8 bytes but shape (3,) of '<f4' needs 12"));
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
        let e = write_npy(&dir.0.join("no/such/x.npy"), &[1], &[1u8]).unwrap_err();
        assert!(e.to_string().starts_with("cannot write "), "{e}");
        assert!(dir.entries().is_empty());
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
