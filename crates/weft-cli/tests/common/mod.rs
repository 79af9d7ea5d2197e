//! Helpers every CLI test file shares: run the binary, read its output, make scratch
//! directories.

// Each test file is its own crate and uses a different subset of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `weft` binary under test with `args`.
pub fn weft(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(args)
        .output()
        .expect("the weft binary runs")
}

/// Its standard output, lossily decoded.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Its standard error, lossily decoded.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh, empty directory under the target dir, named after the test file and `name`
/// so that test files never share one.
pub fn scratch(name: &str) -> PathBuf {
    let dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{}-{name}", env!("CARGO_CRATE_NAME")));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// `weft garment generate --kind KIND --vertices N --seed SEED --out PATH`, which must
/// succeed: the garment most CLI tests start from.
pub fn garment(path: &Path, kind: &str, vertices: usize, seed: u64) {
    let (n, seed) = (vertices.to_string(), seed.to_string());
    let o = weft(&[
        "garment",
        "generate",
        "--kind",
        kind,
        "--vertices",
        &n,
        "--seed",
        &seed,
        "--out",
        s(path),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}
