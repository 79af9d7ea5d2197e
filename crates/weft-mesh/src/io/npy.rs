//! The NumPy `.npy` format, once: the preamble, the header dict, the element types and
//! the data section, shared by the standalone `.npy` files of
//! [`export::npy`](crate::export::npy) and the members of [`.npz`](super::npz) archives.
//!
//! ```text
//! \x93NUMPY  major minor  header_len (u16 LE for 1.0, u32 LE for 2.0 / 3.0)
//! {'descr': '<f4', 'fortran_order': False, 'shape': (2, 4000, 3), }   (space padded, '\n')
//! data
//! ```
//!
//! Reading is two steps so memory is bounded by the input, never by what a header claims:
//! [`read_header`] reads the preamble and the dict (at most [`MAX_HEADER_BYTES`]) and, when
//! the input's length is known, compares the data the shape needs with the bytes present
//! *before* anything is allocated for it; [`read_data`] then reads exactly that many bytes,
//! growing its buffer with the bytes that actually arrive. A small file that claims a huge
//! array fails at once with an error saying so.
//!
//! The callers decide policy: `export::npy` refuses Fortran order and reads six element
//! types; `.npz` members transpose Fortran order (files converted from SMPL's pickles have
//! it) and read every numeric type here.

use std::fmt::{self, Write as _};
use std::io::{self, Read};

/// The first six bytes of every `.npy` file.
pub(crate) const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// The data section starts at a multiple of this (NumPy aligns to 64 bytes since 1.14).
const ALIGN: usize = 64;

/// The longest header dict weft reads (bytes). NumPy itself refuses headers over 10 000
/// bytes by default; a longer length field is corrupt, and is refused before reading it.
pub const MAX_HEADER_BYTES: usize = 1 << 20;

mod sealed {
    pub trait Sealed {}
}

/// An element type weft writes in `.npy` files and `.npz` members, always little-endian.
pub trait Element: Copy + sealed::Sealed {
    /// The NumPy `descr` string, e.g. `<f4`.
    const DESCR: &'static str;
    /// Appends the little-endian bytes of `self`.
    fn put(self, out: &mut Vec<u8>);
}

macro_rules! element {
    ($t:ty, $descr:literal) => {
        impl sealed::Sealed for $t {}
        impl Element for $t {
            const DESCR: &'static str = $descr;
            #[inline]
            fn put(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
        }
    };
}

element!(f32, "<f4");
element!(f64, "<f8");
element!(i32, "<i4");
element!(i64, "<i8");
element!(u32, "<u4");
element!(u8, "|u1");

impl sealed::Sealed for bool {}
impl Element for bool {
    const DESCR: &'static str = "|b1";
    #[inline]
    fn put(self, out: &mut Vec<u8>) {
        out.push(u8::from(self));
    }
}

/// The element types weft reads (a header's `descr`, byte order resolved).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Dtype {
    F4,
    F8,
    I1,
    I2,
    I4,
    I8,
    U1,
    U2,
    U4,
    U8,
    B1,
}

impl Dtype {
    /// The dtype of a `descr`; big-endian and non-numeric types are refused with a hint.
    pub(crate) fn parse(descr: &str) -> Result<Self, String> {
        // The byte order is one ASCII character; split after the first character, not
        // the first byte, so a multi-byte first character is refused, not a panic.
        let first = descr.chars().next().map_or(0, char::len_utf8);
        let (order, code) = descr.split_at(first);
        if order == ">" && !matches!(code, "i1" | "u1" | "b1") {
            return Err(format!(
                "dtype '{descr}' is big-endian; expected little-endian data (in NumPy: a.astype(a.dtype.newbyteorder('<')))"
            ));
        }
        if !matches!(order, "<" | "|" | "=" | ">") {
            return Err(format!("dtype '{descr}' is not a numeric dtype weft reads"));
        }
        Ok(match code {
            "f4" => Dtype::F4,
            "f8" => Dtype::F8,
            "i1" => Dtype::I1,
            "i2" => Dtype::I2,
            "i4" => Dtype::I4,
            "i8" => Dtype::I8,
            "u1" => Dtype::U1,
            "u2" => Dtype::U2,
            "u4" => Dtype::U4,
            "u8" => Dtype::U8,
            "b1" => Dtype::B1,
            _ => {
                return Err(format!(
                    "dtype '{descr}' is not supported; expected a float ('<f4', '<f8'), integer ('<i4', '<i8', '<u4', …) or bool ('|b1') array"
                ))
            }
        })
    }

