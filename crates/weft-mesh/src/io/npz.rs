//! NumPy `.npz` archives: a zip of `.npy` members, read by name with dtype and shape
//! checks, and written atomically.
//!
//! Body models (SMPL's and weft's own), motions (AMASS) and datasets travel as `.npz`.
//! What we need from the format is small, and the point is the errors: every failure
//! names the file, the key (the array's name, without `.npy`) and what was expected
//! against what was found, so "wrong shape of `shapedirs`" is one line a user can act on.
//!
//! Reading:
//! - members stored or deflated (`numpy.savez` and `numpy.savez_compressed`);
//! - `.npy` format versions 1.0, 2.0 and 3.0, little-endian or byte-order-free dtypes
//!   `<f4 <f8 <i1 <i2 <i4 <i8 <u1 <u2 <u4 <u8 |b1` (and `|i1 |u1`);
//! - **Fortran-order arrays** too, transposed to C order on load: files converted from
//!   SMPL's pickles often hold Fortran-ordered arrays, and refusing them would break the
//!   promise that a user's SMPL file loads unchanged;
//! - members are parsed only when asked for, so a file may carry other members weft does
//!   not read (strings, objects: SMPL files have `bs_style`, `bs_type`).
//!
//! Typed access converts losslessly within a kind: [`Npz::floats`] accepts `f4`/`f8` as
//! `f64`, [`Npz::ints`] any integer or bool dtype as `i64`. Floats are never silently
//! turned into indices, nor indices into floats.
//!
//! Writing ([`NpzWriter`]) builds the archive in memory and hands it to
//! [`write_atomic`](super::write_atomic), so a crash never leaves a partial file; entries
//! get a fixed timestamp so the same arrays give the same bytes.
//!
//! Members are parsed by the one `.npy` reader of [`super::npy`], streaming out of the
//! archive: the array's header is read first and its shape checked against the member's
//! size, and that size against what the member's compressed bytes can hold, before the
//! data is read, so a small crafted archive that claims a huge array fails at once
//! instead of allocating for the claim.

use std::collections::BTreeMap;
use std::fmt;
use std::fs::File;
use std::io::{self, BufReader, Cursor, Read, Seek, Write};
use std::path::{Path, PathBuf};

use super::npy::{self, fortran_to_c, npy_header, Dtype, Element, ReadError, ShapeDisplay};
use super::write_atomic;

/// The largest member weft will inflate (bytes): far above any body model or motion, far
/// below what would exhaust memory from a corrupt size field.
pub const MAX_MEMBER_BYTES: u64 = 8 << 30;

/// The most a deflated stream can expand (deflate's limit is about 1032:1): a member
/// claiming more per compressed byte is damaged, and is refused before it is read.
pub const MAX_DEFLATE_RATIO: u64 = 1032;

/// What went wrong reading or writing a `.npz` file.
#[derive(Debug, thiserror::Error)]
pub enum NpzError {
    /// The file could not be read.
    #[error("cannot read {}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: io::Error,
    },
    /// The file could not be written (nothing is left behind).
    #[error("cannot write {}", .path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's (or the zip writer's) error.
        #[source]
        source: io::Error,
    },
    /// The zip layer refused the archive or one of its members.
    #[error("{}: {what}", .path.display())]
    Zip {
        /// The file.
        path: PathBuf,
        /// What was being read, and what was expected.
        what: String,
        /// The zip reader's error.
        #[source]
        source: zip::result::ZipError,
    },
    /// A member is damaged: it claims more bytes than the archive can hold.
    #[error("{}: {message}", .path.display())]
    Archive {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A key the caller needs is not in the archive.
    #[error("{}: no array `{key}` (the file has: {}); expected an .npz with `{key}`", .path.display(), .available.join(", "))]
    Missing {
        /// The file.
        path: PathBuf,
        /// The array name asked for.
        key: String,
        /// The array names present.
        available: Vec<String>,
    },
    /// The member is not a `.npy` array weft reads.
    #[error("{}: `{key}`: {message}", .path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The array name.
        key: String,
        /// What was found and what was expected.
        message: String,
    },
    /// The array has an element type of the wrong kind.
    #[error("{}: `{key}` has dtype '{found}'; expected {expected}", .path.display())]
    Dtype {
        /// The file.
        path: PathBuf,
        /// The array name.
        key: String,
        /// What would have been accepted, in words.
        expected: String,
        /// The NumPy `descr` found.
        found: String,
    },
    /// The array has the wrong shape.
    #[error("{}: `{key}` has shape {}; expected {}", .path.display(), ShapeDisplay(.found), ShapePattern(.expected))]
    Shape {
        /// The file.
        path: PathBuf,
        /// The array name.
        key: String,
        /// The expected shape, `None` where any extent is accepted.
        expected: Vec<Option<usize>>,
        /// The shape found.
        found: Vec<usize>,
    },
}

