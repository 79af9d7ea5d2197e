//! End-to-end tests of `weft mesh …` through the real binary.

use std::path::{Path, PathBuf};

mod common;
use common::{scratch, stderr, stdout, weft};

fn malformed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/malformed")
}

#[test]
fn hierarchy_json_of_the_builtin_garment_halves_each_level() {
    let o = weft(&["mesh", "hierarchy", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("one JSON object");
    let levels = v["levels"].as_array().expect("levels array");
    assert_eq!(levels.len(), 3);
    let counts: Vec<u64> = levels
        .iter()
        .map(|l| l["vertices"].as_u64().unwrap())
        .collect();
    assert_eq!(counts[..2], [4000, 2000]);
    assert!((900..=1100).contains(&counts[2]), "{counts:?}");
    assert!(levels.iter().all(|l| l["components"] == 1));
    assert!(levels[0].get("kept").is_none());
    for l in 1..3 {
        let kept = levels[l]["kept"].as_array().unwrap();
        assert_eq!(kept.len() as u64, counts[l]);
        assert!(kept.iter().all(|k| k.as_u64().unwrap() < counts[l - 1]));
    }
}

#[test]
fn hierarchy_writes_one_ply_per_level_that_reads_back() {
    let dir = scratch("hierarchy_out");
    let o = weft(&[
        "mesh",
        "hierarchy",
        "--levels",
        "2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let level0 = weft_mesh::io::read_mesh(&dir.join("level_0.ply")).expect("level 0 is a mesh");
    assert_eq!(level0.vertex_count(), 4000);
    assert!(dir.join("level_1.ply").is_file());
    assert!(!dir.join("level_2.ply").exists());
}

#[test]
fn info_reports_counts_of_a_valid_obj() {
    let dir = scratch("info_ok");
    let path = dir.join("tube.obj");
    weft_mesh::io::write_obj(&path, &weft_mesh::primitives::cylinder(4, 6, 1.0, 0.5)).unwrap();
    let o = weft(&["mesh", "info", path.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["vertices"], 24);
    assert_eq!(v["faces"], 36);
    assert_eq!(v["components"], 1);
    assert_eq!(v["boundary_loops"], 2);
    assert_eq!(v["findings"].as_array().unwrap().len(), 0);
}

#[test]
fn every_command_refuses_every_malformed_file_in_one_line() {
    let mut checked = 0;
    for entry in std::fs::read_dir(malformed_dir()).expect("tests/malformed exists") {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        // The mesh files are at the top; subdirectories hold the other readers' inputs
        // (all of them are run by malformed_cli.rs).
        if !(name.ends_with(".obj") || name.ends_with(".ply")) {
            continue;
        }
        for args in [
            vec!["mesh", "info", path.to_str().unwrap()],
            vec!["mesh", "hierarchy", path.to_str().unwrap(), "--json"],
        ] {
            let o = weft(&args);
            let err = stderr(&o);
            assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
            if name == "non_manifold.obj" {
                // Readable, but `info` must say what is wrong with it.
                assert!(o.status.success(), "{args:?}: {err}");
                if args[1] == "info" {
                    assert!(stdout(&o).contains("non-manifold"), "{}", stdout(&o));
                }
                continue;
            }
            assert!(!o.status.success(), "{args:?} accepted {name}");
            assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
            assert!(
                err.starts_with("error: ") && err.contains(&name),
                "{args:?}: {err}"
            );
            assert!(o.stdout.is_empty(), "{args:?} printed to stdout");
        }
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} malformed files");
}

#[test]
fn unreadable_and_unknown_files_are_refused() {
    let o = weft(&["mesh", "info", "/nonexistent/garment.obj"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("/nonexistent/garment.obj"));
    let dir = scratch("unknown_ext");
    let path = dir.join("garment.stl");
    std::fs::write(&path, b"solid x").unwrap();
    let o = weft(&["mesh", "info", path.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("garment.stl"), "{}", stderr(&o));
}

#[test]
fn unwritable_output_leaves_nothing_behind() {
    let dir = scratch("unwritable");
    let blocker = dir.join("file");
    std::fs::write(&blocker, b"not a directory").unwrap();
    let out = blocker.join("levels");
    let o = weft(&["mesh", "hierarchy", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("levels"), "{}", stderr(&o));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
}

#[test]
fn zero_levels_is_a_usage_error() {
    let o = weft(&["mesh", "hierarchy", "--levels", "0"]);
    assert_eq!(o.status.code(), Some(2));
}
