//! `weft demo` through the real binary. The whole pipeline is tested in CI by
//! weft-eval's `tests/demo.rs` (same code, stand-in simulator, seconds); here: the
//! command line, a clean failure, and — ignored, about a minute with the real simulator —
//! `weft demo --quick` end to end.

use std::path::Path;

mod common;
use common::{stderr, stdout, weft};

#[test]
fn help_names_the_default_directory() {
    let o = weft(&["demo", "--help"]);
    assert!(o.status.success());
    let text = stdout(&o);
    assert!(text.contains("[default: weft-demo]"), "{text}");
    let top = weft(&["--help"]);
    let top = stdout(&top);
    let first = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .nth(1)
        .unwrap_or_default();
    assert!(first.trim_start().starts_with("demo"), "{top}");
}

#[test]
fn an_output_path_that_is_a_file_fails_in_one_line() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("demo_cli_file");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("taken");
    std::fs::write(&file, "not a directory").unwrap();
    let o = weft(&["demo", "--quick", "--out", file.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert_eq!(
        e.lines().filter(|l| l.starts_with("error")).count(),
        1,
        "{e}"
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "not a directory");
}

#[test]
#[ignore = "real simulation: about a minute in a debug build"]
fn quick_demo_end_to_end() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("demo_cli_quick");
    let _ = std::fs::remove_dir_all(&dir);
    let o = weft(&["demo", "--quick", "--out", dir.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    for stage in ["[1/5]", "[2/5]", "[3/5]", "[4/5]", "[5/5]"] {
        assert!(e.contains(stage), "{e}");
    }
    let out = stdout(&o);
    assert!(out.contains("report:"), "{out}");
    assert!(dir.join("report.html").is_file());
}