/// An array read from an `.npz`: its shape (C order) and its elements.
#[derive(Clone, Debug, PartialEq)]
pub struct NpzArray<T> {
    /// Extent of each axis; empty for a scalar.
    pub shape: Vec<usize>,
    /// The elements in C order, `shape.iter().product()` of them.
    pub data: Vec<T>,
}

/// What an archive is read from: a file or bytes in memory.
trait Source: Read + Seek + Send + Sync {}
impl<T: Read + Seek + Send + Sync> Source for T {}

/// A `.npz` archive opened for reading. Members are inflated and parsed on request.
pub struct Npz {
    path: PathBuf,
    archive: zip::ZipArchive<Box<dyn Source>>,
    /// Bytes in the archive: no stored member is larger, no deflated one more than
    /// [`MAX_DEFLATE_RATIO`] times larger.
    len: u64,
    /// Array name (member name without `.npy`) → member name.
    members: BTreeMap<String, String>,
}

impl fmt::Debug for Npz {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Npz")
            .field("path", &self.path)
            .field("keys", &self.members.keys().collect::<Vec<_>>())
            .finish()
    }
}

impl Npz {
    /// Opens the `.npz` file at `path`. Members are read from the file when asked for, so
    /// memory follows the arrays read, not the file (nor an endless device: a zip is found
    /// from its end, which a stream does not have).
    pub fn open(path: &Path) -> Result<Self, NpzError> {
        let io_err = |source| NpzError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = File::open(path).map_err(io_err)?;
        let len = file.metadata().map_err(io_err)?.len();
        Self::from_source(Box::new(BufReader::new(file)), len, path)
    }

    /// Reads an `.npz` held in memory; `path` only names it in errors.
    pub fn from_bytes(bytes: Vec<u8>, path: &Path) -> Result<Self, NpzError> {
        let len = bytes.len() as u64;
        Self::from_source(Box::new(Cursor::new(bytes)), len, path)
    }

    fn from_source(source: Box<dyn Source>, len: u64, path: &Path) -> Result<Self, NpzError> {
        let archive = zip::ZipArchive::new(source).map_err(|source| NpzError::Zip {
            path: path.to_path_buf(),
            what: "not a readable .npz (zip) archive; expected a file written by numpy.savez"
                .into(),
            source,
        })?;
        let members = archive
            .file_names()
            .filter(|n| !n.ends_with('/'))
            .map(|n| {
                (
                    n.strip_suffix(".npy").unwrap_or(n).to_string(),
                    n.to_string(),
                )
            })
            .collect();
        Ok(Npz {
            path: path.to_path_buf(),
            archive,
            len,
            members,
        })
    }

    /// The file this archive was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The array names, sorted.
    pub fn keys(&self) -> Vec<String> {
        self.members.keys().cloned().collect()
    }

    /// Whether the archive has an array called `key`.
    pub fn contains(&self, key: &str) -> bool {
        self.members.contains_key(key)
    }

