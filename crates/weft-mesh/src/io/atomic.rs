//! Atomic file output: a reader never sees a half-written file.
//!
//! The content goes to a temporary file in the destination's directory (same file
//! system, so the final `rename` is atomic), which is flushed and synced before it
//! replaces the destination. On any error — or a panic inside the writer — the temporary
//! file is removed and the destination is left as it was. Every crate that writes an
//! output (meshes, shards, checkpoints, pictures) goes through [`write_atomic`].

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes temporary files of concurrent writes from one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// How many temporary names to try before giving up (only collisions with files left by
/// other processes make a second try necessary).
const MAX_ATTEMPTS: u32 = 64;

/// Writes `path` atomically: `write` fills a buffered writer on a temporary file beside
/// `path`, which then replaces `path` by a rename. Missing parent directories are
/// created.
///
/// Errors are those of the operating system or of `write`; they carry no path, so wrap
/// them with the destination when reporting (see [`crate::MeshError::Io`]). Callers with
/// non-I/O failures inside `write` can return them as [`io::Error::other`].
///
/// ```
/// # let dir = std::env::temp_dir();
/// # let path = dir.join(format!("weft-doc-atomic-{}.txt", std::process::id()));
/// weft_mesh::io::write_atomic(&path, |w| writeln!(w, "hello"))?;
/// assert_eq!(std::fs::read_to_string(&path)?, "hello\n");
/// # std::fs::remove_file(&path)?;
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn write_atomic<F>(path: &Path, write: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let (file, temp) = create_temp(path)?;
    // Removes the temporary file unless the rename below succeeded, also on panic.
    let mut guard = TempGuard(Some(temp));
    let mut writer = BufWriter::new(file);
    write(&mut writer)?;
    writer.flush()?;
    let file = writer
        .into_inner()
        .map_err(io::IntoInnerError::into_error)?;
    file.sync_all()?;
    drop(file);
    let temp = guard.0.as_deref().unwrap_or(path);
    fs::rename(temp, path)?;
    guard.0 = None;
    sync_parent(path);
    Ok(())
}

/// Creates a fresh temporary file next to `path`, named `.NAME.PID.N.tmp`.
fn create_temp(path: &Path) -> io::Result<(File, PathBuf)> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            "the output path names no file (expected a path like out/mesh.ply)",
        )
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // Missing parent directories are created, as for every weft output.
    fs::create_dir_all(dir)?;
    let mut last = None;
    for _ in 0..MAX_ATTEMPTS {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(name);
        temp_name.push(format!(".{}.{n}.tmp", std::process::id()));
        let temp = dir.join(temp_name);
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(file) => return Ok((file, temp)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| io::Error::other("could not create a temporary file")))
}

/// Makes the rename durable where the platform allows syncing a directory. Best effort:
/// the file's content is already synced, and some file systems refuse directory syncs.
fn sync_parent(path: &Path) {
    #[cfg(unix)]
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = path;
}

/// Deletes the temporary file when dropped while still armed.
struct TempGuard(Option<PathBuf>);

impl Drop for TempGuard {
    fn drop(&mut self) {
        if let Some(temp) = self.0.take() {
            let _ = fs::remove_file(temp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_dir::TestDir;

    #[test]
    fn writes_and_replaces() {
        let dir = TestDir::new("atomic");
        let path = dir.0.join("out.txt");
        write_atomic(&path, |w| w.write_all(b"one")).unwrap();
        write_atomic(&path, |w| w.write_all(b"two")).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"two");
        assert_eq!(dir.entries(), vec!["out.txt"]);
    }

    #[test]
    fn failed_write_leaves_old_content_and_no_temp() {
        let dir = TestDir::new("atomic-fail");
        let path = dir.0.join("out.txt");
        fs::write(&path, b"old").unwrap();
        let err = write_atomic(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "boom");
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert_eq!(dir.entries(), vec!["out.txt"]);
    }

    #[test]
    fn panic_in_writer_removes_temp() {
        let dir = TestDir::new("atomic-panic");
        let path = dir.0.join("out.txt");
        let result = std::panic::catch_unwind(|| {
            let _ = write_atomic(&path, |_| panic!("writer panicked"));
        });
        assert!(result.is_err());
        assert!(dir.entries().is_empty());
    }

    #[test]
    fn missing_parents_are_created_but_not_through_a_file() {
        let dir = TestDir::new("atomic-missing");
        let path = dir.0.join("no/such/dir/out.txt");
        write_atomic(&path, |w| w.write_all(b"x")).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"x");
        let under_file = path.join("out.txt");
        assert!(write_atomic(&under_file, |w| w.write_all(b"x")).is_err());
        assert_eq!(fs::read(&path).unwrap(), b"x");
    }

    #[test]
    fn a_path_without_a_file_name_is_an_error() {
        let err = write_atomic(Path::new("/"), |w| w.write_all(b"x")).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    }
}