    /// Bytes per element.
    pub(crate) fn size(self) -> usize {
        match self {
            Dtype::I1 | Dtype::U1 | Dtype::B1 => 1,
            Dtype::I2 | Dtype::U2 => 2,
            Dtype::F4 | Dtype::I4 | Dtype::U4 => 4,
            Dtype::F8 | Dtype::I8 | Dtype::U8 => 8,
        }
    }

    /// The canonical `descr`.
    pub(crate) fn descr(self) -> &'static str {
        match self {
            Dtype::F4 => "<f4",
            Dtype::F8 => "<f8",
            Dtype::I1 => "|i1",
            Dtype::I2 => "<i2",
            Dtype::I4 => "<i4",
            Dtype::I8 => "<i8",
            Dtype::U1 => "|u1",
            Dtype::U2 => "<u2",
            Dtype::U4 => "<u4",
            Dtype::U8 => "<u8",
            Dtype::B1 => "|b1",
        }
    }
}

/// Why an array could not be read: the input failed, or it is not an array weft reads.
#[derive(Debug)]
pub(crate) enum ReadError {
    /// The underlying reader failed (not end of input: that is [`ReadError::Invalid`]).
    Io(io::Error),
    /// What was found and what was expected, in words.
    Invalid(String),
}

impl From<String> for ReadError {
    fn from(message: String) -> Self {
        ReadError::Invalid(message)
    }
}

/// A parsed header: everything about the array but its data.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Header {
    /// The `descr` as written.
    pub descr: String,
    /// The element type.
    pub dtype: Dtype,
    /// Whether the data is in Fortran (column-major) order.
    pub fortran_order: bool,
    /// Extent of each axis; empty for a 0-dimensional array (one element).
    pub shape: Vec<usize>,
    /// Bytes the data section needs: elements × element size.
    pub data_len: usize,
}

impl Header {
    /// The error for a data section of `found` bytes where [`Header::data_len`] are needed.
    fn data_mismatch(&self, found: u64) -> ReadError {
        ReadError::Invalid(format!(
            "the data has {found} bytes but shape {} of '{}' needs {}; the file is truncated or not what its header says",
            ShapeDisplay(&self.shape),
            self.descr,
            self.data_len
        ))
    }
}

/// Reads `buf.len()` bytes, or fails with `eof` when the input ends first.
fn fill(r: &mut impl Read, buf: &mut [u8], eof: impl FnOnce() -> String) -> Result<(), ReadError> {
    r.read_exact(buf).map_err(|e| match e.kind() {
        io::ErrorKind::UnexpectedEof => ReadError::Invalid(eof()),
        _ => ReadError::Io(e),
    })
}

