//! The Python package (`crates/weft-py`, `import weft`) passes its pytest suite, with
//! this test's `weft` binary for the test that trains a run.
//!
//! Uses the environment `.ci/run` makes: `crates/weft-py/.venv` with the package
//! installed (`pip install "./crates/weft-py[test]"`). Without that directory the test
//! prints how to make it and passes, so a machine without Python still runs the rest of
//! the suite; with it, a package that does not import fails the test.

use std::path::Path;
use std::process::Command;

#[test]
fn the_python_package_passes_its_tests() {
    let package = Path::new(env!("CARGO_MANIFEST_DIR")).join("../weft-py");
    let python = package.join(".venv/bin/python");
    if !python.is_file() {
        eprintln!(
            "SKIPPED Python package tests: run `python3 -m venv {0}/.venv && {0}/.venv/bin/pip install \"{0}[test]\"`",
            package.display()
        );
        return;
    }
    // An environment that exists must hold a package that imports: a broken build is a
    // failure, not a skip.
    let import = Command::new(&python)
        .args(["-c", "import weft, pytest"])
        .output()
        .expect("run python");
    assert!(
        import.status.success(),
        "{} cannot import weft and pytest: {}",
        python.display(),
        String::from_utf8_lossy(&import.stderr)
    );
    let out = Command::new(&python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(package.join("tests"))
        .env("WEFT_BIN", env!("CARGO_BIN_EXE_weft"))
        .output()
        .expect("run pytest");
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "pytest failed");
    assert!(text.contains(" passed"), "{text}");
    assert!(!text.contains("skipped"), "a test was skipped: {text}");
}