    /// Parses member `key` into its dtype, C-order shape and C-order element bytes.
    ///
    /// Checks, in order and before reading the data: the member's size against
    /// [`MAX_MEMBER_BYTES`] and against what its compressed bytes (at most the archive)
    /// can hold, then the array's shape against the member's size. The data is then read
    /// as it inflates, so memory follows the bytes really present.
    fn raw(&mut self, key: &str) -> Result<RawArray, NpzError> {
        let Some(name) = self.members.get(key).cloned() else {
            return Err(NpzError::Missing {
                path: self.path.clone(),
                key: key.into(),
                available: self.keys(),
            });
        };
        let path = self.path.clone();
        let invalid = |message: String| NpzError::Invalid {
            path: path.clone(),
            key: key.into(),
            message,
        };
        let member_err = |what: &str, source| NpzError::Zip {
            path: path.clone(),
            what: format!("member `{name}` {what}"),
            source,
        };
        let mut file = self
            .archive
            .by_name(&name)
            .map_err(|e| member_err("cannot be opened", e))?;
        let size = file.size();
        if size > MAX_MEMBER_BYTES {
            return Err(invalid(format!(
                "the member claims {size} bytes, more than the {MAX_MEMBER_BYTES} weft reads at once"
            )));
        }
        let packed = file.compressed_size().min(self.len);
        let most = match file.compression() {
            zip::CompressionMethod::Stored => packed,
            _ => packed.saturating_mul(MAX_DEFLATE_RATIO).saturating_add(64),
        };
        if size > most {
            return Err(NpzError::Archive {
                path: path.clone(),
                message: format!(
                    "member `{name}` claims {size} bytes but its {packed} stored bytes hold at most {most}; the file is damaged"
                ),
            });
        }
        let read_err = |e: ReadError| match e {
            ReadError::Invalid(message) => invalid(message),
            // Inflating failed: a damaged stream or a checksum mismatch.
            ReadError::Io(source) => NpzError::Io {
                path: path.clone(),
                source,
            },
        };
        let header = npy::read_header(&mut file, Some(size)).map_err(read_err)?;
        let data = npy::read_data(&mut file, &header, false).map_err(read_err)?;
        let bytes = if header.fortran_order && header.shape.len() > 1 {
            fortran_to_c(&data, &header.shape, header.dtype.size())
        } else {
            data
        };
        Ok(RawArray {
            dtype: header.dtype,
            shape: header.shape,
            bytes,
        })
    }

    /// The dtype (`descr`) and shape of `key`, without converting its data.
    pub fn describe(&mut self, key: &str) -> Result<(String, Vec<usize>), NpzError> {
        let raw = self.raw(key)?;
        Ok((raw.dtype.descr().to_string(), raw.shape))
    }

    /// A floating-point array (`f4` or `f8`) as `f64`, checked against `expected`
    /// (`None` accepts any extent on that axis).
    pub fn floats(
        &mut self,
        key: &str,
        expected: &[Option<usize>],
    ) -> Result<NpzArray<f64>, NpzError> {
        let raw = self.raw(key)?;
        let data = match raw.dtype {
            Dtype::F4 => raw.decode(|b| f64::from(f32::from_le_bytes(arr(b)))),
            Dtype::F8 => raw.decode(|b| f64::from_le_bytes(arr(b))),
            d => return Err(self.dtype_error(key, "a float array ('<f4' or '<f8')", d)),
        };
        self.check_shape(key, expected, &raw.shape)?;
        Ok(NpzArray {
            shape: raw.shape,
            data,
        })
    }

    /// An integer or bool array (any width, signed or not) as `i64`, checked against
    /// `expected`. `u8` values above `i64::MAX` are refused as out of range.
    pub fn ints(
        &mut self,
        key: &str,
        expected: &[Option<usize>],
    ) -> Result<NpzArray<i64>, NpzError> {
        let raw = self.raw(key)?;
        let data = match raw.dtype {
            Dtype::B1 | Dtype::U1 => raw.decode(|b| i64::from(b[0])),
            Dtype::I1 => raw.decode(|b| i64::from(b[0] as i8)),
            Dtype::I2 => raw.decode(|b| i64::from(i16::from_le_bytes(arr(b)))),
            Dtype::U2 => raw.decode(|b| i64::from(u16::from_le_bytes(arr(b)))),
            Dtype::I4 => raw.decode(|b| i64::from(i32::from_le_bytes(arr(b)))),
            Dtype::U4 => raw.decode(|b| i64::from(u32::from_le_bytes(arr(b)))),
            Dtype::I8 => raw.decode(|b| i64::from_le_bytes(arr(b))),
            Dtype::U8 => {
                let wide = raw.decode(|b| u64::from_le_bytes(arr(b)));
                let mut out = Vec::with_capacity(wide.len());
                for (i, &x) in wide.iter().enumerate() {
                    out.push(i64::try_from(x).map_err(|_| NpzError::Invalid {
                        path: self.path.clone(),
                        key: key.into(),
                        message: format!("element {i} is {x}, too large for a 64-bit signed index"),
                    })?);
                }
                out
            }
            d @ (Dtype::F4 | Dtype::F8) => {
                return Err(self.dtype_error(key, "an integer array ('<i4', '<i8', '<u4', …)", d))
            }
        };
        self.check_shape(key, expected, &raw.shape)?;
        Ok(NpzArray {
            shape: raw.shape,
            data,
        })
    }

    fn dtype_error(&self, key: &str, expected: &str, found: Dtype) -> NpzError {
        NpzError::Dtype {
            path: self.path.clone(),
            key: key.into(),
            expected: expected.into(),
            found: found.descr().into(),
        }
    }

