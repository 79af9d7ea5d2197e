//! The `.glb` files weft writes pass the Khronos glTF validator with no errors.
//!
//! Runs `node tools/gltf-validator/validate.js` (the npm package `gltf-validator`, pinned
//! in `tools/gltf-validator/package-lock.json`; install it with
//! `npm ci --prefix tools/gltf-validator`). When `node` or the package is missing the test
//! prints why and passes, so a machine without Node still runs the rest of the suite.

use std::path::{Path, PathBuf};
use std::process::Command;

use weft_mesh::export::gltf::{write_glb, GlbOptions};
use weft_mesh::export::AnimatedMesh;

mod common;
use common::{frames_of, Scene};

fn validator() -> Option<(PathBuf, PathBuf)> {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/gltf-validator");
    let script = tools.join("validate.js");
    let package = tools.join("node_modules/gltf-validator/package.json");
    let node_ok = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !node_ok {
        eprintln!("SKIPPED glTF validation: `node` is not on PATH (install Node.js to run it)");
        return None;
    }
    if !package.is_file() {
        eprintln!(
            "SKIPPED glTF validation: the validator is not installed; run `npm ci --prefix {}`",
            tools.display()
        );
        return None;
    }
    Some((PathBuf::from("node"), script))
}

fn validate(node: &Path, script: &Path, glb: &Path) {
    let out = Command::new(node)
        .arg(script)
        .arg(glb)
        .output()
        .expect("run node");
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "the glTF validator found errors in {}",
        glb.display()
    );
    assert!(text.contains(" 0 errors, 0 warnings"), "{text}");
}

#[test]
fn glb_files_pass_the_khronos_validator() {
    let Some((node, script)) = validator() else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("weft-gltf-validator-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    // The built-in garment animated over 24 frames, over a body animated with it.
    let scene = Scene::new(24);
    let both = dir.join("garment_body.glb");
    let options = GlbOptions {
        fps: 30.0,
        normals: true,
    };
    write_glb(&both, &scene.meshes(), options).unwrap();
    validate(&node, &script, &both);

    // Without normals or UVs, with a static body, and a single static frame.
    let still = frames_of(&scene.body, 1, 0.0);
    let variants = dir.join("static_body.glb");
    let garment = AnimatedMesh {
        uvs: None,
        ..scene.garment_mesh(&scene.uvs)
    };
    let options = GlbOptions {
        fps: 24.0,
        normals: false,
    };
    write_glb(&variants, &[garment, scene.body_mesh(&still)], options).unwrap();
    validate(&node, &script, &variants);
    let single = dir.join("single.glb");
    write_glb(&single, &[scene.body_mesh(&still)], GlbOptions::default()).unwrap();
    validate(&node, &script, &single);

    let _ = std::fs::remove_dir_all(&dir);
}