/// Reads the preamble and header of an array from `r`, which holds `len` bytes in all
/// when that is known (a file's or a buffer's length, an archive member's size).
///
/// Accepts format versions 1.0, 2.0 and 3.0 and exactly the keys `descr`,
/// `fortran_order` and `shape`. With `len` known it also checks, before any data is read
/// or allocated, that the data section holds exactly the bytes the shape needs.
pub(crate) fn read_header(r: &mut impl Read, len: Option<u64>) -> Result<Header, ReadError> {
    let not_npy = || {
        "not a .npy file (it does not start with \\x93NUMPY); expected an array saved by numpy.save"
            .to_string()
    };
    let mut preamble = [0u8; 10];
    if len.is_some_and(|n| n < 10) {
        return Err(ReadError::Invalid(not_npy()));
    }
    fill(r, &mut preamble, not_npy)?;
    if &preamble[..6] != MAGIC {
        return Err(ReadError::Invalid(not_npy()));
    }
    let (major, minor) = (preamble[6], preamble[7]);
    let (header_len, start): (usize, u64) = match major {
        1 => (
            usize::from(u16::from_le_bytes([preamble[8], preamble[9]])),
            10,
        ),
        2 | 3 => {
            let mut rest = [0u8; 2];
            fill(r, &mut rest, || {
                "the file ends inside the preamble; the file is truncated".to_string()
            })?;
            let n = u32::from_le_bytes([preamble[8], preamble[9], rest[0], rest[1]]);
            (usize::try_from(n).unwrap_or(usize::MAX), 12)
        }
        _ => {
            return Err(ReadError::Invalid(format!(
                ".npy format version {major}.{minor}; expected 1.0, 2.0 or 3.0"
            )))
        }
    };
    let truncated = |after: String| {
        format!(
            "the header claims {header_len} bytes but the file has only {after} after the preamble; the file is truncated"
        )
    };
    if let Some(len) = len {
        let after = len.saturating_sub(start);
        if header_len as u64 > after {
            return Err(ReadError::Invalid(truncated(after.to_string())));
        }
    }
    if header_len > MAX_HEADER_BYTES {
        return Err(ReadError::Invalid(format!(
            "the header claims {header_len} bytes, more than the {MAX_HEADER_BYTES} weft reads; the file is damaged"
        )));
    }
    let mut text = vec![0u8; header_len];
    fill(r, &mut text, || truncated("fewer".into()))?;
    let text = std::str::from_utf8(&text)
        .map_err(|_| "the header is not text; expected a Python dict literal".to_string())?;
    let (descr, fortran_order, shape) = parse_header(text).map_err(|m| format!("header: {m}"))?;
    let too_large = || format!("shape {} is too large", ShapeDisplay(&shape));
    let count = shape
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(too_large)?;
    let dtype = Dtype::parse(&descr)?;
    let data_len = count.checked_mul(dtype.size()).ok_or_else(too_large)?;
    let header = Header {
        descr,
        dtype,
        fortran_order,
        shape,
        data_len,
    };
    if let Some(len) = len {
        let found = len - start - header_len as u64;
        if found != header.data_len as u64 {
            return Err(header.data_mismatch(found));
        }
    }
    Ok(header)
}

