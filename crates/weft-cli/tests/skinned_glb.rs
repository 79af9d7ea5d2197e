//! Issue 18 item 1: `weft simulate --glb` writes a skinned glTF (the body's skeleton
//! animated, body and garment skinned, per-frame corrective morph targets) that passes
//! the Khronos validator and that Blender's importer plays frame for frame as weft
//! simulated it.
//!
//! The validator (`tools/gltf-validator`, npm) and Blender (`tools/blender/.venv`, PyPI
//! bpy) are installed by `.ci/run`; each check prints `SKIPPED …` and passes without its
//! tool.

use std::path::Path;
use std::process::Command;

mod common;
use common::{garment, s, scratch, stderr, weft};

#[test]
fn a_skinned_glb_validates_and_plays_in_blender_as_simulated() {
    let dir = scratch("skinned");
    let g = dir.join("skirt.obj");
    garment(&g, "skirt", 300, 1);
    let walk = dir.join("walk.npz");
    let o = weft(&[
        "motion",
        "generate",
        "--kind",
        "walk",
        "--frames",
        "4",
        "--out",
        s(&walk),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.join("sim");
    let o = weft(&[
        "simulate",
        "--garment",
        s(&g),
        "--motion",
        s(&walk),
        "--warmup",
        "2",
        "--substeps",
        "2",
        "--out",
        s(&out),
        "--glb",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let glb = out.join("scene.glb");
    let scene = weft_mesh::export::gltf::read_glb(&glb).expect("a readable .glb");
    let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["garment", "body"]);
    let bodies = dir.join("body");
    let o = weft(&[
        "body",
        "pose",
        "--motion",
        s(&walk),
        "--all-frames",
        "--out",
        s(&bodies),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));

    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let validator = root.join("tools/gltf-validator");
    if validator
        .join("node_modules/gltf-validator/package.json")
        .is_file()
    {
        let o = Command::new("node")
            .arg(validator.join("validate.js"))
            .arg(&glb)
            .output()
            .expect("node");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success() && text.contains(" 0 errors, 0 warnings"),
            "{text}"
        );
    } else {
        eprintln!("SKIPPED glTF validation: run `npm ci --prefix tools/gltf-validator`");
    }

    let python = root.join("tools/blender/.venv/bin/python");
    if !python.is_file() {
        eprintln!("SKIPPED Blender playback: run `python3.11 -m venv tools/blender/.venv && tools/blender/.venv/bin/pip install -r tools/blender/requirements.txt`");
        return;
    }
    let o = Command::new(&python)
        .arg(root.join("tools/blender/check_skinned.py"))
        .arg(&glb)
        .arg(out.join("frames.npy"))
        .arg(&bodies)
        .output()
        .expect("run Blender");
    let text = String::from_utf8_lossy(&o.stdout);
    eprintln!(
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
            .lines()
            .filter(|l| !l.contains("INFO"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    assert!(
        o.status.success(),
        "Blender does not play the frames weft wrote: {text}"
    );
}
