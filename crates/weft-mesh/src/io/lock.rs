//! Advisory locks on output directories, so that two weft processes never write one run
//! or one dataset at once, and the clean-up of temporary files that killed writers left.
//!
//! The lock is the operating system's (`flock` on Unix, `LockFileEx` on Windows, through
//! std's `File::try_lock`), held on a small file in the directory: it goes away with the
//! process, so a killed writer never leaves a directory stuck. The exclusive holder
//! writes who it is into the file, for the message a second writer gets. Cluster jobs
//! that share a directory (one dataset, several shard jobs) take the directory's lock
//! shared and their own job's lock exclusive.

use std::fs::{self, File, OpenOptions, TryLockError};
use std::io::{self, Read, Seek, Write};
use std::path::{Path, PathBuf};

/// The lock file of a directory.
pub const LOCK_FILE: &str = ".weft.lock";

/// How a directory is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// One writer, no one else (a training run, a whole dataset).
    Exclusive,
    /// Writers that coordinate among themselves (shard jobs), excluding an exclusive one.
    Shared,
}

/// A held lock; released when dropped (or when the process ends, however it ends).
#[derive(Debug)]
pub struct DirLock {
    _file: File,
}

/// Why a lock could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another process holds it.
    #[error(
        "{} is in use by another weft process ({holder}); wait for it to finish, or write to \
         another directory",
        .dir.display()
    )]
    Busy {
        /// The directory.
        dir: PathBuf,
        /// What the holder wrote about itself (command and pid), or `unknown holder`.
        holder: String,
    },
    /// The lock file could not be created or locked.
    #[error("{}: cannot lock the directory", .path.display())]
    Io {
        /// The lock file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: io::Error,
    },
}

impl DirLock {
    /// Locks `dir` (created if missing) through its lock file `name` ([`LOCK_FILE`] for the
    /// directory as a whole). `holder` describes this process in the message another
    /// writer gets, e.g. `weft train`.
    pub fn acquire(
        dir: &Path,
        name: &str,
        access: Access,
        holder: &str,
    ) -> Result<DirLock, LockError> {
        let path = dir.join(name);
        let io_err = |source| LockError::Io {
            path: path.clone(),
            source,
        };
        fs::create_dir_all(dir).map_err(io_err)?;
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io_err)?;
        let locked = match access {
            Access::Exclusive => file.try_lock(),
            Access::Shared => file.try_lock_shared(),
        };
        match locked {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut text = String::new();
                // The holder may be rewriting it; an empty or unreadable text is fine.
                let _ = file.read_to_string(&mut text);
                let text = text.trim();
                return Err(LockError::Busy {
                    dir: dir.to_path_buf(),
                    holder: if text.is_empty() {
                        "unknown holder".into()
                    } else {
                        text.to_string()
                    },
                });
            }
            Err(TryLockError::Error(e)) => return Err(io_err(e)),
        }
        if access == Access::Exclusive {
            file.set_len(0).map_err(io_err)?;
            file.rewind().map_err(io_err)?;
            writeln!(file, "{holder}, pid {}", std::process::id()).map_err(io_err)?;
        }
        Ok(DirLock { _file: file })
    }
}

/// Whether `name` is one of [`crate::io::write_atomic`]'s temporary files
/// (`.NAME.PID.N.tmp`).
pub fn is_temp_name(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('.').and_then(|n| n.strip_suffix(".tmp")) else {
        return false;
    };
    let mut parts = rest.rsplitn(3, '.');
    let digits =
        |s: Option<&str>| s.is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
    let (n, pid, file) = (parts.next(), parts.next(), parts.next());
    digits(n) && digits(pid) && file.is_some_and(|f| !f.is_empty())
}

/// Removes the temporary files of interrupted atomic writes in `dir` and its
/// subdirectories (to `depth` levels); returns how many and their bytes. Call it only
/// while holding `dir` exclusively: then no other writer can own them.
pub fn remove_stale_temps(dir: &Path, depth: usize) -> io::Result<(usize, u64)> {
    let mut removed = (0usize, 0u64);
    let entries = match fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(removed),
        Err(e) => return Err(e),
    };
    for entry in entries {
        let entry = entry?;
        let kind = entry.file_type()?;
        let path = entry.path();
        if kind.is_dir() && depth > 0 {
            let (n, bytes) = remove_stale_temps(&path, depth - 1)?;
            removed = (removed.0 + n, removed.1 + bytes);
        } else if kind.is_file() && entry.file_name().to_str().is_some_and(is_temp_name) {
            let bytes = entry.metadata().map_or(0, |m| m.len());
            match fs::remove_file(&path) {
                Ok(()) => removed = (removed.0 + 1, removed.1 + bytes),
                Err(e) if e.kind() == io::ErrorKind::NotFound => {}
                Err(e) => return Err(e),
            }
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("weft-lock-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn a_second_writer_is_refused_naming_the_holder() {
        let dir = temp_dir("excl");
        let held = DirLock::acquire(&dir, LOCK_FILE, Access::Exclusive, "weft train").unwrap();
        let e = DirLock::acquire(&dir, LOCK_FILE, Access::Exclusive, "weft train").unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, LockError::Busy { .. }), "{msg}");
        assert!(msg.contains("weft train, pid"), "{msg}");
        assert!(DirLock::acquire(&dir, LOCK_FILE, Access::Shared, "job").is_err());
        drop(held);
        // Released with the holder: shared holders coexist, and exclude an exclusive one.
        let a = DirLock::acquire(&dir, LOCK_FILE, Access::Shared, "job 0").unwrap();
        let b = DirLock::acquire(&dir, LOCK_FILE, Access::Shared, "job 1").unwrap();
        assert!(DirLock::acquire(&dir, LOCK_FILE, Access::Exclusive, "whole").is_err());
        drop((a, b));
        DirLock::acquire(&dir, LOCK_FILE, Access::Exclusive, "whole").unwrap();
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn stale_temporary_files_are_recognised_and_removed() {
        assert!(is_temp_name(".step-000003.bpk.4242.7.tmp"));
        assert!(is_temp_name(".manifest.json.1.0.tmp"));
        for name in [
            "step-000003.bpk",
            ".weft.lock",
            ".x.tmp",
            ".a.b.tmp",
            "a.1.2.tmp",
        ] {
            assert!(!is_temp_name(name), "{name}");
        }
        let dir = temp_dir("stale");
        fs::create_dir_all(dir.join("checkpoints")).unwrap();
        fs::write(
            dir.join("checkpoints/.step-000003.bpk.4242.7.tmp"),
            [0u8; 100],
        )
        .unwrap();
        fs::write(dir.join(".config.toml.4242.8.tmp"), [0u8; 10]).unwrap();
        fs::write(dir.join("checkpoints/step-000003.bpk"), [0u8; 5]).unwrap();
        assert_eq!(remove_stale_temps(&dir, 0).unwrap(), (1, 10));
        assert_eq!(remove_stale_temps(&dir, 2).unwrap(), (1, 100));
        assert!(dir.join("checkpoints/step-000003.bpk").exists());
        fs::remove_dir_all(&dir).unwrap();
    }
}
