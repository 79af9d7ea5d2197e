//! The USD files weft writes open in Pixar's own library, pass its validators (what
//! `usdchecker` runs) and hold weft's frames exactly.
//!
//! Runs `tools/usd/check_usd.py` with the Python of `tools/usd/.venv` (PyPI `usd-core`,
//! pinned in `tools/usd/requirements.txt`; `.ci/run` installs it). When that environment
//! is missing the test prints how to make it and passes, so a machine without Python
//! still runs the rest of the suite.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use weft_mesh::export::npy::write_npy;
use weft_mesh::export::{write_usd, Frames};

mod common;
use common::{frames_of, Scene};

fn usd_python() -> Option<(PathBuf, PathBuf)> {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/usd");
    let python = tools.join(".venv/bin/python");
    if !python.is_file() {
        eprintln!(
            "SKIPPED USD check: usd-core is not installed; run `python3 -m venv {0}/.venv && {0}/.venv/bin/pip install -r {0}/requirements.txt`",
            tools.display()
        );
        return None;
    }
    Some((python, tools.join("check_usd.py")))
}

fn save_npy(path: &Path, frames: &Frames) {
    let shape = [frames.frame_count(), frames.vertex_count(), 3];
    write_npy(path, &shape, frames.positions().as_flattened()).unwrap();
}

#[test]
fn usd_files_open_in_pixars_usd_and_hold_the_frames() {
    let Some((python, script)) = usd_python() else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("weft-usd-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    let scene = Scene::new(24);
    let usda = dir.join("scene.usda");
    write_usd(&usda, &scene.meshes(), 24.0).unwrap();
    // A static body alone, under the `.usd` extension.
    let still = frames_of(&scene.body, 1, 0.0);
    let usd = dir.join("static_body.usd");
    write_usd(&usd, &[scene.body_mesh(&still)], 30.0).unwrap();
    save_npy(&dir.join("garment.npy"), &scene.garment_frames);
    save_npy(&dir.join("body.npy"), &scene.body_frames);

    let out = Command::new(&python)
        .arg(&script)
        .arg("--json")
        .arg(&usda)
        .arg("--points")
        .arg(format!(
            "/weft/garment={}",
            dir.join("garment.npy").display()
        ))
        .arg("--points")
        .arg(format!("/weft/body={}", dir.join("body.npy").display()))
        .output()
        .expect("run the USD checker");
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "the USD check failed");
    let s: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    assert_eq!(s["problems"], serde_json::json!([]));
    assert_eq!(s["up_axis"], "Y");
    assert_eq!(s["meters_per_unit"], 1.0);
    assert_eq!(s["time_codes_per_second"], 24.0);
    assert_eq!(
        (s["start"].as_f64(), s["end"].as_f64()),
        (Some(0.0), Some(23.0))
    );
    assert_eq!(s["default_prim"], "/weft");
    let g = &s["meshes"]["/weft/garment"];
    assert_eq!(g["points"], scene.garment.vertex_count());
    assert_eq!(g["faces"], scene.garment.faces.len());
    assert_eq!(g["time_samples"], 24);
    assert_eq!(
        (g["st"].as_str(), g["st_indexed"].as_bool()),
        (Some("faceVarying"), Some(true))
    );
    assert_eq!(s["meshes"]["/weft/body"]["st"], Value::Null);

    let out = Command::new(&python)
        .arg(&script)
        .arg("--json")
        .arg(&usd)
        .output()
        .expect("run the USD checker");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let s: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    assert_eq!(s["meshes"]["/weft/body"]["time_samples"], 0);
    assert_eq!(
        s["meshes"]["/weft/body"]["points"],
        scene.body.vertex_count()
    );

    // The checker itself fails on a mismatch, so the comparison above can fail.
    let out = Command::new(&python)
        .arg(&script)
        .arg(&usda)
        .arg("--points")
        .arg(format!("/weft/garment={}", dir.join("body.npy").display()))
        .output()
        .expect("run the USD checker");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("points, expected"));

    let _ = std::fs::remove_dir_all(&dir);
}