/// Reads the data section [`read_header`] described: exactly `header.data_len` bytes,
/// refusing an input that ends early or goes on. The buffer grows with the bytes that
/// arrive, so a header's claim costs nothing until the input backs it; `reserve` allocates
/// it at once instead, for inputs whose length [`read_header`] has already checked.
pub(crate) fn read_data(
    r: &mut impl Read,
    header: &Header,
    reserve: bool,
) -> Result<Vec<u8>, ReadError> {
    let mut data = Vec::new();
    if reserve {
        data.reserve_exact(header.data_len);
    }
    r.take(header.data_len as u64 + 1)
        .read_to_end(&mut data)
        .map_err(ReadError::Io)?;
    if data.len() != header.data_len {
        return Err(header.data_mismatch(data.len() as u64));
    }
    Ok(data)
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

/// Appends `data` to a buffer holding a header: the whole member or file in memory.
pub(crate) fn put_all<T: Element>(out: &mut Vec<u8>, data: &[T]) {
    out.reserve(std::mem::size_of_val(data));
    for &x in data {
        x.put(out);
    }
}

/// Reorders Fortran-order (first index fastest) element bytes into C order.
pub(crate) fn fortran_to_c(data: &[u8], shape: &[usize], size: usize) -> Vec<u8> {
    let count: usize = shape.iter().product();
    // Fortran strides, in elements.
    let mut fstride = vec![1usize; shape.len()];
    for k in 1..shape.len() {
        fstride[k] = fstride[k - 1] * shape[k - 1];
    }
    let mut out = Vec::with_capacity(data.len());
    let mut index = vec![0usize; shape.len()];
    for _ in 0..count {
        let src: usize = index.iter().zip(&fstride).map(|(i, s)| i * s).sum();
        out.extend_from_slice(&data[src * size..(src + 1) * size]);
        // Advance the C-order multi-index (last index fastest).
        for k in (0..shape.len()).rev() {
            index[k] += 1;
            if index[k] < shape[k] {
                break;
            }
            index[k] = 0;
        }
    }
    out
}

/// Parses the header dict `{'descr': STR, 'fortran_order': BOOL, 'shape': TUPLE}` in any
/// key order, with optional trailing comma and surrounding whitespace, into
/// (descr, fortran_order, shape).
fn parse_header(text: &str) -> Result<(String, bool, Vec<usize>), String> {
    let mut p = Parser {
        s: text.as_bytes(),
        i: 0,
    };
    let mut descr = None;
    let mut fortran = None;
    let mut shape = None;
    p.ws();
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
    let fortran = fortran.ok_or_else(|| missing("fortran_order"))?;
    let shape = shape.ok_or_else(|| missing("shape"))?;
    Ok((descr, fortran, shape))
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

    /// Found by fuzzing (docs/fuzzing.md): a `descr` starting with a multi-byte character
    /// (`'Ǌ4'`) made the byte-order split panic outside a character boundary.
    #[test]
    fn a_multibyte_descr_is_refused() {
        let bytes = include_bytes!("../../tests/fuzz_regressions/npy_multibyte_descr.npy");
        let e = read_header(&mut &bytes[..], Some(bytes.len() as u64)).unwrap_err();
        let ReadError::Invalid(message) = e else {
            panic!("{e:?}");
        };
        assert!(
            message.contains("dtype 'Ǌ4' is not a numeric dtype"),
            "{message}"
        );
        for descr in ["é", "Ǌ", "<é", "\u{10FFFF}f4", ""] {
            assert!(Dtype::parse(descr).is_err(), "{descr}");
        }
    }

    /// A v1.0 preamble and `dict` as the header, followed by `data`.
    fn file(dict: &str, data: &[u8]) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn invalid(r: Result<Header, ReadError>) -> String {
        match r {
            Err(ReadError::Invalid(m)) => m,
            other => panic!("expected an invalid-array error, got {other:?}"),
        }
    }

    /// A 100-byte input claiming 2⁴⁰ doubles fails at the header, known length or not,
    /// and the streaming read stops at the bytes present.
    #[test]
    fn a_huge_claim_in_a_small_input_fails_before_allocating() {
        let bytes = file(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (1099511627776,), }\n",
            &[0u8; 16],
        );
        let m = invalid(read_header(&mut &bytes[..], Some(bytes.len() as u64)));
        assert!(
            m.starts_with(
                "the data has 16 bytes but shape (1099511627776,) of '<f8' needs 8796093022208"
            ),
            "{m}"
        );
        let mut r = &bytes[..];
        let h = read_header(&mut r, None).unwrap();
        match read_data(&mut r, &h, false) {
            Err(ReadError::Invalid(m)) => assert!(m.starts_with("the data has 16 bytes"), "{m}"),
            other => panic!("{other:?}"),
        }
        // A header length field far beyond the input, and beyond any real header.
        let mut big = file("{}", &[]);
        big[6] = 2;
        big.extend_from_slice(&[0, 0]);
        big[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        let m = invalid(read_header(&mut &big[..], None));
        assert!(m.contains("more than the 1048576 weft reads"), "{m}");
        let m = invalid(read_header(&mut &big[..], Some(big.len() as u64)));
        assert!(m.contains("the file is truncated"), "{m}");
    }

    #[test]
    fn an_endless_input_is_read_only_as_far_as_the_shape_says() {
        let head = file(
            "{'descr': '|u1', 'fortran_order': False, 'shape': (8,)}",
            &[],
        );
        let mut r = head.as_slice().chain(io::repeat(7));
        let h = read_header(&mut r, None).unwrap();
        match read_data(&mut r, &h, false) {
            Err(ReadError::Invalid(m)) => assert!(m.starts_with("the data has 9 bytes"), "{m}"),
            other => panic!("{other:?}"),
        }
        let m = invalid(read_header(&mut io::repeat(0), None));
        assert!(m.starts_with("not a .npy file"), "{m}");
    }
}
