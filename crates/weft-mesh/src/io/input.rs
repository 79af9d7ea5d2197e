//! Whole-file reads whose memory is bounded by the input.
//!
//! `std::fs::read` sizes its buffer from the file's metadata and then reads to the end.
//! For a regular file that is the file; for a pipe or a device (`/dev/zero`, a FIFO, a
//! process substitution) there is no end, and the buffer grows until memory runs out.
//! Every weft reader that takes a whole file goes through [`read_input`]: a regular
//! file is read as it is (its size is the bound), a stream is read up to
//! [`MAX_STREAM_BYTES`] and refused beyond, before that much more is allocated.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// The most bytes read from something that is not a regular file (a pipe, a device).
/// Larger inputs are refused with a message that says to save them to a file first.
pub const MAX_STREAM_BYTES: u64 = 256 << 20;

/// The whole of `path`: a regular file as it is, a stream up to [`MAX_STREAM_BYTES`].
/// A longer stream is an error of kind [`io::ErrorKind::FileTooLarge`].
pub fn read_input(path: &Path) -> io::Result<Vec<u8>> {
    read_input_bounded(path, MAX_STREAM_BYTES)
}

/// [`read_input`] as UTF-8 text; invalid UTF-8 is an [`io::ErrorKind::InvalidData`] error.
pub fn read_input_to_string(path: &Path) -> io::Result<String> {
    String::from_utf8(read_input(path)?).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

fn read_input_bounded(path: &Path, stream_limit: u64) -> io::Result<Vec<u8>> {
    let file = File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_dir() {
        return Err(io::Error::new(
            io::ErrorKind::IsADirectory,
            "is a directory; expected a file",
        ));
    }
    if meta.is_file() {
        let mut bytes = Vec::with_capacity(meta.len() as usize);
        // `take`: a file that grows while it is read is read as it was when opened.
        file.take(meta.len()).read_to_end(&mut bytes)?;
        return Ok(bytes);
    }
    let mut bytes = Vec::new();
    file.take(stream_limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > stream_limit {
        return Err(io::Error::new(
            io::ErrorKind::FileTooLarge,
            format!(
                "not a regular file and longer than {} MiB (an endless device?); save the input to a file first",
                stream_limit >> 20
            ),
        ));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_file_is_read_whole() {
        let dir = std::env::temp_dir().join(format!("weft-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.txt");
        std::fs::write(&path, "hello").unwrap();
        assert_eq!(read_input(&path).unwrap(), b"hello");
        assert_eq!(read_input_to_string(&path).unwrap(), "hello");
        std::fs::write(&path, [0xffu8, 0xfe]).unwrap();
        let e = read_input_to_string(&path).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        let e = read_input(&dir).unwrap_err();
        assert!(e.to_string().contains("is a directory"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 17 item 7: an endless device is refused after the bound, not read until
    /// memory runs out.
    #[cfg(unix)]
    #[test]
    fn an_endless_device_is_refused_at_the_bound() {
        let e = read_input_bounded(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::FileTooLarge);
        assert!(e.to_string().contains("save the input to a file"), "{e}");
        assert!(read_input(Path::new("/dev/null")).unwrap().is_empty());
    }
}