    /// Fails unless `found` matches `expected` axis by axis.
    pub fn check_shape(
        &self,
        key: &str,
        expected: &[Option<usize>],
        found: &[usize],
    ) -> Result<(), NpzError> {
        let ok = expected.len() == found.len()
            && expected
                .iter()
                .zip(found)
                .all(|(e, &f)| e.is_none_or(|e| e == f));
        if ok {
            Ok(())
        } else {
            Err(NpzError::Shape {
                path: self.path.clone(),
                key: key.into(),
                expected: expected.to_vec(),
                found: found.to_vec(),
            })
        }
    }
}

fn arr<const N: usize>(b: &[u8]) -> [u8; N] {
    let mut out = [0u8; N];
    out.copy_from_slice(b);
    out
}

/// Builds an `.npz` in memory, then writes it atomically.
///
/// ```
/// use weft_mesh::io::npz::{Npz, NpzWriter};
/// # let path = std::env::temp_dir().join(format!("weft-doc-npz-{}.npz", std::process::id()));
/// let mut w = NpzWriter::new(true);
/// w.add("betas", &[2], &[0.5f32, -1.0])?;
/// w.write(&path)?;
/// let mut npz = Npz::open(&path)?;
/// assert_eq!(npz.floats("betas", &[Some(2)])?.data, vec![0.5, -1.0]);
/// # std::fs::remove_file(&path).ok();
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct NpzWriter {
    compressed: bool,
    members: Vec<(String, Vec<u8>)>,
}

impl NpzWriter {
    /// A new, empty archive; `compressed` deflates the members (`numpy.savez_compressed`),
    /// otherwise they are stored (`numpy.savez`).
    pub fn new(compressed: bool) -> Self {
        NpzWriter {
            compressed,
            members: Vec::new(),
        }
    }

    /// Adds array `key` of `shape` (C order). Fails with
    /// [`io::ErrorKind::InvalidInput`] when `data` does not hold the elements `shape`
    /// describes, or when `key` was already added.
    pub fn add<T: Element>(&mut self, key: &str, shape: &[usize], data: &[T]) -> io::Result<()> {
        let expected = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if expected != Some(data.len()) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "`{key}`: shape {} does not hold {} elements",
                    ShapeDisplay(shape),
                    data.len()
                ),
            ));
        }
        if self.members.iter().any(|(k, _)| k == key) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("`{key}` added twice"),
            ));
        }
        let mut bytes = npy_header(T::DESCR, shape);
        npy::put_all(&mut bytes, data);
        self.members.push((key.to_string(), bytes));
        Ok(())
    }

    /// The archive's bytes.
    pub fn to_bytes(&self) -> io::Result<Vec<u8>> {
        let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
        let method = if self.compressed {
            zip::CompressionMethod::Deflated
        } else {
            zip::CompressionMethod::Stored
        };
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(method)
            .last_modified_time(zip::DateTime::default())
            .large_file(
                self.members
                    .iter()
                    .any(|(_, b)| b.len() as u64 >= u32::MAX as u64),
            );
        for (key, bytes) in &self.members {
            zip.start_file(format!("{key}.npy"), options)
                .map_err(io::Error::other)?;
            zip.write_all(bytes)?;
        }
        Ok(zip.finish().map_err(io::Error::other)?.into_inner())
    }

    /// Writes the archive to `path` atomically.
    pub fn write(&self, path: &Path) -> Result<(), NpzError> {
        let io_err = |source| NpzError::Write {
            path: path.to_path_buf(),
            source,
        };
        let bytes = self.to_bytes().map_err(io_err)?;
        write_atomic(path, |w| w.write_all(&bytes)).map_err(io_err)
    }
}

/// A parsed member: dtype, C-order shape and C-order element bytes.
struct RawArray {
    dtype: Dtype,
    shape: Vec<usize>,
    bytes: Vec<u8>,
}

impl RawArray {
    fn decode<T>(&self, f: impl Fn(&[u8]) -> T) -> Vec<T> {
        self.bytes.chunks_exact(self.dtype.size()).map(f).collect()
    }
}

/// Displays an expected shape, `*` where any extent is accepted: `(24, *)`.
struct ShapePattern<'a>(&'a [Option<usize>]);

