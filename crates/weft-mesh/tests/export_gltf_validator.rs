//! The `.glb` files weft writes pass the Khronos glTF validator with no errors.
//!
//! Runs `node tools/gltf-validator/validate.js` (the npm package `gltf-validator`, pinned
//! in `tools/gltf-validator/package-lock.json`; install it with
//! `npm ci --prefix tools/gltf-validator`). When `node` or the package is missing the test
//! prints why and passes, so a machine without Node still runs the rest of the suite.

use std::path::{Path, PathBuf};
use std::process::Command;

use weft_mesh::export::gltf::{write_glb, write_skinned_glb, GlbOptions, Skeleton, SkinBinding};
use weft_mesh::export::AnimatedMesh;
use weft_mesh::primitives::cylinder;

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

    // Skinned: a three-joint chain bending a cylinder, with per-frame correctives and
    // UVs (seam split carries joints and weights), and the same without correctives.
    let tube = cylinder(12, 16, 0.05, 0.05);
    let rest: Vec<[f32; 3]> = tube.positions.iter().map(|p| p.map(|c| c as f32)).collect();
    let (low, high) = rest
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), p| (a.min(p[1]), b.max(p[1])));
    let joints_at = [
        [0.0, high, 0.0],
        [0.0, 0.5 * (low + high), 0.0],
        [0.0, low, 0.0f32],
    ];
    let (joints, weights): (Vec<[u16; 4]>, Vec<[f32; 4]>) = rest
        .iter()
        .map(|p| {
            let s = ((high - p[1]) / (high - low)).clamp(0.0, 1.0);
            if s < 0.5 {
                ([0, 1, 0, 0], [1.0 - 2.0 * s, 2.0 * s, 0.0, 0.0])
            } else {
                ([1, 2, 0, 0], [2.0 - 2.0 * s, 2.0 * s - 1.0, 0.0, 0.0])
            }
        })
        .unzip();
    let t = 10;
    let rotations: Vec<Vec<[f32; 4]>> = (0..t)
        .map(|k| {
            let half = 0.06 * k as f32;
            vec![
                [0.0, 0.0, 0.0, 1.0],
                [0.0, 0.0, half.sin(), half.cos()],
                [0.0, 0.0, 0.0, 1.0],
            ]
        })
        .collect();
    let root: Vec<[f32; 3]> = (0..t).map(|k| [0.01 * k as f32, high, 0.0]).collect();
    let names = ["upper", "elbow", "wrist"];
    let skeleton = Skeleton {
        names: &names,
        parents: &[None, Some(0), Some(1)],
        rest: &joints_at,
        rotations: &rotations,
        root: &root,
    };
    let mut correctives = weft_mesh::export::Frames::with_vertex_count(rest.len()).unwrap();
    for k in 0..t {
        let bulge = 0.002 * k as f32;
        let f: Vec<[f32; 3]> = rest
            .iter()
            .map(|p| [p[0] * (1.0 + bulge), p[1], p[2] * (1.0 + bulge)])
            .collect();
        correctives.push_frame(&f).unwrap();
    }
    let uvs = common::seamed_uvs(&tube);
    let binding = SkinBinding {
        rest: &rest,
        joints: &joints,
        weights: &weights,
    };
    let skinned = dir.join("skinned.glb");
    let mesh = AnimatedMesh {
        name: "sleeve",
        faces: &tube.faces,
        uvs: Some(&uvs),
        frames: &correctives,
        color: weft_mesh::export::GARMENT_COLOR,
    };
    write_skinned_glb(
        &skinned,
        &skeleton,
        &[mesh],
        &[binding],
        GlbOptions::default(),
    )
    .unwrap();
    validate(&node, &script, &skinned);
    let bare = weft_mesh::export::Frames::from_frames(std::slice::from_ref(&rest)).unwrap();
    let plain = dir.join("skinned_plain.glb");
    let mesh = AnimatedMesh {
        uvs: None,
        frames: &bare,
        ..mesh
    };
    write_skinned_glb(
        &plain,
        &skeleton,
        &[mesh],
        &[binding],
        GlbOptions::default(),
    )
    .unwrap();
    validate(&node, &script, &plain);

    let _ = std::fs::remove_dir_all(&dir);
}