impl fmt::Display for ShapePattern<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("(")?;
        for (i, d) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            match d {
                Some(n) => write!(f, "{n}")?,
                None => f.write_str("*")?,
            }
        }
        if self.0.len() == 1 {
            f.write_str(",")?;
        }
        f.write_str(")")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_dir::TestDir;

    fn npy_bytes(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let dict = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}\n",
            if fortran { "True" } else { "False" }
        );
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn zip_of(members: &[(&str, Vec<u8>)]) -> Vec<u8> {
        let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
        for (name, bytes) in members {
            zip.start_file(*name, zip::write::SimpleFileOptions::default())
                .unwrap();
            zip.write_all(bytes).unwrap();
        }
        zip.finish().unwrap().into_inner()
    }

    #[test]
    fn arrays_round_trip_with_every_element_type() {
        let dir = TestDir::new("npz");
        for compressed in [false, true] {
            let path = dir.0.join(format!("a{compressed}.npz"));
            let mut w = NpzWriter::new(compressed);
            w.add("f", &[2, 3], &[1.0f32, 2.0, 3.0, 4.0, 5.0, -0.25])
                .unwrap();
            w.add("d", &[1], &[std::f64::consts::PI]).unwrap();
            w.add("i", &[2, 2], &[-1i64, 4294967295, 0, 7]).unwrap();
            w.add("u", &[3], &[1u32, 2, u32::MAX]).unwrap();
            w.add("b", &[2], &[true, false]).unwrap();
            w.add("s", &[], &[5i32]).unwrap();
            w.write(&path).unwrap();
            let mut npz = Npz::open(&path).unwrap();
            assert_eq!(npz.keys(), vec!["b", "d", "f", "i", "s", "u"]);
            let f = npz.floats("f", &[Some(2), None]).unwrap();
            assert_eq!(f.shape, vec![2, 3]);
            assert_eq!(f.data[5], -0.25);
            assert_eq!(
                npz.floats("d", &[Some(1)]).unwrap().data,
                vec![std::f64::consts::PI]
            );
            assert_eq!(
                npz.ints("i", &[None, None]).unwrap().data,
                vec![-1, 4294967295, 0, 7]
            );
            assert_eq!(
                npz.ints("u", &[Some(3)]).unwrap().data[2],
                i64::from(u32::MAX)
            );
            assert_eq!(npz.ints("b", &[Some(2)]).unwrap().data, vec![1, 0]);
            assert_eq!(npz.ints("s", &[]).unwrap().data, vec![5]);
        }
    }

    #[test]
    fn writing_is_deterministic() {
        let mut w = NpzWriter::new(true);
        w.add("x", &[3], &[1.0f32, 2.0, 3.0]).unwrap();
        assert_eq!(w.to_bytes().unwrap(), w.to_bytes().unwrap());
    }

    #[test]
    fn errors_name_file_key_and_expectation() {
        let dir = TestDir::new("npz-err");
        let path = dir.0.join("model.npz");
        let mut w = NpzWriter::new(false);
        w.add("weights", &[4, 23], &[0.0f32; 92]).unwrap();
        w.add("f", &[2, 3], &[0.5f64; 6]).unwrap();
        w.write(&path).unwrap();
        let mut npz = Npz::open(&path).unwrap();
        let e = npz
            .floats("weights", &[Some(4), Some(24)])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("model.npz") && e.contains("`weights` has shape (4, 23); expected (4, 24)"),
            "{e}"
        );
        let e = npz.ints("f", &[None, Some(3)]).unwrap_err().to_string();
        assert!(
            e.contains("`f` has dtype '<f8'; expected an integer array"),
            "{e}"
        );
        let e = npz
            .floats("v_template", &[None, Some(3)])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no array `v_template` (the file has: f, weights)"),
            "{e}"
        );
        let e = npz.floats("weights", &[None]).unwrap_err().to_string();
        assert!(e.contains("expected (*,)"), "{e}");
    }

    #[test]
    fn fortran_order_is_transposed_to_c_order() {
        // C-order [[1,2,3],[4,5,6]] stored column-major: 1 4 2 5 3 6.
        let data: Vec<u8> = [1.0f64, 4.0, 2.0, 5.0, 3.0, 6.0]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let bytes = zip_of(&[("a.npy", npy_bytes("<f8", true, "(2, 3)", &data))]);
        let mut npz = Npz::from_bytes(bytes, Path::new("f.npz")).unwrap();
        let a = npz.floats("a", &[Some(2), Some(3)]).unwrap();
        assert_eq!(a.data, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        // Three axes: element (i, j, k) at i + 2 j + 4 k in Fortran order.
        let shape = [2usize, 2, 3];
        let f: Vec<u8> = (0..12u8).collect();
        let c = fortran_to_c(&f, &shape, 1);
        for i in 0..2 {
            for j in 0..2 {
                for k in 0..3 {
                    assert_eq!(c[i * 6 + j * 3 + k] as usize, i + 2 * j + 4 * k);
                }
            }
        }
    }

    #[test]
    fn damaged_members_and_archives_are_refused() {
        let e = Npz::from_bytes(b"PK\x03\x04 nonsense".to_vec(), Path::new("x.npz")).unwrap_err();
        assert!(
            e.to_string().starts_with("x.npz: not a readable .npz"),
            "{e}"
        );
        let truncated = zip_of(&[("a.npy", npy_bytes("<f4", false, "(4,)", &[0u8; 12]))]);
        let mut npz = Npz::from_bytes(truncated, Path::new("t.npz")).unwrap();
        let e = npz.floats("a", &[Some(4)]).unwrap_err().to_string();
        assert!(
            e.contains("`a`: the data has 12 bytes but shape (4,)"),
            "{e}"
        );
        let big = zip_of(&[("a.npy", npy_bytes(">f8", false, "(1,)", &[0u8; 8]))]);
        let e = Npz::from_bytes(big, Path::new("b.npz"))
            .unwrap()
            .floats("a", &[None])
            .unwrap_err();
        assert!(e.to_string().contains("big-endian"), "{e}");
        let strings = zip_of(&[("s.npy", npy_bytes("<U3", false, "()", &[0u8; 12]))]);
        let e = Npz::from_bytes(strings, Path::new("s.npz"))
            .unwrap()
            .floats("s", &[])
            .unwrap_err();
        assert!(e.to_string().contains("'<U3' is not supported"), "{e}");
    }

    /// Issue 17 item 7: a small archive whose zip headers claim a huge member, or whose
    /// array header claims a huge array, fails at once without allocating for the claim.
    #[test]
    fn huge_claims_in_a_small_archive_fail_fast() {
        let member = npy_bytes("<f8", false, "(4,)", &[0u8; 32]);
        let mut bytes = zip_of(&[("a.npy", member.clone())]);
        // Patch the uncompressed size in the local (offset 22) and central (offset 24)
        // headers to 3.75 GiB.
        let claim = 0xF000_0000u32.to_le_bytes();
        let local = bytes.windows(4).position(|w| w == b"PK\x03\x04").unwrap();
        bytes[local + 22..local + 26].copy_from_slice(&claim);
        let central = bytes.windows(4).position(|w| w == b"PK\x01\x02").unwrap();
        bytes[central + 24..central + 28].copy_from_slice(&claim);
        let start = std::time::Instant::now();
        let e = Npz::from_bytes(bytes, Path::new("z.npz"))
            .unwrap()
            .floats("a", &[None])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("z.npz: member `a.npy` claims 4026531840 bytes but its"),
            "{e}"
        );
        assert!(e.contains("the file is damaged"), "{e}");

        // A deflated member whose array header claims 2^40 doubles over 4 of data.
        let claim = npy_bytes("<f8", false, "(1099511627776,)", &[0u8; 32]);
        let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
        let deflate = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        zip.start_file("a.npy", deflate).unwrap();
        zip.write_all(&claim).unwrap();
        let bytes = zip.finish().unwrap().into_inner();
        let e = Npz::from_bytes(bytes, Path::new("d.npz"))
            .unwrap()
            .floats("a", &[None])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`a`: the data has 32 bytes but shape (1099511627776,) of '<f8' needs 8796093022208"),
            "{e}"
        );
        assert!(start.elapsed() < std::time::Duration::from_secs(5));
    }

    /// An endless device is refused at once, not read into memory.
    #[cfg(unix)]
    #[test]
    fn an_endless_input_is_not_read_into_memory() {
        let e = Npz::open(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.starts_with("/dev/zero: not a readable .npz"), "{e}");
        let e = crate::export::npy::read_npy(Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("/dev/zero: not a .npy file"), "{e}");
    }

    #[test]
    fn a_bad_writer_call_writes_nothing() {
        let mut w = NpzWriter::new(false);
        assert!(w.add("x", &[2, 2], &[1.0f32; 3]).is_err());
        w.add("x", &[1], &[1.0f32]).unwrap();
        assert!(w.add("x", &[1], &[1.0f32]).is_err());
    }
}
